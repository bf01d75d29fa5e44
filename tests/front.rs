//! Passive advection with the explicit front tracker (paper 000): after every step of
//! `zalesak` and `enright` at two resolutions the mesh is closed, label-consistent and free of
//! self-intersections (an exact checker independent of the collision handling); after a full
//! Zalesak turn the volumes and the notch's sharp edges are kept; the command line runs it.

mod common;

use std::fs;

use common::{builtin_at, polyphase, run_small, scratch};
use glam::DVec3;
use polyphase_scenes::{Scene, TrackerKind};
use polyphase_tracker::front::front_tracker::FrontTracker;
use polyphase_tracker::front::intersection::self_intersections;
use polyphase_tracker::{
    invariants, metrics, ply, InterfaceTracker, LabeledMesh, MeshQuery, OUTSIDE,
};

/// A run's first and last mesh and volumes.
struct Finished {
    initial: LabeledMesh,
    start_volumes: Vec<f64>,
    tracker: FrontTracker,
}

/// Runs built-in `name` with the front tracker at `resolution` through the whole scene,
/// checking the invariants and intersection-freedom after every step.
fn run(name: &str, resolution: i64) -> Finished {
    let scene = builtin_at(name, resolution)
        .with_tracker(TrackerKind::Front)
        .expect("valid override");
    let sampler = |x| scene.initial.sample(x);
    let params = scene.file.tracker.front.clone().expect("resolved");
    let mut tracker = FrontTracker::from_sampler(
        scene.grid,
        &sampler,
        scene.file.phases.len(),
        scene.initial.background,
        params,
    )
    .expect("valid start");
    let initial = tracker.mesh().clone();
    let hits = self_intersections(&initial);
    assert!(hits.is_empty(), "{name} {resolution} start: {hits:?}");
    let start_volumes = tracker.phase_volumes();
    let per_frame = scene.steps_per_frame(tracker.max_travel());
    let total = per_frame * scene.file.time.frames as usize;
    let dt = scene.frame_dt() / per_frame as f64;
    for s in 0..total {
        tracker
            .advance(&scene.velocity, s as f64 * dt, dt)
            .unwrap_or_else(|e| panic!("{name} {resolution} step {s}: {e}"));
        invariants::check(tracker.mesh(), 0.0)
            .unwrap_or_else(|e| panic!("{name} {resolution} step {s}: {e}"));
        let hits = self_intersections(tracker.mesh());
        assert!(hits.is_empty(), "{name} {resolution} step {s}: {hits:?}");
    }
    Finished {
        initial,
        start_volumes,
        tracker,
    }
}

/// Points along the exact notch edges of `zalesak` (scenes/builtin/zalesak.toml): the two top
/// edges (walls x = 0.475, 0.525 meeting the notch top y = 0.85) and the two curves where the
/// walls cut the sphere (centre (0.5, 0.75, 0.5), radius 0.15) below the top.
fn notch_edges() -> Vec<DVec3> {
    let mut points = Vec::new();
    for x in [0.475, 0.525] {
        // Sphere section radius in the wall plane, and its half-width at the top y = 0.85.
        let r = (0.15f64.powi(2) - (x - 0.5f64).powi(2)).sqrt();
        let w = (r * r - 0.1f64.powi(2)).sqrt();
        for i in 0..=20 {
            points.push(DVec3::new(x, 0.85, 0.5 - w + 2.0 * w * i as f64 / 20.0));
        }
        // The wall curve from the top edge's ends round the bottom of the sphere (y < 0.85).
        let top = (0.1f64 / r).acos();
        for i in 0..=40 {
            let a = top + (std::f64::consts::TAU - 2.0 * top) * i as f64 / 40.0;
            points.push(DVec3::new(x, 0.75 + r * a.cos(), 0.5 + r * a.sin()));
        }
    }
    points
}

/// Largest distance from the exact notch edges to `mesh`.
fn notch_error(mesh: &LabeledMesh) -> f64 {
    let query = MeshQuery::new(mesh, 0);
    notch_edges()
        .into_iter()
        .map(|p| query.distance(p))
        .fold(0.0, f64::max)
}

#[test]
fn zalesak_full_turn_keeps_volumes_and_the_notch_edges() {
    for resolution in [32, 48] {
        let f = run("zalesak", resolution);
        let mesh = f.tracker.mesh();
        let end = f.tracker.phase_volumes();
        for (phase, (v, v0)) in end.iter().zip(&f.start_volumes).enumerate() {
            // Issue 6: per-phase volume error ≤ 0.5 % over the full turn, against the
            // tracker's own starting mesh (a rigid rotation changes no volume).
            let e = (v - v0) / v0;
            assert!(
                e.abs() <= 5e-3,
                "{resolution}: phase {phase} {:.3} %",
                e * 100.0
            );
        }
        // Issue 6: the notch's edges end within 0.5 mean edge length of the exact shape.
        // The start mesh is contoured at h/2, so its edges are already off by up to ~0.4 L;
        // the turn itself must not round them further (measured: unchanged to 1e-4).
        let l = mesh.mean_edge_length();
        let (start, end) = (notch_error(&f.initial), notch_error(mesh));
        assert!(
            end <= 0.5 * l,
            "{resolution}: notch edges {end:.4} off, L = {l:.4}"
        );
        assert!(
            end <= start + 0.05 * l,
            "{resolution}: notch {start:.4} -> {end:.4}"
        );
    }
}

#[test]
fn enright_stays_intersection_free_at_two_resolutions() {
    for resolution in [24, 32] {
        let f = run("enright", resolution);
        // The flow returns the ball at the end of the period. The front keeps it whole: its
        // shape is back within 2 h of the start (measured 1.2 h at 32³; the contouring tracker
        // strands debris tens of h away), though thin sheets lose a few percent of volume to
        // collapses at these coarse edge lengths.
        let h = 1.0 / resolution as f64;
        let d = metrics::hausdorff(f.tracker.mesh(), &f.initial);
        eprintln!(
            "enright {resolution}: hausdorff {:.2} h, volumes {:?} -> {:?}",
            d / h,
            f.start_volumes,
            f.tracker.phase_volumes()
        );
        assert!(d <= 2.0 * h, "{resolution}: Hausdorff {:.2} h", d / h);
    }
}

#[test]
fn front_runs_from_the_command_line_identically_on_one_and_two_threads() {
    let dir = scratch("front_cli");
    let run = |threads: &str| {
        let out = dir.join(format!("t{threads}"));
        let o = run_small(
            "zalesak",
            16,
            2,
            &out,
            &["--tracker", "front", "--threads", threads],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let frames: Vec<Vec<u8>> = (0..=2)
            .map(|f| fs::read(out.join(format!("frames/{f:04}.ply"))).expect("frame"))
            .collect();
        for bytes in &frames {
            let mesh = ply::read_ply(&bytes[..]).expect("valid PLY");
            invariants::check(&mesh, 0.0).expect("closed and consistent");
            assert!(self_intersections(&mesh).is_empty());
            // The ball never reaches the walls, so the box faces were dropped.
            assert!(mesh.labels.iter().all(|l| !l.contains(&OUTSIDE)));
        }
        let resolved = fs::read_to_string(out.join("scene.toml")).expect("scene.toml");
        let scene = Scene::parse(&resolved, "scene.toml").expect("reloads");
        assert_eq!(scene.file.tracker.kind, TrackerKind::Front);
        frames
    };
    assert!(
        run("1") == run("2"),
        "frames differ between 1 and 2 threads"
    );
}

#[test]
fn an_unknown_tracker_or_resume_of_a_finished_front_run_is_one_clear_error() {
    let dir = scratch("front_refused");
    let out = dir.join("frnt");
    let o = run_small("dambreak_column", 16, 1, &out, &["--tracker", "frnt"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    // One line naming the problem (clap adds its usual `--help` hint below a bad value).
    let first = err.lines().next().unwrap_or_default();
    assert!(
        first.starts_with("error:")
            && first.contains("unknown tracker 'frnt' (trackers: contour, front)"),
        "{err}"
    );
    assert!(!out.exists(), "no output folder for a refused run");
    // A front run keeps a checkpoint like a contouring run (`tests/resume.rs` resumes one), so
    // `resume` on a finished one says it is finished.
    let out = dir.join("passive");
    let o = run_small("zalesak", 16, 1, &out, &["--tracker", "front"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = polyphase(&["resume", out.to_str().expect("UTF-8 path")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("is finished (1 frames); nothing to resume"),
        "{err}"
    );
}
