//! A validation case as written: `validation/<case>/case.toml` names the scene, the source of
//! the reference, and the metrics with their tolerances.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{ensure, Context, Result};
use serde::Deserialize;

/// One case folder's `case.toml`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaseFile {
    /// One line for the table.
    pub description: String,
    /// The scene: a file relative to the case folder, or `builtin:NAME`.
    pub scene: String,
    /// Where the reference comes from: paper, table or figure, or the analytic solution.
    pub source: String,
    /// Tracker resolution of the full version (the scene's own when absent).
    #[serde(default)]
    pub resolution: Option<i64>,
    /// Tracker resolution of the coarse version `--quick` runs (the full version's otherwise).
    #[serde(default)]
    pub quick_resolution: Option<i64>,
    /// The tracker the scene runs with, when not the scene's own (`"contour"` or `"front"`):
    /// one scene file serves a case per tracker.
    #[serde(default)]
    pub tracker: Option<polyphase_scenes::TrackerKind>,
    /// What is compared, each with its tolerance.
    #[serde(rename = "metric")]
    pub metrics: Vec<MetricSpec>,
}

/// One metric as written; `kind` selects which fields are needed (see `metrics.rs`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MetricSpec {
    /// Name in the table.
    pub name: String,
    /// `rt_linear_growth`, `free_fall`, `roundness`, `max_value`, `final_max`, `series`,
    /// `surge_front`, `profile`, `laplace`, `oscillation_period`, `minimum`, `maximum`,
    /// `time_of_minimum`, `time_of_maximum`, `final_value`, or the first-step kinds
    /// `indicator_accuracy` and `indicator_mismatch_distance` (`indicator.rs`), which need no
    /// run.
    pub kind: String,
    /// The stats key it reads (a dotted path into a frame's JSON line, e.g. `tips.max`).
    #[serde(default)]
    pub key: Option<String>,
    /// `rt_linear_growth`: the heavy and the light phase; `laplace`, `oscillation_period`:
    /// the drop's phase and the one around it; by name.
    #[serde(default)]
    pub phases: Option<[String; 2]>,
    /// `rt_linear_growth`: the perturbation's wavelength (m).
    #[serde(default)]
    pub wavelength: Option<f64>,
    /// `laplace`, `oscillation_period`: the drop's equilibrium radius (m).
    #[serde(default)]
    pub radius: Option<f64>,
    /// `oscillation_period`: the shape mode (default 2).
    #[serde(default)]
    pub mode: Option<u32>,
    /// `profile`: the phases of the layers from the low wall up, by name.
    #[serde(default)]
    pub layers: Option<Vec<String>>,
    /// `profile`: the coordinates (m, along the profile's axis) of the interfaces between
    /// consecutive `layers`, increasing.
    #[serde(default)]
    pub interfaces: Option<Vec<f64>>,
    /// `series`: a CSV of `time,value` rows (header allowed), relative to the case folder;
    /// `surge_front`: of `T,Z` rows.
    #[serde(default)]
    pub reference: Option<String>,
    /// `surge_front`: the column's width a and height H (m).
    #[serde(default)]
    pub column: Option<[f64; 2]>,
    /// `surge_front`: the Z at which the time origin is set (both fronts pass it at one T).
    #[serde(default)]
    pub align_at: Option<f64>,
    /// `surge_front`: the range of T compared.
    #[serde(default)]
    pub window: Option<[f64; 2]>,
    /// `minimum`, `maximum`, `time_of_*`, `final_value`: a second stats key whose value is
    /// subtracted from `key`'s in every frame (a width from a `tips` measure: `key =
    /// "tips.max"`, `minus = "tips.min"`).
    #[serde(default)]
    pub minus: Option<String>,
    /// `minimum`, `maximum`, `final_value`: the reference's value of the stats key;
    /// `time_of_minimum`, `time_of_maximum`: the reference's time (s) of that extremum.
    #[serde(default)]
    pub value: Option<f64>,
    /// Largest accepted error: relative, or for `max_value` and `roundness` the bound itself.
    pub tolerance: f64,
    /// `indicator_accuracy`, `indicator_mismatch_distance`: the paper's rows as printed,
    /// `[resolution, accuracy %, e_i]`; the row of the case's resolution is the reference.
    #[serde(default)]
    pub table: Option<Vec<[f64; 3]>>,
    /// `indicator_accuracy`, `indicator_mismatch_distance`: random points (default 10⁷, the
    /// paper's count).
    #[serde(default)]
    pub samples: Option<usize>,
    /// Why this metric fails today and where that is tracked: the table shows it as a known
    /// gap (not a pass) and it does not fail the command; once it passes the command fails
    /// until the line is removed, so a gap cannot close unnoticed.
    #[serde(default)]
    pub known_gap: Option<String>,
    /// The tolerance of the `--quick` version, when its coarser grid needs another.
    #[serde(default)]
    pub quick_tolerance: Option<f64>,
    /// Why the `--quick` version fails today where the full one passes: read instead of
    /// `known_gap` under `--quick`.
    #[serde(default)]
    pub quick_known_gap: Option<String>,
}

impl MetricSpec {
    /// The tolerance of this run: `quick_tolerance` under `--quick` where the case has one,
    /// else `tolerance`.
    pub fn tolerance_for(&self, quick: bool) -> f64 {
        match (quick, self.quick_tolerance) {
            (true, Some(t)) => t,
            _ => self.tolerance,
        }
    }

    /// The known gap of this run: `quick_known_gap` under `--quick` where the case has one,
    /// else `known_gap`.
    pub fn gap(&self, quick: bool) -> Option<String> {
        match (quick, &self.quick_known_gap) {
            (true, Some(g)) => Some(g.clone()),
            _ => self.known_gap.clone(),
        }
    }
}

/// A case found on disk.
#[derive(Clone, Debug)]
pub struct Case {
    /// The folder's name.
    pub name: String,
    pub dir: PathBuf,
    pub file: CaseFile,
}

impl Case {
    /// Reads `dir/case.toml`; errors name the file.
    pub fn load(dir: &Path) -> Result<Case> {
        let path = dir.join("case.toml");
        let text =
            fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
        let file: CaseFile = toml::from_str(&text)
            .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.message()))?;
        ensure!(
            !file.metrics.is_empty(),
            "{}: at least one [[metric]] is required",
            path.display()
        );
        for (i, m) in file.metrics.iter().enumerate() {
            for (what, t) in [
                ("tolerance", Some(m.tolerance)),
                ("quick_tolerance", m.quick_tolerance),
            ] {
                if let Some(t) = t {
                    ensure!(
                        t.is_finite() && t >= 0.0,
                        "{}: metric[{i}].{what}: must be a finite number ≥ 0, got {t}",
                        path.display()
                    );
                }
            }
        }
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| dir.display().to_string());
        Ok(Case {
            name,
            dir: dir.to_path_buf(),
            file,
        })
    }

    /// The scene argument for `polyphase run`: a built-in name or the scene file's path.
    pub fn scene_arg(&self) -> String {
        match self.file.scene.strip_prefix("builtin:") {
            Some(name) => name.to_string(),
            None => self.dir.join(&self.file.scene).display().to_string(),
        }
    }
}
