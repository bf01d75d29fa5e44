//! `wedge.json`: the index of a wedge folder, naming each variant's folder and settings; read
//! by `polyphase submit wedge`, `polyphase status` and `polyphase render` (contact sheet).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

/// The index file's name inside a wedge folder.
pub const FILE: &str = "wedge.json";

/// A wedge folder's index.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WedgeIndex {
    /// The scene the wedge was made from, as given on the command line.
    pub scene: String,
    /// One entry per `--set`, in command-line order.
    pub axes: Vec<Axis>,
    /// Every combination; the first axis varies slowest.
    pub variants: Vec<Variant>,
}

/// One `--set`: a path and its values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Axis {
    pub path: String,
    pub values: Vec<serde_json::Value>,
}

/// One variant: its folder (relative to the wedge folder) and the value of every axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variant {
    /// Scene name and folder name, `<scene>-<k>`.
    pub name: String,
    pub settings: Vec<Setting>,
}

/// The value one axis takes in a variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    pub path: String,
    pub value: serde_json::Value,
}

impl Variant {
    /// `path=value` pairs joined by `sep`, for tables and labels.
    pub fn label(&self, sep: &str) -> String {
        self.settings
            .iter()
            .map(|s| format!("{}={}", s.path, s.value))
            .collect::<Vec<_>>()
            .join(sep)
    }

    /// The variant's resolved scene file.
    pub fn scene_file(&self, wedge: &Path) -> PathBuf {
        wedge.join(&self.name).join("scene.toml")
    }

    /// Where a variant's run goes when the wedge is run through `polyphase submit`: the
    /// same folder `polyphase run <scene_file> --out <run_dir>` writes locally.
    pub fn run_dir(&self, wedge: &Path) -> PathBuf {
        wedge.join(&self.name).join("run")
    }
}

impl WedgeIndex {
    /// Reads `DIR/wedge.json`.
    pub fn read(dir: &Path) -> Result<WedgeIndex> {
        let path = dir.join(FILE);
        let text = fs::read_to_string(&path).with_context(|| {
            format!(
                "{} is not a wedge folder (no {FILE}; make one with `polyphase wedge`)",
                dir.display()
            )
        })?;
        serde_json::from_str(&text).with_context(|| format!("{} is malformed", path.display()))
    }
}
