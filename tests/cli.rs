//! End-to-end tests of the `polyphase` program: output folder, stats, determinism, bad input.

mod common;

use std::fs;

use common::{polyphase, run_file, run_small, scratch};
use polyphase_tracker::{invariants, ply};

#[test]
fn run_writes_frames_stats_and_resolved_scene() {
    let dir = scratch("run_writes");
    let out = dir.join("zalesak");
    let o = run_small("zalesak", 16, 2, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 0..=2 {
        let bytes = fs::read(out.join(format!("frames/{f:04}.ply"))).unwrap();
        let mesh = ply::read_ply(&bytes[..]).unwrap();
        // Every frame keeps the shared invariants (ARCHITECTURE.md "LabeledMesh").
        invariants::check(&mesh, 0.0).unwrap();
        assert!(!mesh.triangles.is_empty());
    }
    let stats = fs::read_to_string(out.join("stats.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = stats
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // Frames 0, 1, 2 and the summary line.
    assert_eq!(lines.len(), 4);
    for (f, line) in lines.iter().take(3).enumerate() {
        assert_eq!(line["frame"], f);
        for key in ["time", "steps", "phase_volumes", "timings", "mesh"] {
            assert!(!line[key].is_null(), "frame {f} lacks {key}");
        }
        assert!(line["phase_volumes"]["red"].as_f64().unwrap() > 0.0);
    }
    // A periodic scene's last frame reports its errors against the initial state.
    assert!(lines[2]["volume_error"]["blue"].is_number());
    assert!(lines[2]["hausdorff"]["over_h"].is_number());
    // Two halves of one sphere, each one piece after a turn.
    for phase in ["red", "blue"] {
        assert_eq!(lines[2]["pieces"][phase]["count"], 1, "{phase}");
        assert_eq!(lines[2]["pieces"][phase]["largest"], 1.0, "{phase}");
    }
    assert!(lines[3]["summary"]["steps"].as_u64().unwrap() >= 2);
    // The resolved scene reloads, with the command-line overrides applied.
    let resolved = fs::read_to_string(out.join("scene.toml")).unwrap();
    let scene = polyphase_scenes::Scene::parse(&resolved, "scene.toml").unwrap();
    assert_eq!(scene.file.resolution, 16);
    assert_eq!(scene.file.time.frames, 2);
}

/// Water as two balls (radii 0.15 and 0.1, 4.8 and 3.2 cells) and oil as one, turned once
/// about the box's centre: the last frame counts two pieces of water, the larger holding
/// 0.15³ / (0.15³ + 0.1³) = 0.7714 of it, and one of oil. The background has no entry.
#[test]
fn periodic_runs_count_the_pieces_of_each_phase() {
    let dir = scratch("pieces");
    let ball = |phase: &str, c: [f64; 3], r: f64| {
        format!(
            "[[shapes]]\nphase = \"{phase}\"\nkind = \"sphere\"\ncenter = {c:?}\nradius = {r}\n"
        )
    };
    let scene = [
        "name = \"two_drops\"\nresolution = 32\nbackground = \"air\"\n".to_string(),
        "[domain]\nlo = [0.0, 0.0, 0.0]\nhi = [1.0, 1.0, 1.0]\n".to_string(),
        "[time]\nend = 1.0\nframes = 2\nperiodic = true\n".to_string(),
        "[velocity]\nfield = \"rotation\"\ncenter = [0.5, 0.5, 0.5]\nangular_velocity = 6.283185307179586\n"
            .to_string(),
        "[[phases]]\nname = \"air\"\n[[phases]]\nname = \"water\"\n[[phases]]\nname = \"oil\"\n"
            .to_string(),
        ball("water", [0.3, 0.5, 0.5], 0.15),
        ball("water", [0.72, 0.5, 0.5], 0.1),
        ball("oil", [0.5, 0.2, 0.5], 0.1),
    ]
    .join("\n");
    let path = dir.join("two_drops.toml");
    fs::write(&path, scene).unwrap();
    let out = dir.join("out");
    let o = run_file(&path, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = fs::read_to_string(out.join("stats.jsonl")).unwrap();
    let last: serde_json::Value = serde_json::from_str(stats.lines().nth(2).unwrap()).unwrap();
    let pieces = &last["pieces"];
    assert_eq!(pieces["water"]["count"], 2, "{pieces}");
    assert_eq!(pieces["oil"]["count"], 1, "{pieces}");
    assert!(pieces["air"].is_null(), "{pieces}");
    // A share s = V₁/(V₁ + V₂) moves by s(1 − s)(e₁ − e₂) for relative volume errors e₁, e₂
    // of the two balls; each within 3 % at 3–5 cells per radius gives 0.0106.
    let share = pieces["water"]["largest"].as_f64().unwrap();
    let exact = 0.15_f64.powi(3) / (0.15_f64.powi(3) + 0.1_f64.powi(3));
    assert!((share - exact).abs() < 0.0106, "{share} vs {exact}");
}

#[test]
fn one_and_two_threads_write_identical_frames() {
    let dir = scratch("threads");
    let run = |threads: &str| {
        let out = dir.join(format!("t{threads}"));
        let o = run_small("enright", 16, 2, &out, &["--threads", threads]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (0..=2)
            .map(|f| fs::read(out.join(format!("frames/{f:04}.ply"))).unwrap())
            .collect::<Vec<_>>()
    };
    assert!(
        run("1") == run("2"),
        "frames differ between 1 and 2 threads"
    );
}

#[test]
fn bad_scenes_fail_with_one_line_and_write_nothing() {
    let dir = scratch("bad_scenes");
    let good = polyphase_scenes::BUILTIN[0].1;
    let cases = [
        (
            "unknown_phase",
            good.replace("phase = \"blue\"", "phase = \"oil\""),
            "shapes[1].phase",
        ),
        (
            "negative_res",
            good.replace("resolution = 64", "resolution = -8"),
            "resolution",
        ),
        (
            "missing_field",
            good.replace("end = 1.0\n", ""),
            "missing field `end`",
        ),
        (
            "nan",
            good.replace("radius = 0.15\n\n# Upper", "radius = nan\n\n# Upper"),
            "shapes[0].radius",
        ),
        (
            "not_toml",
            "name = \"x\"\nresolution = [".to_string(),
            "bad.toml",
        ),
    ];
    for (name, text, expect) in cases {
        let path = dir.join(format!("{name}.toml"));
        fs::write(&path, text).unwrap();
        let out = dir.join(format!("{name}_out"));
        let o = run_file(&path, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{name}: should fail");
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: one line: {err}");
        let expect = if expect == "bad.toml" { name } else { expect };
        assert!(err.contains(expect), "{name}: '{expect}' not in {err}");
        assert!(!out.exists(), "{name}: output folder must not be created");
    }
}

#[test]
fn unwritable_output_and_unknown_scene_are_clear_errors() {
    let dir = scratch("unwritable");
    let file = dir.join("a_file");
    fs::write(&file, "not a folder").unwrap();
    let out = file.join("out");
    let o = polyphase(&[
        "run",
        "zalesak",
        "--resolution",
        "8",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("cannot create output folder"), "{err}");

    let o = polyphase(&["run", "no_such_scene"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("no_such_scene") && err.contains("zalesak"),
        "{err}"
    );
}
