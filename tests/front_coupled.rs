//! The front tracker driving the fluid (issue 12): `dambreak_column` at low resolution, the
//! mesh checked every 5 ms (closed, label-consistent, intersection-free), its water's volume
//! held without any correction, and its surge front beside the contouring tracker's under the
//! same solver; and falling balls of five liquids, one landed, keep their volumes.

mod common;

use common::builtin_at;
use polyphase_coupling::from_scene;
use polyphase_scenes::{Scene, TrackerKind};
use polyphase_tracker::front::intersection::self_intersections;
use polyphase_tracker::{invariants, InterfaceTracker, LabeledMesh, PhaseId};

/// Tracker cells along x (64 × 32 × 2; the solver 32 × 16): a few seconds a run.
const RESOLUTION: i64 = 64;
/// Simulated time: the surge reaches x = 0.40 m of the 0.5 m box, before it hits the wall.
const END: f64 = 0.2;
/// Frames (checks and comparisons): one every 5 ms, about every second solver step.
const FRAMES: usize = 40;

/// The farthest x of any vertex on a water–air face.
fn surge_front(mesh: &LabeledMesh, water: PhaseId, air: PhaseId) -> f64 {
    mesh.triangles
        .iter()
        .zip(&mesh.labels)
        .filter(|(_, l)| l.contains(&water) && l.contains(&air))
        .flat_map(|(t, _)| t.iter().map(|&v| mesh.vertices[v as usize].x))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// Runs `scene` to `END` frame by frame (the run loop's schedule: the tracker follows the
/// solver every few steps and at each frame end), checking the mesh after each frame when
/// `check` is set, and returns the surge front and the water's volume at each frame end.
fn run(scene: &Scene, check: bool) -> Vec<(f64, f64)> {
    let names = scene.phase_names();
    let index = |n: &str| names.iter().position(|x| x == n).expect("phase") as PhaseId;
    let (water, air) = (index("water"), index("air"));
    let (mut sim, _) = from_scene(scene).expect("coupled scene");
    let mut out = Vec::new();
    for frame in 1..=FRAMES {
        sim.advance_to(END * frame as f64 / FRAMES as f64)
            .expect("frame");
        let mesh = sim.tracker().mesh();
        if check {
            invariants::check(mesh, 0.0).unwrap_or_else(|e| panic!("frame {frame}: {e}"));
            let hits = self_intersections(mesh);
            assert!(hits.is_empty(), "frame {frame}: {hits:?}");
        }
        out.push((
            surge_front(mesh, water, air),
            sim.tracker().phase_volumes()[usize::from(water)],
        ));
    }
    out
}

#[test]
fn the_front_tracker_carries_a_collapsing_column_like_the_contouring_tracker() {
    let contour = builtin_at("dambreak_column", RESOLUTION);
    let mut front = contour
        .with_tracker(TrackerKind::Front)
        .expect("valid override");
    // Measured without the give-back of what mesh operations change.
    front.file.volume_correction = false;
    let start = {
        let (sim, _) = from_scene(&front).expect("coupled scene");
        let names = front.phase_names();
        let water = names.iter().position(|x| x == "water").expect("water");
        sim.tracker().phase_volumes()[water]
    };
    let by_front = run(&front, true);
    let by_contour = run(&contour, false);
    for (k, ((f, v), (c, _))) in by_front.iter().zip(&by_contour).enumerate() {
        // The bound: the mesh moves in a divergence-free velocity and its remeshing
        // keeps volumes, so no correction is needed to hold the water within 0.5 % (measured
        // within 0.014 %).
        let drift = (v - start) / start;
        assert!(drift.abs() < 5e-3, "frame {}: water {drift:+.2e}", k + 1);
        // The issue asks for the two trackers' surge fronts within 3 % of each other at the
        // default resolution (measured there: within 1.7 %). At this coarse one each front is
        // only good to about a tracker cell, and the front tracker's depends on its start
        // mesh's wall triangulation: started from a contour whose tree refined a ±6 h band
        // (split factor 3) it ended 1.5 cells behind at t = 0.2 s, from today's ±4 h band,
        // whose wall closure is coarser, 2.28 cells (the contouring tracker's front the same
        // to 1e-8 either way): within 2.5 cells.
        let cell = 0.5 / RESOLUTION as f64;
        assert!(
            (f - c).abs() < 2.5 * cell,
            "frame {}: front {f} against contouring {c}",
            k + 1
        );
    }
}

#[test]
fn falling_balls_and_a_landed_one_keep_their_volumes_without_correction() {
    // `balls` at 48 tracker cells (solver 24) to t = 0.3 s: four balls fall, the lowest has
    // landed and spread into a sheet on the floor, and no two liquids touch yet.
    let mut scene = builtin_at("balls", 48)
        .with_tracker(TrackerKind::Front)
        .expect("valid override");
    scene.file.volume_correction = false;
    let (mut sim, _) = from_scene(&scene).expect("coupled scene");
    let start = sim.tracker().phase_volumes();
    let liquids = 1..start.len();
    assert!(scene.phase_names()[0] == "air" && liquids.len() == 5);
    for frame in 1..=10 {
        sim.advance_to(0.03 * frame as f64).expect("frame");
        let mesh = sim.tracker().mesh();
        invariants::check(mesh, 0.0).unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        assert!(self_intersections(mesh).is_empty(), "frame {frame}");
        for p in liquids.clone() {
            // The velocity is divergence-free at every point and each triangle sweeps the
            // edge-midpoint rule's flux, so only RK4's and remeshing's errors are left
            // (measured: within 0.011 %). By the corners' flux alone the water gained
            // 0.115 % (0.74 % at 64 cells with trilinear sampling as well).
            let drift = sim.tracker().phase_volumes()[p] / start[p] - 1.0;
            assert!(drift.abs() < 3e-4, "frame {frame}, phase {p}: {drift:+.2e}");
        }
    }
}
