//! Scene input end to end: mesh shapes from OBJ files the tests write, and bad input (ambiguous
//! overlaps, non-positive density, unreadable, malformed or open OBJ files), each of which must
//! stop `polyphase run` with one line naming the place and leave no output folder.

mod common;

use std::fs;
use std::path::Path;

use common::{run_file, scratch};
use polyphase_scenes::Scene;

/// A regular octahedron |x − c|₁ ≤ a as OBJ text (outward faces), volume 4a³/3.
fn octahedron(c: [f64; 3], a: f64) -> String {
    let mut s = String::new();
    for (axis, sign) in [
        (0, 1.0),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ] {
        let mut v = c;
        v[axis] += sign * a;
        s += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    // Vertices 1..6 = +x, −x, +y, −y, +z, −z; each face is one octant, counter-clockwise outside.
    for (x, y, z) in [
        (1, 3, 5),
        (3, 2, 5),
        (2, 4, 5),
        (4, 1, 5),
        (3, 1, 6),
        (2, 3, 6),
        (4, 2, 6),
        (1, 4, 6),
    ] {
        s += &format!("f {x} {y} {z}\n");
    }
    s
}

/// A still (passive) scene over the unit cube with the given extra phases and shapes.
fn scene_text(phases: &str, shapes: &str) -> String {
    format!(
        r#"name = "input"
resolution = 16
background = "air"

[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]

[time]
end = 1.0
frames = 1

[velocity]
field = "still"

[[phases]]
name = "air"
density = 1.2

{phases}
{shapes}"#
    )
}

const TWO_LIQUIDS: &str = r#"
[[phases]]
name = "water"
density = 1000.0

[[phases]]
name = "oil"
density = 800.0
"#;

fn mesh_shape(phase: &str, file: &str) -> String {
    format!("[[shapes]]\nphase = \"{phase}\"\nkind = \"mesh\"\nfile = \"{file}\"\n")
}

fn sphere(phase: &str, x: f64, priority: i64) -> String {
    format!(
        "[[shapes]]\nphase = \"{phase}\"\nkind = \"sphere\"\ncenter = [{x}, 0.5, 0.5]\nradius = 0.2\npriority = {priority}\n"
    )
}

#[test]
fn mesh_shape_volume_and_resolved_path() {
    let dir = scratch("mesh_shape");
    fs::create_dir_all(dir.join("shapes")).unwrap();
    let a = 0.3;
    fs::write(dir.join("shapes/oct.obj"), octahedron([0.5; 3], a)).unwrap();
    // Relative to the scene file's folder, whatever the working directory.
    let text = scene_text(TWO_LIQUIDS, &mesh_shape("water", "shapes/oct.obj"));
    let path = dir.join("oct.toml");
    fs::write(&path, &text).unwrap();
    let scene = polyphase_scenes::load(path.to_str().unwrap()).unwrap();
    let v = scene.reference_volumes();
    let exact = 4.0 / 3.0 * a * a * a;
    // The quadrature's error is O(h²) per unit area on faces tilted to the axes
    // (volume.rs), with h = 1/1024 for mesh scenes and area 8·(√3/2)a² ≈ 0.62: about
    // area·h² ≈ 5.9e-7 absolute; twice that leaves margin.
    let area = 4.0 * 3f64.sqrt() * a * a;
    let h = 1.0 / 1024.0;
    assert!(
        (v[1] - exact).abs() < 2.0 * area * h * h,
        "{v:?} vs {exact}"
    );
    assert!(
        v[2] == 0.0 && (v.iter().sum::<f64>() - 1.0).abs() < 1e-12,
        "{v:?}"
    );
    // Inside and outside by the OBJ, not its bounding box: a corner of the box is air.
    assert_eq!(scene.initial.phase(glam::DVec3::splat(0.5)), 1);
    assert_eq!(scene.initial.phase(glam::DVec3::splat(0.75)), 0);

    // The run folder's scene.toml names the OBJ by absolute path, so it reloads elsewhere.
    let out = dir.join("out");
    let o = run_file(&path, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("frames/0001.ply").is_file());
    let resolved = fs::read_to_string(out.join("scene.toml")).unwrap();
    let abs = std::path::absolute(dir.join("shapes/oct.obj")).unwrap();
    assert!(resolved.contains(abs.to_str().unwrap()), "{resolved}");
    let again = Scene::parse(&resolved, "/nowhere/scene.toml").unwrap();
    assert_eq!(again.reference_volumes(), v);
}

/// Writes `text` as a scene (and `obj` as `shape.obj` beside it, if given), runs it and checks
/// it fails with one line containing every string of `expect` and creates no output folder.
fn assert_refused(dir: &Path, name: &str, text: &str, obj: Option<&str>, expect: &[&str]) {
    let case = dir.join(name);
    fs::create_dir_all(&case).unwrap();
    if let Some(obj) = obj {
        fs::write(case.join("shape.obj"), obj).unwrap();
    }
    let path = case.join("scene.toml");
    fs::write(&path, text).unwrap();
    let out = case.join("out");
    let o = run_file(&path, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{name}: should fail");
    assert_eq!(err.trim_end().lines().count(), 1, "{name}: one line: {err}");
    assert!(
        err.contains(path.to_str().unwrap()),
        "{name}: origin: {err}"
    );
    for e in expect {
        assert!(err.contains(e), "{name}: '{e}' not in {err}");
    }
    assert!(!out.exists(), "{name}: output folder must not be created");
}

#[test]
fn bad_scene_input_fails_with_one_line_and_writes_nothing() {
    let dir = scratch("scene_input_bad");
    let overlap = format!("{}\n{}", sphere("water", 0.35, 0), sphere("oil", 0.65, 0));
    assert_refused(
        &dir,
        "overlap",
        &scene_text(TWO_LIQUIDS, &overlap),
        None,
        &["shapes[1]: overlaps shapes[0]", "priority"],
    );
    let dense = TWO_LIQUIDS.replace("density = 800.0", "density = 0.0");
    assert_refused(
        &dir,
        "density",
        &scene_text(&dense, ""),
        None,
        &["phases[2].density", "must be positive"],
    );
    let missing = scene_text(TWO_LIQUIDS, &mesh_shape("oil", "no_such.obj"));
    assert_refused(
        &dir,
        "unreadable",
        &missing,
        None,
        &["shapes[0].file", "no_such.obj", "cannot read OBJ file"],
    );
    let with_obj = scene_text(TWO_LIQUIDS, &mesh_shape("oil", "shape.obj"));
    assert_refused(
        &dir,
        "malformed",
        &with_obj,
        Some("v 0 0 zero\nf 1 2 3\n"),
        &["shapes[0].file", "shape.obj", "not a valid OBJ"],
    );
    let unknown = format!(
        "{}\n[[measure]]\nkind = \"pieces\"\nphase = \"honey\"\n",
        sphere("water", 0.35, 0)
    );
    assert_refused(
        &dir,
        "measure_phase",
        &scene_text(TWO_LIQUIDS, &unknown),
        None,
        &["measure[0].phase", "unknown phase 'honey'"],
    );
    let axis = "[[measure]]\nkind = \"front\"\nphase = \"water\"\naxis = \"w\"\n";
    assert_refused(
        &dir,
        "measure_axis",
        &scene_text(TWO_LIQUIDS, axis),
        None,
        &["measure[0].axis", "must be x, y or z"],
    );
    let rise = "[[measure]]\nkind = \"rise_velocity\"\nphase = \"water\"\n";
    assert_refused(
        &dir,
        "measure_rise",
        &scene_text(TWO_LIQUIDS, rise),
        None,
        &["measure[0].kind", "needs a coupled scene"],
    );
    let reversed = fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/builtin/merge2_reverse.toml"),
    )
    .unwrap()
    .replace("reverse_at = 0.3", "reverse_at = nan");
    assert_refused(
        &dir,
        "reverse_at",
        &reversed,
        None,
        &["velocity.reverse_at", "must be a finite number"],
    );
    // The octahedron without its last face: three edges with one face each.
    let open = octahedron([0.5; 3], 0.3).replace("f 1 4 6\n", "");
    assert_refused(
        &dir,
        "open",
        &with_obj,
        Some(&open),
        &["shapes[0].file", "shape.obj", "not closed"],
    );
}

#[test]
fn priority_settles_an_overlap_and_the_higher_one_wins() {
    let shapes = format!("{}\n{}", sphere("water", 0.35, 0), sphere("oil", 0.65, 1));
    let scene = Scene::parse(&scene_text(TWO_LIQUIDS, &shapes), "p.toml").unwrap();
    // x = 0.5 lies in both balls: oil (priority 1) fills it, though it comes second here...
    assert_eq!(scene.initial.phase(glam::DVec3::splat(0.5)), 2);
    // ...and also when it comes first in the file.
    let swapped = format!("{}\n{}", sphere("oil", 0.65, 1), sphere("water", 0.35, 0));
    let scene = Scene::parse(&scene_text(TWO_LIQUIDS, &swapped), "p.toml").unwrap();
    assert_eq!(scene.initial.phase(glam::DVec3::splat(0.5)), 2);
    // Same phase, same priority: a union, no conflict.
    let union = format!("{}\n{}", sphere("oil", 0.35, 0), sphere("oil", 0.65, 0));
    assert!(Scene::parse(&scene_text(TWO_LIQUIDS, &union), "p.toml").is_ok());
}

#[test]
fn declared_measurements_reach_the_stats() {
    let dir = scratch("measure_stats");
    let shapes = format!(
        "{}\n{}\n[[measure]]\nkind = \"pieces\"\nphase = \"water\"\n\n\
         [[measure]]\nkind = \"centroid\"\nphase = \"oil\"\n\n\
         [[measure]]\nkind = \"front\"\nname = \"reach\"\nphase = \"oil\"\naxis = \"x\"\n",
        sphere("water", 0.3, 0),
        sphere("oil", 0.7, 0)
    );
    let path = dir.join("two.toml");
    fs::write(&path, scene_text(TWO_LIQUIDS, &shapes)).unwrap();
    let out = dir.join("out");
    let o = run_file(&path, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stats = fs::read_to_string(out.join("stats.jsonl")).unwrap();
    // The last line is the run's summary; the one before it is frame 1's.
    let lines: Vec<&str> = stats.lines().collect();
    let last: serde_json::Value = serde_json::from_str(lines[lines.len() - 2]).unwrap();
    let pieces = last["pieces_water"].as_array().unwrap();
    assert_eq!(pieces.len(), 1, "{last}");
    let (r, h) = (0.2, 1.0 / 16.0);
    let volume = pieces[0]["volume"].as_f64().unwrap();
    let exact = 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    // One step of the volume correction leaves −0.075 % of the exact ball (what it has not
    // yet given back of the first contouring's loss at 3.2 cells per radius); the piece is the
    // whole phase, so its volume must be the phase's, within that 0.1 %.
    assert!((volume / exact - 1.0).abs() < 1e-3, "{volume} vs {exact}");
    // A ball contoured at 3.2 cells per radius: vertices within a tenth of a cell of the
    // sphere, which is 1/32 of the radius.
    for key in ["nearest", "farthest"] {
        let x = pieces[0][key].as_f64().unwrap();
        assert!((x - 1.0).abs() < 0.1 * h / r, "{key} {x}");
    }
    let c = last["centroid_oil"].as_array().unwrap();
    let c: Vec<f64> = c.iter().map(|v| v.as_f64().unwrap()).collect();
    // Symmetric contouring about the ball's centre, up to the cell-aligned asymmetry.
    assert!(
        (c[0] - 0.7).abs() < 0.05 * h && (c[1] - 0.5).abs() < 0.05 * h,
        "{c:?}"
    );
    // The correction's share is visible: frame 1 reports the volume its first step added, which
    // is what the first contouring left short of the exact ball (2.3 % at 3.2 cells per
    // radius); the target is the scene's quadrature volume, within 1e-6 of the exact one, so
    // the two agree to 1e-3 of the gap.
    let first: serde_json::Value = serde_json::from_str(lines[0]).unwrap();
    let v0 = first["phase_volumes"]["water"].as_f64().unwrap();
    let gap = (exact - v0) / exact;
    let given = last["volume_correction"]["water"].as_f64().unwrap();
    assert!(
        gap > 0.01 && (given - gap).abs() < 1e-3 * gap,
        "{given} vs {gap}"
    );
    let reach = last["reach"].as_f64().unwrap();
    assert!((reach - 0.9).abs() < 0.5 * h, "oil reaches x = {reach}");
}
