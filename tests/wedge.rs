//! `polyphase wedge` end to end: one validated scene per combination, an index naming each
//! variant's settings, one clear error naming the `--set` for a bad path or value and no folder
//! left behind; and `polyphase run --resume`, which a re-queued farm task runs.

mod common;

use std::fs;
use std::path::Path;

use common::{polyphase, run_small, scratch};
use serde_json::Value;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn wedge_writes_every_combination_with_its_values() {
    let dir = scratch("wedge_values");
    let out = dir.join("w");
    let o = polyphase(&[
        "wedge",
        "viscous",
        "--set",
        "phases.oil.viscosity=0.01,0.1,1",
        "--set",
        "resolution=48,96",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let index: Value =
        serde_json::from_str(&fs::read_to_string(out.join("wedge.json")).unwrap()).unwrap();
    let variants = index["variants"].as_array().unwrap();
    assert_eq!(variants.len(), 6, "3 viscosities × 2 resolutions");
    for (k, v) in variants.iter().enumerate() {
        let name = format!("viscous-{k}");
        assert_eq!(v["name"], name.as_str());
        let text = fs::read_to_string(out.join(&name).join("scene.toml")).unwrap();
        let scene = polyphase_scenes::Scene::parse(&text, &name).expect("a valid scene");
        assert_eq!(scene.file.name, name);
        // The first axis varies slowest: k = 2·i + j.
        let viscosity = [0.01, 0.1, 1.0][k / 2];
        let resolution = [48, 96][k % 2];
        let oil = scene.file.phases.iter().find(|p| p.name == "oil").unwrap();
        assert_eq!(oil.viscosity, viscosity);
        assert_eq!(v["settings"][0]["value"].as_f64(), Some(viscosity));
        assert_eq!(scene.file.resolution, resolution);
        // `resolution` keeps the built-in scene's tracker-to-solver ratio of 4.
        assert_eq!(
            scene.file.solver.as_ref().unwrap().resolution,
            Some(resolution / 4)
        );
        // Every other phase keeps its viscosity.
        let honey = scene
            .file
            .phases
            .iter()
            .find(|p| p.name == "honey")
            .unwrap();
        assert_eq!(honey.viscosity, 10.0);
    }
}

#[test]
fn bad_sets_name_the_set_and_write_nothing() {
    let dir = scratch("wedge_errors");
    let out = dir.join("w");
    let cases: [(&str, &str); 4] = [
        ("phases.water.viscosity=1", "no entry named 'water'"),
        ("time.ends=1,2", "time.ends"),
        ("phases.oil.viscosity=0.1,-1", "viscosity"),
        ("phases.oil.viscosity", "expected PATH=VALUE"),
    ];
    for (set, expected) in cases {
        let o = polyphase(&[
            "wedge",
            "viscous",
            "--set",
            set,
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = stderr(&o);
        assert!(!o.status.success(), "{set} was accepted");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(err.contains(expected), "{set}: {err}");
        assert!(!out.exists(), "{set} left {} behind", out.display());
    }
    // The bad value's message names the variant's settings.
    let o = polyphase(&[
        "wedge",
        "viscous",
        "--set",
        "phases.oil.viscosity=0.1,-1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        stderr(&o).contains("phases.oil.viscosity=-1"),
        "{}",
        stderr(&o)
    );
    // A folder that already holds something is refused.
    fs::create_dir_all(&out).unwrap();
    fs::write(out.join("keep.txt"), "mine").unwrap();
    let o = polyphase(&[
        "wedge",
        "viscous",
        "--set",
        "time.end=1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("not empty"),
        "{}",
        stderr(&o)
    );
    assert_eq!(fs::read_dir(&out).unwrap().count(), 1);
}

/// Modification times of every frame, to see that nothing was rewritten.
fn frame_times(dir: &Path) -> Vec<std::time::SystemTime> {
    let mut names: Vec<_> = fs::read_dir(dir.join("frames"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    names.sort();
    names
        .iter()
        .map(|p| fs::metadata(p).unwrap().modified().unwrap())
        .collect()
}

#[test]
fn run_resume_continues_a_killed_run_and_leaves_a_finished_one_alone() {
    let dir = scratch("run_resume_flag");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run_small("circle3_rotate", 32, 3, &a, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A finished run: --resume does nothing.
    let before = frame_times(&a);
    let o = run_small("circle3_rotate", 32, 3, &a, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("finished"), "{}", stderr(&o));
    assert_eq!(frame_times(&a), before, "a finished run was rewritten");
    // A run killed after its first checkpoint (frame 0) is continued to the same bytes.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_polyphase"))
        .args([
            "run",
            "circle3_rotate",
            "--resolution",
            "32",
            "--frames",
            "3",
            "--out",
        ])
        .arg(&b)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !b.join("checkpoint.bin").exists() {
        assert!(child.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!b.join("frames/0003.ply").exists());
    let o = run_small("circle3_rotate", 32, 3, &b, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    for f in 0..=3 {
        let name = format!("frames/{f:04}.ply");
        assert!(
            fs::read(a.join(&name)).unwrap() == fs::read(b.join(&name)).unwrap(),
            "{name} differs from the uninterrupted run's"
        );
    }
    // Another scene in the folder: --resume starts over rather than resuming it.
    let o = run_small("circle3_rotate", 24, 3, &b, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("resuming"), "{}", stderr(&o));
    let text = fs::read_to_string(b.join("scene.toml")).unwrap();
    assert!(
        text.contains("resolution = 24"),
        "the folder holds the new scene"
    );
}
