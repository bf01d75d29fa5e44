//! `[[measure]] kind = "circularity"`: read in a slab scene, cut at its mid-plane, and refused
//! in a 3D scene with the place named.

use polyphase_scenes::{MeasureKind, Scene};

/// A passive scene with one circularity measurement, as a slab or in 3D.
fn scene(slab: bool) -> String {
    format!(
        r#"name = "disc"
resolution = 16
background = "a"

[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 0.1]
slab = {slab}

[time]
end = 1.0
frames = 1

[velocity]
field = "still"

[[phases]]
name = "a"

[[phases]]
name = "b"

[[shapes]]
phase = "b"
kind = "cylinder"
center = [0.5, 0.5, 0.0]
radius = 0.25

[[measure]]
kind = "circularity"
phase = "b"
"#
    )
}

#[test]
fn a_slab_cuts_at_its_mid_plane() {
    let scene = Scene::parse(&scene(true), "disc.toml").unwrap();
    let m = &scene.measures[0];
    assert_eq!(m.name, "circularity_b");
    // The slab is snapped to two tracker cells of 1/16: its mid-plane is z = 1/16.
    let mid = 0.5 * (scene.file.domain.lo[2] + scene.file.domain.hi[2]);
    assert_eq!(mid, 1.0 / 16.0);
    assert_eq!(m.kind, MeasureKind::Circularity { phase: 1, z: mid });
}

#[test]
fn a_3d_scene_is_refused() {
    let err = Scene::parse(&scene(false), "disc.toml")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            "measure[0].kind: 'circularity' measures a 2D cross-section: it needs a slab scene"
        ),
        "{err}"
    );
}
