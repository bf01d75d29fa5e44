//! Helpers shared by the end-to-end tests: run the binary, make scratch folders, run a
//! built-in scene in process with the mesh checked after every step.
// Each test file compiles this module on its own and uses only some of the helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use polyphase_coupling::build_tracker;
use polyphase_tracker::front::intersection::self_intersections;
use polyphase_tracker::{invariants, InterfaceTracker, LabeledMesh};

/// Built-in scene `name` at tracker `resolution`.
pub fn builtin_at(name: &str, resolution: i64) -> polyphase_scenes::Scene {
    polyphase_scenes::builtin(name)
        .expect("built-in")
        .expect("valid")
        .with_overrides(Some(resolution), None)
        .expect("valid override")
}

/// Runs built-in `name` at `resolution` for `frames` frames (all when `None`), checking after
/// every step that the mesh is closed, label-consistent and intersection-free; returns the
/// tracker and the region counts before and after.
pub fn run_checked(
    name: &str,
    resolution: i64,
    frames: Option<usize>,
) -> (Box<dyn InterfaceTracker>, usize, usize) {
    run_checked_frames(name, resolution, frames, |_, _| {})
}

/// [`run_checked`], calling `at_frame(frame, tracker)` at the start and after every frame.
pub fn run_checked_frames(
    name: &str,
    resolution: i64,
    frames: Option<usize>,
    mut at_frame: impl FnMut(usize, &dyn InterfaceTracker),
) -> (Box<dyn InterfaceTracker>, usize, usize) {
    let scene = builtin_at(name, resolution);
    let (mut tracker, _) = build_tracker(&scene, None).expect("a valid start");
    let regions_before = tracker
        .region_count()
        .expect("the front tracker counts regions");
    let per_frame = scene.steps_per_frame(tracker.max_travel());
    let total = per_frame * frames.unwrap_or(scene.file.time.frames as usize);
    let dt = scene.frame_dt() / per_frame as f64;
    at_frame(0, tracker.as_ref());
    for s in 0..total {
        tracker
            .advance(&scene.velocity, s as f64 * dt, dt)
            .unwrap_or_else(|e| panic!("{name} step {s}: {e}"));
        invariants::check(tracker.mesh(), 0.0).unwrap_or_else(|e| panic!("{name} step {s}: {e}"));
        let hits = self_intersections(tracker.mesh());
        assert!(hits.is_empty(), "{name} step {s}: {hits:?}");
        if (s + 1) % per_frame == 0 {
            at_frame((s + 1) / per_frame, tracker.as_ref());
        }
    }
    let regions_after = tracker
        .region_count()
        .expect("the front tracker counts regions");
    (tracker, regions_before, regions_after)
}

/// Vertices of the faces between phases `a` and `b`.
pub fn interface_vertices(mesh: &LabeledMesh, a: u16, b: u16) -> Vec<glam::DVec3> {
    mesh.triangles
        .iter()
        .zip(&mesh.labels)
        .filter(|(_, l)| (l[0] == a && l[1] == b) || (l[0] == b && l[1] == a))
        .flat_map(|(t, _)| t.map(|v| mesh.vertices[v as usize]))
        .collect()
}

/// Runs the `polyphase` binary with `args`.
pub fn polyphase(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_polyphase"))
        .args(args)
        .output()
        .expect("the polyphase binary runs")
}

/// A fresh, empty scratch folder under the target directory, unique per test name.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// `polyphase run SCENE --resolution R --frames F --out OUT` plus `extra` arguments.
pub fn run_small(scene: &str, resolution: u32, frames: u32, out: &Path, extra: &[&str]) -> Output {
    let (r, f) = (resolution.to_string(), frames.to_string());
    let mut args = vec!["run", scene, "--resolution", &r, "--frames", &f];
    let out = out.to_str().expect("UTF-8 path");
    args.extend(["--out", out]);
    args.extend(extra);
    polyphase(&args)
}

/// `polyphase run FILE --out OUT`.
pub fn run_file(file: &Path, out: &Path) -> Output {
    polyphase(&[
        "run",
        file.to_str().expect("UTF-8 path"),
        "--out",
        out.to_str().expect("UTF-8 path"),
    ])
}
