//! `polyphase run`: load a scene, track its interfaces frame by frame, write the run folder
//! with a checkpoint at every frame end; `polyphase resume` continues from that checkpoint.
//! Passive scenes go to [`crate::run_passive`], coupled ones to [`crate::run_coupled`].

use std::fs;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use polyphase_scenes::{Scene, TrackerKind};
use serde_json::Value;

use crate::checkpoint::{scene_hash, Checkpoint};
use crate::output::RunFolder;

/// What `polyphase run` was asked to do.
pub struct RunOptions {
    pub scene: String,
    pub out: Option<PathBuf>,
    pub resolution: Option<i64>,
    pub frames: Option<i64>,
    pub tracker: Option<TrackerKind>,
    /// Continue the output folder's killed run of the same scene from its checkpoint, or
    /// leave a finished one alone, instead of starting over (a re-queued farm task).
    pub resume: bool,
}

/// Runs a scene to its end time and returns its output folder. Everything about the input is
/// checked before the output folder is touched, so a bad scene leaves no frames behind.
pub fn run(opts: &RunOptions) -> Result<PathBuf> {
    let scene = polyphase_scenes::load(&opts.scene)?;
    let scene = if opts.resolution.is_some() || opts.frames.is_some() {
        scene.with_overrides(opts.resolution, opts.frames)?
    } else {
        scene
    };
    let scene = match opts.tracker {
        Some(kind) => scene.with_tracker(kind)?,
        None => scene,
    };
    let root = opts
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.file.name));
    let toml = scene.to_toml();
    if opts.resume && same_scene(&root, &toml) {
        match RunFolder::open(&root).read_checkpoint() {
            Ok(Some(c)) if finished(&RunFolder::open(&root), &scene, &c)? => {
                eprintln!("the run in {} is finished; nothing to do", root.display());
                return Ok(root);
            }
            Ok(Some(_)) => {
                resume(&root)?;
                return Ok(root);
            }
            _ => {}
        }
    }
    let folder = RunFolder::create(&root)?;
    folder.write("scene.toml", toml.as_bytes())?;
    let start = Start::Fresh(scene_hash(toml.as_bytes()));
    if scene.is_coupled() {
        crate::run_coupled::run_coupled(&scene, &folder, &root, start)?;
    } else {
        crate::run_passive::run_passive(&scene, &folder, &root, start)?;
    }
    Ok(root)
}

/// `polyphase resume DIR`: continues a killed run from its last checkpoint with the resolved
/// scene it was started with. A folder without a usable checkpoint, or a finished run, is an
/// error that changes nothing.
pub fn resume(dir: &Path) -> Result<()> {
    let scene_path = dir.join("scene.toml");
    let toml = fs::read_to_string(&scene_path)
        .with_context(|| format!("{} is not a run folder (no scene.toml)", dir.display()))?;
    let scene = Scene::parse(&toml, &scene_path.display().to_string())?;
    let folder = RunFolder::open(dir);
    let checkpoint = folder.read_checkpoint()?.with_context(|| {
        format!(
            "{} has no checkpoint: the run stopped before its first frame; start it again",
            dir.display()
        )
    })?;
    anyhow::ensure!(
        checkpoint.scene_hash == scene_hash(toml.as_bytes()),
        "{} was edited after the checkpoint was written; cannot resume",
        scene_path.display()
    );
    let frames = scene.file.time.frames as usize;
    anyhow::ensure!(
        !finished(&folder, &scene, &checkpoint)?,
        "the run in {} is finished ({frames} frames); nothing to resume",
        dir.display()
    );
    folder.rewind(checkpoint.frame)?;
    eprintln!(
        "resuming {} after frame {} of {frames}",
        dir.display(),
        checkpoint.frame
    );
    let start = Start::Resume(Box::new(checkpoint));
    if scene.is_coupled() {
        return crate::run_coupled::run_coupled(&scene, &folder, dir, start);
    }
    crate::run_passive::run_passive(&scene, &folder, dir, start)
}

/// True when the folder's `scene.toml` is `toml` (the run there is of this very scene).
fn same_scene(root: &Path, toml: &str) -> bool {
    fs::read_to_string(root.join("scene.toml")).is_ok_and(|t| t == toml)
}

/// True when the run reached its last frame and wrote its summary.
fn finished(folder: &RunFolder, scene: &Scene, checkpoint: &Checkpoint) -> Result<bool> {
    let summary = folder
        .stats_lines()?
        .iter()
        .any(|l| serde_json::from_str::<Value>(l).is_ok_and(|v| v.get("summary").is_some()));
    Ok(summary && checkpoint.frame >= scene.file.time.frames as usize)
}

/// Where a run starts: at frame 0 (with the fingerprint of its `scene.toml`), or after a
/// checkpoint.
pub enum Start {
    /// A new run; the [`scene_hash`] of the `scene.toml` it wrote.
    Fresh(u64),
    /// A killed run, continued after the checkpoint's frame.
    Resume(Box<Checkpoint>),
}

/// Where a frame loop starts: a new tracker (with the stats of building it), or after a
/// checkpoint's frame.
pub enum Progress {
    Fresh(polyphase_tracker::StepStats),
    After(usize),
}

/// A progress bar on stderr when it is a terminal, hidden otherwise.
pub(crate) fn progress(total: usize) -> ProgressBar {
    let target = if std::io::stderr().is_terminal() {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(total as u64), target);
    if let Ok(style) =
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed} elapsed, ETA {eta}")
    {
        bar.set_style(style);
    }
    bar
}
