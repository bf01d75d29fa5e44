//! The run folder (DESIGN.md "Output of a run"): every file is written to a temporary name and
//! renamed into place, so a killed run never leaves a half-written frame.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use polyphase_tracker::{ply, LabeledMesh};

/// An output folder that has been checked to be writable.
pub struct RunFolder {
    root: PathBuf,
}

impl RunFolder {
    /// Creates `root/frames`, and removes the frames and stats of an earlier run there.
    pub fn create(root: &Path) -> Result<RunFolder> {
        let frames = root.join("frames");
        fs::create_dir_all(&frames)
            .with_context(|| format!("cannot create output folder {}", frames.display()))?;
        let probe = root.join(".polyphase-write-test");
        fs::write(&probe, b"ok")
            .with_context(|| format!("output folder {} is not writable", root.display()))?;
        fs::remove_file(&probe).ok();
        for entry in fs::read_dir(&frames)
            .with_context(|| format!("cannot list {}", frames.display()))?
            .flatten()
        {
            if entry.path().extension().is_some_and(|e| e == "ply") {
                fs::remove_file(entry.path()).ok();
            }
        }
        fs::remove_file(root.join("stats.jsonl")).ok();
        Ok(RunFolder {
            root: root.to_path_buf(),
        })
    }

    /// Writes `bytes` to `name` atomically.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        write_atomic(&self.root.join(name), bytes)
    }

    /// Writes frame `n` as `frames/NNNN.ply`.
    pub fn write_frame(&self, n: usize, mesh: &LabeledMesh) -> Result<()> {
        let mut bytes = Vec::new();
        ply::write_ply(mesh, &mut bytes)?;
        self.write(&format!("frames/{n:04}.ply"), &bytes)
    }

    /// Appends one line to `stats.jsonl` (rewritten atomically with the new line).
    pub fn append_stats(&self, line: &serde_json::Value) -> Result<()> {
        let path = self.root.join("stats.jsonl");
        let mut text = fs::read(&path).unwrap_or_default();
        text.extend_from_slice(serde_json::to_string(line)?.as_bytes());
        text.push(b'\n');
        write_atomic(&path, &text)
    }
}

fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    let mut f =
        fs::File::create(&tmp).with_context(|| format!("cannot write {}", tmp.display()))?;
    f.write_all(bytes)
        .and_then(|_| f.sync_all())
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))
}
