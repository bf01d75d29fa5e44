//! Checkpoint and resume through the binary: a run killed with SIGKILL mid-way and resumed
//! (coupled and passive, with either tracker) writes the same frame bytes as an
//! uninterrupted run; unusable folders are refused untouched.

mod common;

use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};
use std::thread::sleep;
use std::time::Duration;

use common::{polyphase, run_small, scratch};
use serde_json::Value;

/// Starts `polyphase run` with `args` plus `--out out`, waits until `marker` (a path inside
/// `out`) exists, and SIGKILLs the run (std's `Child::kill` is SIGKILL on unix).
fn run_and_kill(args: &[&str], out: &Path, marker: &str) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_polyphase"))
        .args(args)
        .args(["--out", out.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    while !out.join(marker).exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before {marker} appeared"
        );
        sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
}

/// `polyphase resume DIR` plus `extra`, which must succeed.
fn resume(dir: &Path, extra: &[&str]) {
    let mut args = vec!["resume", dir.to_str().unwrap()];
    args.extend(extra);
    let o = polyphase(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Every frame of `a` and `b`, byte for byte: meshes, and slab scenes' EXR and PNG images.
fn assert_same_frames(a: &Path, b: &Path, frames: usize) {
    for f in 0..=frames {
        for ext in ["ply", "exr", "png"] {
            let name = format!("frames/{f:04}.{ext}");
            let (x, y) = (fs::read(a.join(&name)).ok(), fs::read(b.join(&name)).ok());
            assert!(x == y, "{name} differs after resume");
            assert!(ext != "ply" || x.is_some(), "{name} missing");
        }
    }
    assert!(!b.join(format!("frames/{:04}.ply", frames + 1)).exists());
}

/// The stats lines without wall-clock timings, which differ between any two runs.
fn stats_without_timings(dir: &Path) -> Vec<Value> {
    fs::read_to_string(dir.join("stats.jsonl"))
        .unwrap()
        .lines()
        .map(|l| {
            let mut v: Value = serde_json::from_str(l).unwrap();
            if let Some(o) = v.as_object_mut() {
                o.remove("timings");
            }
            if let Some(s) = v.get_mut("summary").and_then(Value::as_object_mut) {
                s.remove("wall_s");
                s.remove("process");
                s.remove("stage_s");
            }
            v
        })
        .collect()
}

#[test]
fn coupled_run_killed_twice_and_resumed_matches_uninterrupted_run() {
    let dir = scratch("resume_coupled");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let frames = 8;
    let o = run_small("dambreak_column", 64, frames, &a, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let args = [
        "run",
        "dambreak_column",
        "--resolution",
        "64",
        "--frames",
        "8",
    ];
    run_and_kill(&args, &b, "frames/0002.ply");
    // The kill interrupted the run: its last frame and summary were never written.
    assert!(!b.join("frames/0008.ply").exists());
    // Killed again while resuming, then resumed on another thread count.
    let mut child = Command::new(env!("CARGO_BIN_EXE_polyphase"))
        .args(["resume", b.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    while !b.join("frames/0005.ply").exists() {
        assert!(child.try_wait().unwrap().is_none(), "resume ended early");
        sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!b.join("frames/0008.ply").exists());
    resume(&b, &["--threads", "1"]);

    assert_same_frames(&a, &b, frames as usize);
    // Frame lines (volumes, steps, iterations, surge front) and the summary's counts agree too:
    // exactly one line per frame survives the kills.
    assert_eq!(stats_without_timings(&a), stats_without_timings(&b));
}

/// Runs `scene` at `resolution` for `frames` frames (with `extra` arguments) into `DIR/a`;
/// runs it again into `DIR/b`, killed once `kill_at` (a path in the run folder) exists, and
/// resumes that; asserts the two wrote the same frames and the same stats lines (timings
/// aside). Returns `DIR/b`'s stats.
fn kill_resume_and_compare(
    dir: &str,
    (scene, resolution, frames, extra): (&str, u32, u32, &[&str]),
    kill_at: &str,
) -> Vec<Value> {
    let dir = scratch(dir);
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run_small(scene, resolution, frames, &a, extra);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (res, n) = (resolution.to_string(), frames.to_string());
    let mut args = vec!["run", scene, "--resolution", &res, "--frames", &n];
    args.extend(extra);
    run_and_kill(&args, &b, kill_at);
    assert!(!b.join(format!("frames/{frames:04}.ply")).exists());
    resume(&b, &[]);
    assert_same_frames(&a, &b, frames as usize);
    let stats = stats_without_timings(&b);
    assert_eq!(stats_without_timings(&a), stats);
    stats
}

#[test]
fn passive_run_killed_mid_frame_and_resumed_matches_uninterrupted_run() {
    // circle3_rotate is periodic: its last frame line compares with the first mesh, which the
    // resumed run has to rebuild. The first checkpoint is written right after frame 0: the
    // kill lands in frame 1.
    kill_resume_and_compare(
        "resume_passive",
        ("circle3_rotate", 32, 4, &[]),
        "checkpoint.bin",
    );
}

#[test]
fn front_run_killed_mid_run_and_resumed_matches_uninterrupted_run() {
    // merge2 at 16³: the spheres meet near t = 0.2 (frame 2 of 6) and merge, so the
    // checkpoint and the resumed frames straddle the topology change. Volumes, regions and
    // the topology events per frame agree too.
    let stats = kill_resume_and_compare("resume_front", ("merge2", 16, 6, &[]), "frames/0002.ply");
    let merged = stats
        .iter()
        .any(|l| l["events"]["merge_snaps"].as_u64().is_some_and(|n| n > 0));
    assert!(merged, "the spheres never merged");
}

#[test]
fn mean_curvature_run_killed_mid_run_and_resumed_matches_uninterrupted_run() {
    // Mean-curvature flow coarsens a new tracker's start once more (junctions as ridges); a
    // restored one must not, or the resumed frames drift from the uninterrupted run's.
    kill_resume_and_compare("resume_mcf", ("mcf_t2", 16, 6, &[]), "frames/0002.ply");
}

#[test]
fn front_coupled_run_killed_mid_run_and_resumed_matches_uninterrupted_run() {
    // The front tracker driving the fluid (issue 12): the checkpoint holds the mesh, the
    // solver's state and the steps the tracker has not yet followed; frames and stats lines
    // (volumes, surge front, steps) of the resumed run are those of the uninterrupted one.
    kill_resume_and_compare(
        "resume_front_coupled",
        ("dambreak_column", 32, 6, &["--tracker", "front"]),
        "frames/0002.ply",
    );
}

#[test]
fn unusable_folders_are_refused_with_one_line_and_left_untouched() {
    let dir = scratch("resume_errors");
    let done = dir.join("done");
    let o = run_small("dambreak_column", 16, 2, &done, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let snapshot = |d: &Path| {
        ["stats.jsonl", "checkpoint.bin", "frames/0002.ply"].map(|n| fs::read(d.join(n)).ok())
    };
    let refused = |d: &Path, expect: &str| {
        let before = snapshot(d);
        let o = polyphase(&["resume", d.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{expect}: should fail");
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert!(err.contains(expect), "'{expect}' not in {err}");
        assert!(before == snapshot(d), "{expect}: the folder changed");
    };
    refused(&done, "finished");

    let empty = dir.join("empty");
    fs::create_dir_all(&empty).unwrap();
    refused(&empty, "not a run folder");

    let no_checkpoint = dir.join("no_checkpoint");
    fs::create_dir_all(no_checkpoint.join("frames")).unwrap();
    fs::copy(done.join("scene.toml"), no_checkpoint.join("scene.toml")).unwrap();
    refused(&no_checkpoint, "no checkpoint");

    // A checkpoint cut short (as by a full disk) or with one bit flipped fails its checksum.
    let bytes = fs::read(done.join("checkpoint.bin")).unwrap();
    for (name, bad) in [
        ("truncated", bytes[..bytes.len() / 2].to_vec()),
        ("flipped", {
            let mut b = bytes.clone();
            b[bytes.len() / 3] ^= 1;
            b
        }),
    ] {
        let d = dir.join(name);
        fs::create_dir_all(d.join("frames")).unwrap();
        fs::copy(done.join("scene.toml"), d.join("scene.toml")).unwrap();
        fs::copy(done.join("stats.jsonl"), d.join("stats.jsonl")).unwrap();
        fs::write(d.join("checkpoint.bin"), bad).unwrap();
        refused(&d, "checksum");
    }

    // An edited scene would not continue the same run.
    let edited = dir.join("edited");
    fs::create_dir_all(edited.join("frames")).unwrap();
    let scene = fs::read_to_string(done.join("scene.toml")).unwrap();
    fs::write(
        edited.join("scene.toml"),
        scene.replace("density = 1000.0", "density = 900.0"),
    )
    .unwrap();
    fs::copy(done.join("checkpoint.bin"), edited.join("checkpoint.bin")).unwrap();
    refused(&edited, "edited");
}
