//! `polyphase run` for a coupled scene: the solver's velocity moves the tracker (paper 004
//! §7.5); frames, stats with per-stage timings, solver iterations and scene diagnostics.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use polyphase_coupling::{interface_extent, CoupledSim, FrameReport};
use polyphase_scenes::Scene;
use polyphase_tracker::{ContourTracker, InterfaceTracker, PhaseId, StepStats};
use serde_json::{json, Value};

use crate::output::RunFolder;
use crate::run::progress;
use crate::summary::Summary;

/// Runs a validated coupled scene into `root` (already checked to be writable by `folder`).
pub fn run_coupled(scene: &Scene, folder: &RunFolder, root: &Path) -> Result<()> {
    let names = scene.phase_names();
    let reference = scene.reference_volumes();
    let frames = scene.file.time.frames as usize;
    let (mut sim, first) = polyphase_coupling::from_scene(scene)?;
    let sg = *sim.solver().grid();
    eprintln!(
        "{}: tracker {}×{}×{} cells (h = {:.4e}), solver {}×{}×{} cells (h = {:.4e}), {frames} frames, output {}",
        scene.file.name,
        scene.grid.dims[0],
        scene.grid.dims[1],
        scene.grid.dims[2],
        scene.grid.h,
        sg.dims[0],
        sg.dims[1],
        sg.dims[2],
        sg.h,
        root.display()
    );
    let bar = progress(frames);
    let mut summary = Summary::new(&names);
    summary.add_step(&first);
    folder.write_frame(0, sim.tracker().mesh())?;
    let initial = FrameReport {
        stages: first.stages.clone(),
        cells: first.cells,
        interface_cells: first.interface_cells,
        ..FrameReport::default()
    };
    folder.append_stats(&frame_line(0, 0.0, &initial, &sim, scene))?;

    let started = Instant::now();
    let (mut pressure_its, mut viscosity_its) = (0, 0);
    for frame in 1..=frames {
        let time = frame as f64 * scene.frame_dt();
        let mut report = sim
            .advance_to(time)
            .with_context(|| format!("frame {frame} (t = {time:.4} s)"))?;
        let write_start = Instant::now();
        folder.write_frame(frame, sim.tracker().mesh())?;
        report
            .stages
            .push(("write", write_start.elapsed().as_secs_f64()));
        summary.add_step(&StepStats {
            stages: report.stages.clone(),
            ..StepStats::default()
        });
        pressure_its += report.pressure_iterations;
        viscosity_its += report.viscosity_iterations;
        folder.append_stats(&frame_line(frame, time, &report, &sim, scene))?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    summary.set_solver_iterations(pressure_its, viscosity_its);
    summary.finish(
        frames,
        sim.steps(),
        started.elapsed().as_secs_f64(),
        &reference,
        &sim.tracker().phase_volumes(),
        sim.tracker().mesh(),
    );
    print!("{}", summary.table());
    folder.append_stats(&summary.json())?;
    Ok(())
}

fn frame_line(
    frame: usize,
    time: f64,
    report: &FrameReport,
    sim: &CoupledSim<ContourTracker>,
    scene: &Scene,
) -> Value {
    let tracker = sim.tracker();
    let names = scene.phase_names();
    let volumes: BTreeMap<&str, f64> = names
        .iter()
        .map(String::as_str)
        .zip(tracker.phase_volumes())
        .collect();
    let timings: BTreeMap<&str, f64> = report.stages.iter().copied().collect();
    let mesh = tracker.mesh();
    let mut line = json!({
        "frame": frame,
        "time": time,
        "steps": report.steps,
        "tracker_steps": report.tracker_steps,
        "dt_min": if report.steps > 0 { report.dt_range.0 } else { 0.0 },
        "dt_max": report.dt_range.1,
        "pressure_iterations": report.pressure_iterations,
        "viscosity_iterations": report.viscosity_iterations,
        "max_speed": sim.solver().velocity().max_abs(),
        "phase_volumes": volumes,
        "timings": timings,
        "mesh": { "vertices": mesh.vertices.len(), "triangles": mesh.triangles.len() },
        "cells": report.cells,
        "interface_cells": report.interface_cells,
    });
    add_diagnostics(&mut line, scene, tracker);
    line
}

/// Scene-specific measurements: the surge front of a single column, the bubble and spike
/// tips of Rayleigh–Taylor (the phases are the scene's second and first).
fn add_diagnostics(line: &mut Value, scene: &Scene, tracker: &ContourTracker) {
    let mesh = tracker.mesh();
    match scene.file.name.as_str() {
        "dambreak_column" => {
            if let Some((_, front)) = interface_extent(mesh, 1 as PhaseId, None, 0) {
                line["surge_front"] = json!(front - scene.grid.origin.x);
            }
        }
        "rayleigh_taylor" => {
            if let Some((spike, bubble)) = interface_extent(mesh, 0, Some(1), 1) {
                line["bubble_tip"] = json!(bubble);
                line["spike_tip"] = json!(spike);
            }
        }
        _ => {}
    }
}
