//! The `[foam]` table: a Voronoi foam's phases are made or checked, its reference volumes are
//! its cells' exact volumes, and contradictory files are refused with the place named.

use polyphase_scenes::Scene;

fn scene(foam: &str, phases: &str, extra: &str) -> String {
    format!(
        r#"
name = "f"
resolution = 8
background = "cell0"
tracker = "front"
{extra}
[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 2.0, 1.0]

[time]
end = 0.01
frames = 1

[velocity]
field = "mean_curvature"

[foam]
{foam}
{phases}
"#
    )
}

#[test]
fn cells_become_phases_that_fill_the_box() {
    let s = Scene::parse(&scene("regions = 20\nseed = 3", "", ""), "test").expect("valid");
    assert_eq!(s.file.phases.len(), 20);
    assert_eq!(s.file.phases[19].name, "cell19");
    let v = s.reference_volumes();
    // The cells tile the 1 × 2 × 1 box; the clipped polytopes' volumes sum to it up to rounding.
    assert!((v.iter().sum::<f64>() - 2.0).abs() < 1e-12, "{v:?}");
    // The resolved file (with its phases written out) reads back as the same foam.
    let text = toml::to_string(&s.file).expect("serialises");
    let again = Scene::parse(&text, "again").expect("the resolved file is valid");
    assert_eq!(again.reference_volumes(), v);
}

#[test]
fn contradictions_are_refused_with_the_place() {
    let refused = |text: String| Scene::parse(&text, "test").unwrap_err().to_string();
    let e = refused(scene("regions = 1", "", ""));
    assert!(e.contains("foam.regions"), "{e}");
    let e = refused(scene(
        "regions = 3",
        "[[phases]]\nname = \"cell0\"\n[[phases]]\nname = \"b\"",
        "",
    ));
    assert!(e.contains("phases") && e.contains("exactly 3"), "{e}");
    let shape = "[[shapes]]\nphase = \"cell0\"\nkind = \"sphere\"\ncenter = [0.5, 0.5, 0.5]\nradius = 0.1\n";
    let text = scene("regions = 3", "", "") + shape;
    let e = refused(text);
    assert!(e.contains("shapes"), "{e}");
}
