//! Passive runs: a scene's analytic velocity moves the interfaces, frame by frame, with the
//! tracker the scene asks for. Runs of a tracker that has a snapshot (both trackers have one)
//! write a checkpoint at every frame end (`polyphase resume`).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use polyphase_coupling::{build_tracker, AnyTracker};
use polyphase_scenes::Scene;
use polyphase_tracker::volume_correction::components::Components;
use polyphase_tracker::{metrics, InterfaceTracker, LabeledMesh, StepStats};
use serde_json::{json, Value};

use crate::checkpoint::{Checkpoint, Totals};
use crate::measurements::{add_measurements, add_topology, add_volume_correction};
use crate::output::RunFolder;
use crate::run::{progress, Progress, Start};
use crate::slab::{self, SlabFrame};
use crate::summary::Summary;

/// Runs (or resumes) a passive scene in `folder`.
pub fn run_passive(scene: &Scene, folder: &RunFolder, root: &Path, start: Start) -> Result<()> {
    let (tracker, hash, done, prior) = match start {
        Start::Fresh(hash) => {
            let (tracker, first) = build_tracker(scene, None)?;
            (tracker, hash, Progress::Fresh(first), Totals::default())
        }
        Start::Resume(c) => {
            let c = *c;
            let (tracker, _) = build_tracker(scene, Some(c.tracker))?;
            (tracker, c.scene_hash, Progress::After(c.frame), c.totals)
        }
    };
    let frames = scene.file.time.frames as usize;
    let steps = scene.steps_per_frame(tracker.max_travel());
    eprintln!(
        "{}: {}×{}×{} cells (h = {:.4e}), {frames} frames × {steps} steps, {:?} tracker, output {}",
        scene.file.name,
        scene.grid.dims[0],
        scene.grid.dims[1],
        scene.grid.dims[2],
        scene.grid.h,
        scene.file.tracker.kind,
        root.display()
    );
    // The periodic error of the last frame compares with the first mesh (rebuilt exactly when
    // resuming: the initial build is deterministic).
    let initial_mesh = match done {
        _ if !scene.file.time.periodic => None,
        Progress::Fresh(_) => Some(tracker.mesh().clone()),
        Progress::After(_) => Some(build_tracker(scene, None)?.0.mesh().clone()),
    };
    // A tracker without a snapshot keeps no checkpoint; its runs cannot be resumed.
    let save = |frame: usize, tracker: &AnyTracker, summary: &Summary, wall: f64| {
        let Some(snapshot) = tracker.snapshot() else {
            return Ok(());
        };
        folder.write_checkpoint(&Checkpoint {
            scene_hash: hash,
            frame,
            time: frame as f64 * scene.frame_dt(),
            steps: frame * steps,
            tracker: snapshot,
            solver: None,
            totals: Totals {
                wall,
                stages: summary.stages().to_vec(),
                ..Totals::default()
            },
        })
    };
    track(
        scene,
        folder,
        tracker,
        done,
        prior,
        initial_mesh.as_ref(),
        save,
    )
}

/// The frame loop: advances `tracker` through every remaining frame, writing the frame mesh,
/// its stats line and (through `save`) a checkpoint at each frame end, then the summary.
fn track<T: InterfaceTracker>(
    scene: &Scene,
    folder: &RunFolder,
    mut tracker: T,
    progress_at: Progress,
    prior: Totals,
    initial_mesh: Option<&LabeledMesh>,
    save: impl Fn(usize, &T, &Summary, f64) -> Result<()>,
) -> Result<()> {
    let names = scene.phase_names();
    let reference = scene.reference_volumes();
    let frames = scene.file.time.frames as usize;
    let steps = scene.steps_per_frame(tracker.max_travel());
    let dt = scene.frame_dt() / steps as f64;
    let mut summary = Summary::new(&names);
    for (name, secs) in &prior.stages {
        summary.add_stage(name, *secs);
    }
    let done = match progress_at {
        Progress::Fresh(first) => {
            summary.add_step(&first);
            folder.write_frame(0, tracker.mesh())?;
            if scene.file.domain.slab {
                write_slab_images(folder, 0, scene, &tracker)?;
            }
            folder.append_stats(&frame_line(0, 0.0, 0, &first, &tracker, scene)?)?;
            save(0, &tracker, &summary, 0.0)?;
            0
        }
        Progress::After(frame) => frame,
    };
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
        if scene.file.domain.slab {
            let start = Instant::now();
            write_slab_images(folder, frame, scene, &tracker)?;
            stats
                .stages
                .push(("slab_images", start.elapsed().as_secs_f64()));
        }
        let mut line = frame_line(frame, time, steps, &stats, &tracker, scene)?;
        if let (true, Some(initial_mesh)) = (frame == frames, initial_mesh) {
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

/// Writes frame `n`'s EXR and PNG images of a slab scene (`crate::slab`): the tracker on the
/// mid-plane of its own grid, with the scene's velocity at the frame's time.
fn write_slab_images(
    folder: &RunFolder,
    n: usize,
    scene: &Scene,
    tracker: &impl InterfaceTracker,
) -> Result<()> {
    let time = n as f64 * scene.frame_dt();
    let frame = SlabFrame::passive(tracker, &scene.grid, &scene.velocity, time);
    slab::write_images(folder, n, scene, time, &frame, &frame.field)
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
    step.add_volume_correction_to(&mut total.volume_correction);
    step.add_events_to(&mut total.events);
}

fn frame_line(
    frame: usize,
    time: f64,
    steps: usize,
    stats: &StepStats,
    tracker: &impl InterfaceTracker,
    scene: &Scene,
) -> Result<Value> {
    let names = scene.phase_names();
    let volumes: BTreeMap<&str, f64> = names
        .iter()
        .map(String::as_str)
        .zip(tracker.phase_volumes())
        .collect();
    let timings: BTreeMap<&str, f64> = stats.stages.iter().copied().collect();
    let mesh = tracker.mesh();
    let mut line = json!({
        "frame": frame,
        "time": time,
        "steps": steps,
        "phase_volumes": volumes,
        "timings": timings,
        "mesh": { "vertices": mesh.vertices.len(), "triangles": mesh.triangles.len() },
        "cells": stats.cells,
        "interface_cells": stats.interface_cells,
    });
    add_topology(&mut line, tracker.region_count(), &stats.events);
    // Scene validation allows `rise_velocity` on coupled scenes only.
    add_measurements(&mut line, scene, mesh, &|_| Ok(Value::Null))?;
    add_volume_correction(
        &mut line,
        &names,
        &stats.volume_correction,
        &scene.reference_volumes(),
    );
    Ok(line)
}

/// For a periodic flow the shapes should be back where they started: relative volume error per
/// phase against the exact initial volumes, the Hausdorff distance to the initial mesh, and
/// the connected pieces of each phase but the background (how many, and the largest one's
/// share of the phase's volume): a sheet torn on the way comes back as several.
fn add_period_errors(
    line: &mut Value,
    tracker: &impl InterfaceTracker,
    initial_mesh: &LabeledMesh,
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
    let background = scene.initial.background;
    let found = Components::find(tracker.mesh(), names.len(), background);
    let pieces: BTreeMap<&str, Value> = names
        .iter()
        .enumerate()
        .filter(|&(p, _)| p != usize::from(background))
        .map(|(p, name)| {
            let volumes = (0..found.len())
                .filter(|&c| usize::from(found.phase[c]) == p)
                .map(|c| found.volume[c]);
            let (count, total, largest) =
                volumes.fold((0, 0.0, 0.0_f64), |(n, t, m), v| (n + 1, t + v, m.max(v)));
            let share = if total > 0.0 { largest / total } else { 0.0 };
            (name.as_str(), json!({ "count": count, "largest": share }))
        })
        .collect();
    line["pieces"] = json!(pieces);
}
