//! End-to-end coupled runs through the binary: frames, stats with diagnostics, bad input.

mod common;

use std::fs;

use common::{run_file, run_small, scratch};

#[test]
fn coupled_column_writes_frames_and_surge_front() {
    let out = scratch("coupled_column");
    let o = run_small("dambreak_column", 32, 4, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 0..=4 {
        assert!(
            out.join(format!("frames/{f:04}.ply")).is_file(),
            "frame {f}"
        );
    }
    let stats = fs::read_to_string(out.join("stats.jsonl")).unwrap();
    let lines: Vec<serde_json::Value> = stats
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 6, "5 frames and the summary");
    // The front starts at the column's side, x = a = 0.1 m, and only moves outward.
    let fronts: Vec<f64> = lines[..5]
        .iter()
        .map(|l| l["surge_front"].as_f64().unwrap())
        .collect();
    // Within one tracker cell (0.5 m / 32) of the initial side.
    assert!((fronts[0] - 0.1).abs() < 0.5 / 32.0, "{fronts:?}");
    assert!(fronts.windows(2).all(|w| w[1] >= w[0]), "{fronts:?}");
    assert!(fronts[4] > 0.2, "{fronts:?}");
    assert!(lines[1]["pressure_iterations"].as_u64().unwrap() > 0);
    assert!(
        lines[5]["summary"]["solver_iterations"]["pressure"]
            .as_u64()
            .unwrap()
            > 0
    );
    let resolved = fs::read_to_string(out.join("scene.toml")).unwrap();
    assert!(resolved.contains("[solver]") && resolved.contains("field = \"fluid\""));
}

#[test]
fn bad_coupled_input_fails_with_one_line_and_writes_nothing() {
    let dir = scratch("coupled_bad");
    let good = polyphase_scenes::BUILTIN
        .iter()
        .find(|(n, _)| *n == "dambreak_column")
        .unwrap()
        .1;
    let path = dir.join("dense.toml");
    fs::write(&path, good.replace("density = 1000.0", "density = -5.0")).unwrap();
    let out = dir.join("dense_out");
    let o = run_file(&path, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains("phases[1].density"), "{err}");
    assert!(!out.exists());

    let file = dir.join("a_file");
    fs::write(&file, "not a folder").unwrap();
    let o = run_small("dambreak_column", 16, 1, &file.join("out"), &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("cannot create output folder"), "{err}");
}
