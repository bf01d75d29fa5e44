//! `[[measure]] kind = "contact_angles"`: three different phases, by name, fitted over a reach
//! of tracker cells; anything else refused with the place named.

use polyphase_scenes::{MeasureKind, Scene};

/// A passive scene of three phases with one contact-angle measurement of `phases`.
fn scene(phases: &str) -> String {
    format!(
        r#"name = "junction"
resolution = 16
background = "a"

[domain]
lo = [0.0, 0.0, 0.0]
hi = [1.0, 1.0, 1.0]

[time]
end = 1.0
frames = 1

[velocity]
field = "still"

[[phases]]
name = "a"

[[phases]]
name = "b"

[[phases]]
name = "c"

[[shapes]]
phase = "b"
kind = "half_space"
point = [0.5, 0.5, 0.5]
normal = [0.0, 1.0, 0.0]

[[shapes]]
phase = "c"
kind = "sphere"
center = [0.5, 0.5, 0.5]
radius = 0.25
priority = 1

[[measure]]
kind = "contact_angles"
phases = {phases}
"#
    )
}

#[test]
fn three_phases_by_name() {
    let scene = Scene::parse(&scene(r#"["c", "b", "a"]"#), "junction.toml").unwrap();
    let m = &scene.measures[0];
    assert_eq!(m.name, "contact_angles_c_b_a");
    assert_eq!(
        m.kind,
        MeasureKind::ContactAngles {
            phases: [2, 1, 0],
            reach: 6.0 / 16.0,
        }
    );
}

#[test]
fn two_phases_or_a_repeated_one_are_refused() {
    let err = |phases: &str| {
        Scene::parse(&scene(phases), "junction.toml")
            .unwrap_err()
            .to_string()
    };
    let two = err(r#"["a", "b"]"#);
    assert!(
        two.contains("measure[0]: kind 'contact_angles' needs the field 'phases' with three"),
        "{two}"
    );
    let repeated = err(r#"["a", "b", "a"]"#);
    assert!(
        repeated.contains("measure[0].phases: needs three different phases"),
        "{repeated}"
    );
    let unknown = err(r#"["a", "b", "d"]"#);
    assert!(unknown.contains("measure[0].phases"), "{unknown}");
}
