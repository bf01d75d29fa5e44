//! The run folder (ARCHITECTURE.md "Output folder"): every file is written to a temporary name
//! and renamed into place, so a killed run never leaves a half-written frame. A killed run's
//! folder is rewound to its last checkpoint before it continues.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use polyphase_tracker::{ply, LabeledMesh};

use crate::checkpoint::{self, Checkpoint};

/// Temporary names [`write_atomic`] leaves behind when a run is killed mid-write.
const TEMPORARIES: [&str; 3] = ["scene.tmp", "stats.tmp", "checkpoint.tmp"];

/// What a frame writes into `frames/`: the mesh, and for slab scenes the EXR and PNG images.
const FRAME_EXTENSIONS: [&str; 3] = ["ply", "exr", "png"];

/// An output folder that has been checked to be writable.
pub struct RunFolder {
    root: PathBuf,
}

impl RunFolder {
    /// Creates `root/frames`, and removes the frames (meshes and slab images), grids, stats and
    /// checkpoint of an earlier run there.
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
            if entry
                .path()
                .extension()
                .is_some_and(|e| FRAME_EXTENSIONS.iter().any(|f| e == *f))
            {
                fs::remove_file(entry.path()).ok();
            }
        }
        if let Ok(entries) = fs::read_dir(root.join("grids")) {
            for entry in entries.flatten() {
                if entry.path().extension().is_some_and(|e| e == "vdb") {
                    fs::remove_file(entry.path()).ok();
                }
            }
        }
        fs::remove_file(root.join("stats.jsonl")).ok();
        fs::remove_file(root.join(checkpoint::FILE)).ok();
        Ok(RunFolder {
            root: root.to_path_buf(),
        })
    }

    /// An existing run folder, to resume (nothing is changed yet).
    pub fn open(root: &Path) -> RunFolder {
        RunFolder {
            root: root.to_path_buf(),
        }
    }

    /// The checkpoint, if the run wrote one; an error if it cannot be read or is damaged.
    pub fn read_checkpoint(&self) -> Result<Option<Checkpoint>> {
        let path = self.root.join(checkpoint::FILE);
        match fs::read(&path) {
            Ok(bytes) => Checkpoint::decode(&bytes)
                .map(Some)
                .with_context(|| format!("checkpoint {} is unusable", path.display())),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
        }
    }

    /// Writes the checkpoint atomically.
    pub fn write_checkpoint(&self, c: &Checkpoint) -> Result<()> {
        self.write(checkpoint::FILE, &c.encode()?)
    }

    /// The lines of `stats.jsonl` (none when it does not exist).
    pub fn stats_lines(&self) -> Result<Vec<String>> {
        let path = self.root.join("stats.jsonl");
        match fs::read_to_string(&path) {
            Ok(text) => Ok(text.lines().map(str::to_string).collect()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
            Err(e) => Err(e).with_context(|| format!("cannot read {}", path.display())),
        }
    }

    /// Rewinds a killed run to the end of frame `frame`: keeps the stats lines of frames
    /// `0..=frame` (a kill between the stats line and the checkpoint leaves one more), removes
    /// later frames and temporary files. Checks everything before changing anything.
    pub fn rewind(&self, frame: usize) -> Result<()> {
        let path = self.root.join("stats.jsonl");
        let lines = self.stats_lines()?;
        let kept = lines
            .iter()
            .take(frame + 1)
            .enumerate()
            .take_while(|(i, l)| frame_of(l) == Some(*i))
            .count();
        anyhow::ensure!(
            kept == frame + 1,
            "{} holds {kept} frame lines but the checkpoint is at frame {frame}",
            path.display()
        );
        let mut text = lines[..kept].join("\n");
        text.push('\n');
        let mut later = Vec::new();
        for (folder, extensions) in [("frames", &FRAME_EXTENSIONS[..]), ("grids", &["vdb"])] {
            let dir = self.root.join(folder);
            if folder == "grids" && !dir.exists() {
                continue;
            }
            later.extend(
                fs::read_dir(&dir)
                    .with_context(|| format!("cannot list {}", dir.display()))?
                    .flatten()
                    .map(|e| e.path())
                    .filter(|p| {
                        let number = p
                            .file_stem()
                            .and_then(|s| s.to_str()?.parse::<usize>().ok());
                        match p.extension().and_then(|e| e.to_str()) {
                            Some(e) if extensions.contains(&e) => number.is_some_and(|n| n > frame),
                            Some("tmp") => number.is_some(),
                            _ => false,
                        }
                    }),
            );
        }
        if lines.len() != kept {
            write_atomic(&path, text.as_bytes())?;
        }
        for p in later {
            fs::remove_file(&p).with_context(|| format!("cannot remove {}", p.display()))?;
        }
        for name in TEMPORARIES {
            fs::remove_file(self.root.join(name)).ok();
        }
        Ok(())
    }

    /// Writes `bytes` to `name` atomically.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        write_atomic(&self.root.join(name), bytes)
    }

    /// Writes frame `n`'s grids (an OpenVDB file) as `grids/NNNN.vdb`.
    pub fn write_grids(&self, n: usize, bytes: &[u8]) -> Result<()> {
        let dir = self.root.join("grids");
        fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        self.write(&format!("grids/{n:04}.vdb"), bytes)
    }

    /// Writes frame `n` as `frames/NNNN.ply`.
    pub fn write_frame(&self, n: usize, mesh: &LabeledMesh) -> Result<()> {
        let mut bytes = Vec::new();
        ply::write_ply(mesh, &mut bytes)?;
        self.write(&format!("frames/{n:04}.ply"), &bytes)
    }

    /// Writes frame `n`'s slab images as `frames/NNNN.exr` and `frames/NNNN.png`.
    pub fn write_slab_images(&self, n: usize, exr: &[u8], png: &[u8]) -> Result<()> {
        self.write(&format!("frames/{n:04}.exr"), exr)?;
        self.write(&format!("frames/{n:04}.png"), png)
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

/// The `frame` number of a stats line, if it is a complete frame line.
fn frame_of(line: &str) -> Option<usize> {
    let v: serde_json::Value = serde_json::from_str(line).ok()?;
    v.get("frame")?.as_u64().map(|f| f as usize)
}

/// Writes `bytes` to `path` under a temporary name, then renames it: a killed program never
/// leaves a half-written file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    let mut f =
        fs::File::create(&tmp).with_context(|| format!("cannot write {}", tmp.display()))?;
    f.write_all(bytes)
        .and_then(|_| f.sync_all())
        .with_context(|| format!("cannot write {}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))
}
