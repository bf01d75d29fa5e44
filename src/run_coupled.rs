//! `polyphase run` for a coupled scene: the solver's velocity moves the tracker (paper 004
//! §7.5); frames, stats with per-stage timings, solver iterations and the scene's
//! measurements, and, when the tracker has a snapshot, a checkpoint (tracker snapshot, solver
//! state) at every frame end.

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use polyphase_coupling::{build_tracker, AnyTracker, CoupledSim, FrameReport};
use polyphase_grid::vdb::{encode, phase_field_grids, Compression, VdbGrid};
use polyphase_scenes::{MeasureKind, Scene};
use polyphase_tracker::{InterfaceTracker, StepStats};
use serde_json::{json, Value};

use crate::checkpoint::{Checkpoint, Totals};
use crate::measurements::{add_measurements, add_topology, add_volume_correction};
use crate::output::RunFolder;
use crate::run::{progress, Progress, Start};
use crate::slab::{self, mid_plane, SlabFrame};
use crate::summary::Summary;

/// Runs a validated coupled scene into `root` (already checked to be writable by `folder`),
/// from frame 0 or from a checkpoint, with the scene's tracker.
pub fn run_coupled(scene: &Scene, folder: &RunFolder, root: &Path, start: Start) -> Result<()> {
    let (sim, hash, progress_at, prior) = match start {
        Start::Fresh(hash) => {
            let (sim, first) = polyphase_coupling::from_scene(scene)?;
            (sim, hash, Progress::Fresh(first), Totals::default())
        }
        Start::Resume(c) => {
            let c = *c;
            let (tracker, _) = build_tracker(scene, Some(c.tracker))?;
            let mut sim = polyphase_coupling::with_tracker(scene, tracker)?;
            let solver = c
                .solver
                .context("the checkpoint has no solver state (it is of a passive run)")?;
            sim.restore(solver, c.time, c.steps)?;
            (sim, c.scene_hash, Progress::After(c.frame), c.totals)
        }
    };
    // A tracker without a snapshot keeps no checkpoint; its runs cannot be resumed.
    let save = |frame: usize, sim: &CoupledSim<AnyTracker>, totals: Totals| {
        let Some(snapshot) = sim.tracker().snapshot() else {
            return Ok(());
        };
        folder.write_checkpoint(&Checkpoint {
            scene_hash: hash,
            frame,
            time: sim.time(),
            steps: sim.steps(),
            tracker: snapshot,
            solver: Some(sim.solver().state()),
            totals,
        })
    };
    simulate(scene, folder, root, sim, progress_at, prior, save)
}

/// The frame loop: frames, grids, stats lines and (through `save`) checkpoints, then the
/// summary.
fn simulate<T: InterfaceTracker>(
    scene: &Scene,
    folder: &RunFolder,
    root: &Path,
    mut sim: CoupledSim<T>,
    progress_at: Progress,
    prior: Totals,
    save: impl Fn(usize, &CoupledSim<T>, Totals) -> Result<()>,
) -> Result<()> {
    let names = scene.phase_names();
    let reference = scene.reference_volumes();
    let frames = scene.file.time.frames as usize;
    let mut summary = Summary::new(&names);
    for (name, secs) in &prior.stages {
        summary.add_stage(name, *secs);
    }
    let sg = *sim.solver().grid();
    eprintln!(
        "{}: tracker {}×{}×{} cells (h = {:.4e}), solver {}×{}×{} cells (h = {:.4e}), {frames} frames, {:?} tracker, output {}",
        scene.file.name,
        scene.grid.dims[0],
        scene.grid.dims[1],
        scene.grid.dims[2],
        scene.grid.h,
        sg.dims[0],
        sg.dims[1],
        sg.dims[2],
        sg.h,
        scene.file.tracker.kind,
        root.display()
    );
    let unbalanced: Vec<String> = scene
        .tension
        .unbalanced_triples()
        .into_iter()
        .map(|t| format!("({})", t.map(|p| names[usize::from(p)].as_str()).join(", ")))
        .collect();
    if !unbalanced.is_empty() {
        eprintln!(
            "note: no Neumann triangle for the tensions of {} (one σ is at least the sum of the \
             other two): where those three phases meet, the pull on their triple curve cannot \
             balance and the time step may collapse",
            unbalanced.join(", ")
        );
    }
    let done = match progress_at {
        Progress::Fresh(first) => {
            summary.add_step(&first);
            folder.write_frame(0, sim.tracker().mesh())?;
            write_grids_and_images(folder, 0, &sim, scene)?;
            let initial = FrameReport {
                stages: first.stages.clone(),
                cells: first.cells,
                interface_cells: first.interface_cells,
                ..FrameReport::default()
            };
            folder.append_stats(&frame_line(0, 0.0, &initial, &sim, scene)?)?;
            save(
                0,
                &sim,
                Totals {
                    stages: summary.stages().to_vec(),
                    ..Totals::default()
                },
            )?;
            0
        }
        Progress::After(frame) => frame,
    };

    let bar = progress(frames);
    bar.set_position(done as u64);
    let started = Instant::now();
    let (mut pressure_its, mut viscosity_its) =
        (prior.pressure_iterations, prior.viscosity_iterations);
    for frame in done + 1..=frames {
        let time = frame as f64 * scene.frame_dt();
        let mut report = sim
            .advance_to(time)
            .with_context(|| format!("frame {frame} (t = {time:.4} s)"))?;
        let write_start = Instant::now();
        folder.write_frame(frame, sim.tracker().mesh())?;
        let slab_secs = write_grids_and_images(folder, frame, &sim, scene)?;
        report.stages.push((
            "write",
            write_start.elapsed().as_secs_f64() - slab_secs.unwrap_or(0.0),
        ));
        if let Some(secs) = slab_secs {
            report.stages.push(("slab_images", secs));
        }
        summary.add_step(&StepStats {
            stages: report.stages.clone(),
            ..StepStats::default()
        });
        pressure_its += report.pressure_iterations;
        viscosity_its += report.viscosity_iterations;
        folder.append_stats(&frame_line(frame, time, &report, &sim, scene)?)?;
        save(
            frame,
            &sim,
            Totals {
                wall: prior.wall + started.elapsed().as_secs_f64(),
                pressure_iterations: pressure_its,
                viscosity_iterations: viscosity_its,
                stages: summary.stages().to_vec(),
            },
        )?;
        bar.inc(1);
    }
    bar.finish_and_clear();
    summary.set_solver_iterations(pressure_its, viscosity_its);
    summary.finish(
        frames,
        sim.steps(),
        prior.wall + started.elapsed().as_secs_f64(),
        &reference,
        &sim.tracker().phase_volumes(),
        sim.tracker().mesh(),
    );
    print!("{}", summary.table());
    folder.append_stats(&summary.json())?;
    Ok(())
}

/// Writes frame `n`'s grids on the solver's cells as `grids/NNNN.vdb`: φ and χ as the solver
/// reads them, each cell's velocity in its own phase's field ("v", see
/// `Solver::cell_velocities`) and the pressure ("p"). For a slab scene also its EXR and PNG
/// images (`crate::slab`), the PNG from the tracker on the mid-plane of its finer grid; returns
/// the seconds those took.
fn write_grids_and_images<T: InterfaceTracker>(
    folder: &RunFolder,
    n: usize,
    sim: &CoupledSim<T>,
    scene: &Scene,
) -> Result<Option<f64>> {
    let solver = sim.solver();
    let grid = *solver.grid();
    let field = sim.tracker().sample(&grid);
    let velocity = solver.cell_velocities(&field, sim.phases())?;
    let mut out: Vec<VdbGrid> = phase_field_grids(&field).into();
    out.push(VdbGrid::vector(
        "v",
        velocity.iter().map(|v| v.as_vec3().to_array()).collect(),
        [0.0; 3],
    ));
    let pressure = solver.pressure().iter().map(|&p| p as f32).collect();
    out.push(VdbGrid::scalar("p", pressure, 0.0));
    folder.write_grids(n, &encode(&grid, &out, Compression::Zip)?)?;
    if !scene.file.domain.slab {
        return Ok(None);
    }
    let start = Instant::now();
    let frame = SlabFrame::coupled(&field, &velocity, solver.pressure());
    let picture = sim.tracker().sample(&mid_plane(&scene.grid));
    slab::write_images(folder, n, scene, sim.time(), &frame, &picture)?;
    Ok(Some(start.elapsed().as_secs_f64()))
}

fn frame_line<T: InterfaceTracker>(
    frame: usize,
    time: f64,
    report: &FrameReport,
    sim: &CoupledSim<T>,
    scene: &Scene,
) -> Result<Value> {
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
        "interface_lag": report.interface_lag,
    });
    add_topology(&mut line, tracker.region_count(), &report.events);
    if let Some(c) = report.capillary {
        line["capillary"] = json!({
            "dt_limit": c.dt_limit,
            "faces": c.faces,
            "missed_faces": c.missed,
        });
    }
    add_measurements(&mut line, scene, mesh, &|kind| {
        Ok(match *kind {
            MeasureKind::RiseVelocity { phase } => json!(sim.rise_velocity(phase)?),
            MeasureKind::PressureJump { inside, outside } => {
                json!(sim.pressure_jump(inside, outside))
            }
            MeasureKind::VelocityProfile { component, axis } => {
                let profile = sim.velocity_profile(component, axis)?;
                let (position, value): (Vec<f64>, Vec<f64>) = profile.into_iter().unzip();
                json!({ "position": position, "value": value })
            }
            _ => Value::Null,
        })
    })?;
    add_volume_correction(
        &mut line,
        &names,
        &report.volume_correction,
        &scene.reference_volumes(),
    );
    Ok(line)
}
