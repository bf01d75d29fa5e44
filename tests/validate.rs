//! `polyphase validate`: the shipped cases pass in their quick versions (known gaps listed as
//! such), and a failing or unknown case makes the command fail with the case named.

mod common;

use std::fs;
use std::path::Path;
use std::process::Output;

use common::{polyphase, scratch};
use serde_json::Value;

#[test]
fn shipped_cases_pass_in_their_quick_versions() {
    let dir = scratch("validate_quick");
    let json = dir.join("results.json");
    let o = polyphase(&[
        "validate",
        "--quick",
        "--out",
        dir.join("runs").to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{table}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let rows: Value = serde_json::from_str(&fs::read_to_string(&json).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    for case in [
        "couette2",
        "drop_oscillation2",
        "fall",
        "hydrostatic2",
        "hydrostatic3",
        "laplace2",
        "martin_moyce2",
        "poiseuille2",
        "rt_linear",
        "table2_enright",
        "bubble_rise2",
        "vortex4",
    ] {
        assert!(
            rows.iter().any(|r| r["case"] == case && r["pass"] == true),
            "{case} missing or failed: {table}"
        );
    }
    // The square column is a known gap (its case file says why): listed as one, not a pass, and
    // its note gives the error from the release beside the aligned one.
    let square = rows
        .iter()
        .find(|r| r["case"] == "martin_moyce1")
        .unwrap_or_else(|| panic!("martin_moyce1 missing: {table}"));
    assert_eq!(square["verdict"], "known gap", "{square}");
    assert!(square["note"]
        .as_str()
        .unwrap()
        .contains("from the release"));
    // The static drop with the front tracker: its Laplace jump and its spurious currents pass
    // (issue 15), the currents since the start lies on the exact circle.
    let front: Vec<&Value> = rows
        .iter()
        .filter(|r| r["case"] == "laplace2_front")
        .collect();
    assert_eq!(front.len(), 2, "{table}");
    assert!(front.iter().all(|r| r["verdict"] == "pass"), "{table}");
    // So is Table 2's accuracy on the notched sphere at 128³ (issue 17); its e_i passes.
    let zalesak: Vec<&Value> = rows
        .iter()
        .filter(|r| r["case"] == "table2_zalesak")
        .collect();
    assert_eq!(zalesak.len(), 2, "{table}");
    assert_eq!(zalesak[0]["verdict"], "known gap", "{table}");
    assert_eq!(zalesak[1]["verdict"], "pass", "{table}");
    // Every row names its reference's source and carries the numbers of the table.
    for r in rows {
        assert!(!r["source"].as_str().unwrap().is_empty());
        assert!(r["ours"].is_f64() && r["tolerance"].is_f64(), "{r}");
    }
    // Every metric that has a curve is plotted, ours beside its reference: a two-curve SVG.
    for (case, plot, reference) in [
        ("couette2", "u_profile__L____max_u", "exact layered flow"),
        ("fall", "centroid_drop", "g t² / 2"),
        ("rt_linear", "growth_rate_ln_a_a0__t", "exact linear theory"),
        ("hydrostatic2", "spurious_speed__m_s_", "bound"),
        ("martin_moyce2", "surge_front_Z_T_", "martin_moyce_n2.csv"),
    ] {
        let path = dir
            .join("runs")
            .join(format!("{case}-quick/plots/{plot}.svg"));
        let svg = fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains(">polyphase") && svg.contains(&format!(">{reference}</text>")));
    }
}

/// `polyphase validate --quick` of the case folder `case`, runs under `dir/runs`.
fn validate_quick(dir: &Path, case: &Path) -> Output {
    polyphase(&[
        "validate",
        "--quick",
        "--out",
        dir.join("runs").to_str().unwrap(),
        case.to_str().unwrap(),
    ])
}

#[test]
fn a_failing_or_unknown_case_fails_the_command_and_names_it() {
    let dir = scratch("validate_user");
    let case = dir.join("my_column");
    fs::create_dir_all(&case).unwrap();
    // A user's own case: the built-in column's surge front against a made-up reference that
    // runs 50 % ahead of it, so the 5 % tolerance must fail.
    fs::write(
        case.join("case.toml"),
        r#"description = "made-up reference"
scene = "builtin:dambreak_column"
source = "invented for the test"
quick_resolution = 32

[[metric]]
name = "surge front"
kind = "series"
key = "surge_front"
reference = "front.csv"
tolerance = 0.05
"#,
    )
    .unwrap();
    fs::write(case.join("front.csv"), "time,front\n0.0,0.15\n0.1,0.3\n").unwrap();
    let o = validate_quick(&dir, &case);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(!o.status.success(), "{out}");
    assert!(out.contains("my_column") && out.contains("FAIL"), "{out}");
    assert!(err.contains("my_column: surge front"), "{err}");

    // A known gap that passes fails the command until its `known_gap` line goes: the same case
    // with a tolerance of 1000 % passes.
    let text = fs::read_to_string(case.join("case.toml")).unwrap();
    // The case with its tolerance line replaced, validated in its quick version: the table.
    let with_tolerance = |line: &str| {
        fs::write(
            case.join("case.toml"),
            text.replace("tolerance = 0.05", line),
        )
        .unwrap();
        let o = validate_quick(&dir, &case);
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
        )
    };
    let (ok, out) = with_tolerance("tolerance = 10.0\nknown_gap = \"made up\"");
    assert!(!ok, "{out}");
    assert!(out.contains("FAIL: passes, remove known_gap"), "{out}");

    // A gap of the quick version alone (`quick_known_gap`): the failing quick run lists it as
    // a known gap and the command succeeds.
    let (ok, out) = with_tolerance("tolerance = 0.05\nquick_known_gap = \"made up\"");
    assert!(ok, "{out}");
    assert!(
        out.contains("known gap") && out.contains("made up"),
        "{out}"
    );

    // First-step metrics measure the contouring tracker (paper 004 Table 2): a case that asks
    // for the front tracker is refused by name, before anything runs.
    let first = dir.join("front_first_step");
    fs::create_dir_all(&first).unwrap();
    fs::write(
        first.join("case.toml"),
        r#"description = "Table 2 with the wrong tracker"
scene = "builtin:zalesak"
tracker = "front"
source = "paper 004 Table 2"
quick_resolution = 32

[[metric]]
name = "indicator accuracy (%)"
kind = "indicator_accuracy"
table = [[32, 99.9517, 1.30]]
tolerance = 0.15
"#,
    )
    .unwrap();
    let o = validate_quick(&dir, &first);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(!o.status.success(), "{out}");
    assert!(
        out.contains("case 'front_first_step'") && out.contains("not tracker = \"front\""),
        "{out}"
    );
    assert!(err.contains("front_first_step: did not run"), "{err}");

    let o = polyphase(&["validate", "no_such_case"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("unknown validation case 'no_such_case'") && err.contains("rt_linear"),
        "{err}"
    );
}
