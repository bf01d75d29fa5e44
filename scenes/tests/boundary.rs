//! `[solver.boundary]`: periodic, no-slip and moving walls are read, survive the resolved
//! scene, and bad values are refused with the place named.

use polyphase_scenes::{BoundaryKind, Scene};

/// A coupled channel scene with the given `[solver.boundary]` body and extra tables.
fn channel(boundary: &str, extra: &str) -> String {
    format!(
        r#"name = "channel"
resolution = 16
background = "a"

[domain]
lo = [0.0, 0.0, 0.0]
hi = [0.5, 1.0, 0.1]
slab = true

[time]
end = 1.0
frames = 1

[velocity]
field = "fluid"

[solver.boundary]
{boundary}

[[phases]]
name = "a"
{extra}"#
    )
}

fn refused(text: &str) -> String {
    match Scene::parse(text, "channel.toml") {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_moving_lid_over_a_periodic_channel_is_read_and_resolved() {
    let text = channel(
        "x = \"periodic\"\ny = \"no_slip\"\nwall_velocity = { y_high = [0.5, 0.0, -0.25] }",
        "",
    );
    let scene = Scene::parse(&text, "channel.toml").unwrap();
    let b = &scene.file.solver.as_ref().unwrap().boundary;
    // z was not named: free-slip, the default.
    assert_eq!(
        b.axes(),
        [
            BoundaryKind::Periodic,
            BoundaryKind::NoSlip,
            BoundaryKind::FreeSlip
        ]
    );
    assert_eq!(b.wall_velocity["y_high"], [0.5, 0.0, -0.25]);
    // The resolved scene (what a run folder keeps) reads back to the same boundary.
    let again = Scene::parse(&scene.to_toml(), "resolved.toml").unwrap();
    assert_eq!(&again.file.solver.unwrap().boundary, b);
}

#[test]
fn bad_boundaries_are_refused_with_the_place() {
    let err = refused(&channel(
        "y = \"no_slip\"\nwall_velocity = { y_top = [1.0, 0.0, 0.0] }",
        "",
    ));
    assert!(
        err.contains("solver.boundary.wall_velocity.y_top: unknown wall (walls: x_low,"),
        "{err}"
    );
    let err = refused(&channel("wall_velocity = { y_high = [1.0, 0.0, 0.0] }", ""));
    assert!(
        err.contains(
            "wall_velocity.y_high: only a no-slip wall moves, but solver.boundary.y is 'free_slip'"
        ),
        "{err}"
    );
    let err = refused(&channel(
        "y = \"no_slip\"\nwall_velocity = { y_low = [1.0, 0.2, 0.0] }",
        "",
    ));
    assert!(
        err.contains("wall_velocity.y_low[1]: a wall moves along itself only"),
        "{err}"
    );
    let err = refused(&channel("x = \"sticky\"", ""));
    assert!(err.contains("unknown variant `sticky`"), "{err}");
}

#[test]
fn a_velocity_profile_names_its_component_and_axis() {
    let measure = "\n[[measure]]\nkind = \"velocity_profile\"\ncomponent = \"x\"\n";
    let err = refused(&channel("", measure));
    assert!(
        err.contains("measure[0]: kind 'velocity_profile' needs the field 'axis'"),
        "{err}"
    );
    let measure = "\n[[measure]]\nkind = \"velocity_profile\"\ncomponent = \"q\"\naxis = \"y\"\n";
    let err = refused(&channel("", measure));
    assert!(
        err.contains("measure[0].component: must be x, y or z"),
        "{err}"
    );
    let ok = "\n[[measure]]\nkind = \"velocity_profile\"\ncomponent = \"x\"\naxis = \"y\"\n";
    let scene = Scene::parse(&channel("", ok), "channel.toml").unwrap();
    assert_eq!(scene.measures[0].name, "velocity_profile_x_y");
}
