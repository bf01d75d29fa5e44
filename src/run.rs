//! `polyphase run`: load a scene, track its interfaces frame by frame, write the run folder
//! with a checkpoint at every frame end; `polyphase resume` continues from that checkpoint.
//! Coupled scenes go to [`crate::run_coupled`].

use std::collections::BTreeMap;
use std::fs;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use polyphase_scenes::{Scene, TrackerKind};
use polyphase_tracker::{metrics, ContourTracker, InterfaceTracker, StepStats};
use serde_json::{json, Value};

use crate::checkpoint::{scene_hash, Checkpoint, Totals};
use crate::output::RunFolder;
use crate::summary::Summary;

/// What `polyphase run` was asked to do.
pub struct RunOptions {
    pub scene: String,
    pub out: Option<PathBuf>,
    pub resolution: Option<i64>,
    pub frames: Option<i64>,
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
    anyhow::ensure!(
        scene.file.tracker == TrackerKind::Contour,
        "{}: tracker = \"front\" is not available yet; use tracker = \"contour\"",
        opts.scene
    );
    let root = opts
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.file.name));
    let folder = RunFolder::create(&root)?;
    let toml = scene.to_toml();
    folder.write("scene.toml", toml.as_bytes())?;
    let start = Start::Fresh(scene_hash(toml.as_bytes()));
    if scene.is_coupled() {
        crate::run_coupled::run_coupled(&scene, &folder, &root, start)?;
    } else {
        run_passive(&scene, &folder, &root, start)?;
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
            "{} has no checkpoint (the run stopped before its first frame): start it again",
            dir.display()
        )
    })?;
    anyhow::ensure!(
        checkpoint.scene_hash == scene_hash(toml.as_bytes()),
        "{} was edited after the checkpoint was written; cannot resume",
        scene_path.display()
    );
    anyhow::ensure!(
        scene.file.tracker == TrackerKind::Contour,
        "{}: only contour-tracker runs can be resumed",
        scene_path.display()
    );
    let frames = scene.file.time.frames as usize;
    let finished = folder
        .stats_lines()?
        .iter()
        .any(|l| serde_json::from_str::<Value>(l).is_ok_and(|v| v.get("summary").is_some()));
    anyhow::ensure!(
        !(checkpoint.frame >= frames && finished),
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
    run_passive(&scene, &folder, dir, start)
}

/// Where a run starts: at frame 0 (with the fingerprint of its `scene.toml`), or after a
/// checkpoint.
pub enum Start {
    /// A new run; the [`scene_hash`] of the `scene.toml` it wrote.
    Fresh(u64),
    /// A killed run, continued after the checkpoint's frame.
    Resume(Box<Checkpoint>),
}

fn run_passive(scene: &Scene, folder: &RunFolder, root: &Path, start: Start) -> Result<()> {
    let names = scene.phase_names();
    let n_phases = names.len();
    let reference = scene.reference_volumes();
    let frames = scene.file.time.frames as usize;
    let steps = scene.steps_per_frame();
    let dt = scene.frame_dt() / steps as f64;
    eprintln!(
        "{}: {}×{}×{} cells (h = {:.4e}), {frames} frames × {steps} steps, output {}",
        scene.file.name,
        scene.grid.dims[0],
        scene.grid.dims[1],
        scene.grid.dims[2],
        scene.grid.h,
        root.display()
    );

    let initial = |x| scene.initial.sample(x);
    let build_first = || {
        let (mut tracker, first) =
            ContourTracker::new(scene.grid, &initial, n_phases, scene.initial.background);
        tracker.set_volume_targets(scene.volume_targets());
        (tracker, first)
    };
    let mut summary = Summary::new(&names);
    let (mut tracker, hash, done, prior) = match start {
        Start::Fresh(hash) => {
            let (tracker, first) = build_first();
            summary.add_step(&first);
            folder.write_frame(0, tracker.mesh())?;
            folder.append_stats(&frame_line(0, 0.0, 0, &first, &tracker, &names))?;
            (tracker, hash, 0, Totals::default())
        }
        Start::Resume(c) => {
            let c = *c;
            let tracker = ContourTracker::from_parts(
                scene.grid,
                c.mesh,
                c.tree,
                n_phases,
                scene.initial.background,
                c.volume_targets,
            );
            (tracker, c.scene_hash, c.frame, c.totals)
        }
    };
    for (name, secs) in &prior.stages {
        summary.add_stage(name, *secs);
    }
    // The periodic error of the last frame compares with the first mesh (rebuilt exactly when
    // resuming: the initial build is deterministic).
    let initial_mesh = if scene.file.time.periodic {
        Some(if done == 0 {
            tracker.mesh().clone()
        } else {
            build_first().0.mesh().clone()
        })
    } else {
        None
    };
    let save = |frame: usize, tracker: &ContourTracker, summary: &Summary, wall: f64| {
        folder.write_checkpoint(&Checkpoint {
            scene_hash: hash,
            frame,
            time: frame as f64 * scene.frame_dt(),
            steps: frame * steps,
            mesh: tracker.mesh().clone(),
            tree: tracker.tree().clone(),
            volume_targets: tracker.volume_targets().map(<[f64]>::to_vec),
            solver: None,
            totals: Totals {
                wall,
                stages: summary.stages().to_vec(),
                ..Totals::default()
            },
        })
    };
    if done == 0 {
        save(0, &tracker, &summary, 0.0)?;
    }

    let bar = progress(frames * steps);
    bar.set_position((done * steps) as u64);
    let started = Instant::now();
    for frame in done + 1..=frames {
        let mut stats = StepStats::default();
        for s in 0..steps {
            let t = ((frame - 1) * steps + s) as f64 * dt;
            let step = tracker
                .advance(&scene.velocity, t, dt)
                .with_context(|| format!("frame {frame}, step {s}"))?;
            summary.add_step(&step);
            accumulate(&mut stats, &step);
            bar.inc(1);
        }
        let time = frame as f64 * scene.frame_dt();
        let write_start = Instant::now();
        folder.write_frame(frame, tracker.mesh())?;
        stats
            .stages
            .push(("write", write_start.elapsed().as_secs_f64()));
        let mut line = frame_line(frame, time, steps, &stats, &tracker, &names);
        if let (true, Some(initial_mesh)) = (frame == frames, &initial_mesh) {
            add_period_errors(&mut line, &tracker, initial_mesh, &reference, &names, scene);
        }
        folder.append_stats(&line)?;
        save(
            frame,
            &tracker,
            &summary,
            prior.wall + started.elapsed().as_secs_f64(),
        )?;
    }
    bar.finish_and_clear();
    summary.finish(
        frames,
        frames * steps,
        prior.wall + started.elapsed().as_secs_f64(),
        &reference,
        &tracker.phase_volumes(),
        tracker.mesh(),
    );
    print!("{}", summary.table());
    folder.append_stats(&summary.json())?;
    Ok(())
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

fn accumulate(total: &mut StepStats, step: &StepStats) {
    for &(name, secs) in &step.stages {
        match total.stages.iter_mut().find(|(n, _)| *n == name) {
            Some(entry) => entry.1 += secs,
            None => total.stages.push((name, secs)),
        }
    }
    total.cells = step.cells;
    total.interface_cells = step.interface_cells;
}

fn frame_line(
    frame: usize,
    time: f64,
    steps: usize,
    stats: &StepStats,
    tracker: &ContourTracker,
    names: &[String],
) -> Value {
    let volumes: BTreeMap<&str, f64> = names
        .iter()
        .map(String::as_str)
        .zip(tracker.phase_volumes())
        .collect();
    let timings: BTreeMap<&str, f64> = stats.stages.iter().copied().collect();
    let mesh = tracker.mesh();
    json!({
        "frame": frame,
        "time": time,
        "steps": steps,
        "phase_volumes": volumes,
        "timings": timings,
        "mesh": { "vertices": mesh.vertices.len(), "triangles": mesh.triangles.len() },
        "cells": stats.cells,
        "interface_cells": stats.interface_cells,
    })
}

/// For a periodic flow the shapes should be back where they started: relative volume error per
/// phase against the exact initial volumes, and the Hausdorff distance to the initial mesh.
fn add_period_errors(
    line: &mut Value,
    tracker: &ContourTracker,
    initial_mesh: &polyphase_tracker::LabeledMesh,
    reference: &[f64],
    names: &[String],
    scene: &Scene,
) {
    let volumes = tracker.phase_volumes();
    let errors: BTreeMap<&str, f64> = names
        .iter()
        .zip(volumes.iter().zip(reference))
        .filter(|(_, (_, r))| **r > 0.0)
        .map(|(n, (v, r))| (n.as_str(), (v - r) / r))
        .collect();
    let h = metrics::hausdorff(tracker.mesh(), initial_mesh);
    line["volume_error"] = json!(errors);
    line["hausdorff"] = json!({ "absolute": h, "over_h": h / scene.grid.h });
}
