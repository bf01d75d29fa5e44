//! Passive advection of the built-in scenes with the contouring tracker: mesh invariants after
//! every step, and volume / shape recovery after a full period (paper 004 §7.2–7.3).

use polyphase_scenes::{volume, Scene};
use polyphase_tracker::{invariants, metrics, ContourTracker, InterfaceTracker, LabeledMesh};

/// Result of running a scene to its end.
struct Finished {
    initial: LabeledMesh,
    tracker: ContourTracker,
    reference: Vec<f64>,
    h: f64,
}

/// Runs `name` at `resolution` for `steps` tracker steps (all of them when `None`), checking the
/// shared mesh invariants after every step.
fn run(name: &str, resolution: i64, steps: Option<usize>) -> Finished {
    let scene: Scene = polyphase_scenes::builtin(name)
        .expect("built-in")
        .expect("valid")
        .with_overrides(Some(resolution), None)
        .expect("valid override");
    let n = scene.file.phases.len();
    let sampler = |x| scene.initial.sample(x);
    let (mut tracker, _) = ContourTracker::new(scene.grid, &sampler, n, scene.initial.background);
    let min_area = 0.0;
    invariants::check(tracker.mesh(), min_area).unwrap_or_else(|e| panic!("{name} start: {e}"));
    let initial = tracker.mesh().clone();
    let per_frame = scene.steps_per_frame();
    let total = per_frame * scene.file.time.frames as usize;
    let dt = scene.frame_dt() / per_frame as f64;
    for s in 0..steps.unwrap_or(total).min(total) {
        tracker
            .advance(&scene.velocity, s as f64 * dt, dt)
            .expect("finite flow");
        invariants::check(tracker.mesh(), min_area)
            .unwrap_or_else(|e| panic!("{name} step {s}: {e}"));
    }
    let reference =
        volume::reference_volumes(&scene.initial, &scene.grid, n, volume::DEFAULT_DEPTH);
    Finished {
        initial,
        tracker,
        reference,
        h: scene.grid.h,
    }
}

fn volume_errors(f: &Finished) -> Vec<f64> {
    f.tracker
        .phase_volumes()
        .iter()
        .zip(&f.reference)
        .map(|(v, r)| (v - r).abs() / r)
        .collect()
}

#[test]
fn every_builtin_scene_keeps_the_mesh_invariants_every_step() {
    for (name, _) in polyphase_scenes::BUILTIN {
        let slab = polyphase_scenes::builtin(name)
            .unwrap()
            .unwrap()
            .file
            .domain
            .slab;
        // Low resolutions keep the suite fast; invariants must hold at any resolution.
        let res = if slab { 64 } else { 16 };
        run(name, res, Some(8));
    }
}
