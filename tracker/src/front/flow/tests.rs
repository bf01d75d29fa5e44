use glam::DVec3;

use super::*;
use crate::front::front_tracker::FrontTracker;
use crate::front::intersection::self_intersections;
use crate::front::params::FrontParams;
use crate::invariants::check;
use crate::mesh::fixtures::icosphere;
use crate::tracker::InterfaceTracker;
use polyphase_grid::VelocityField;

/// The field handed to `advance`, which a tracker with a flow ignores.
struct Still;

impl VelocityField for Still {
    fn velocity(&self, _x: DVec3, _t: f64) -> DVec3 {
        DVec3::ZERO
    }
}

/// Radius of the sphere with the volume of phase 1.
fn volume_radius(tracker: &FrontTracker) -> f64 {
    (3.0 * tracker.phase_volumes()[1] / (4.0 * std::f64::consts::PI)).cbrt()
}

fn sphere_tracker(r: f64, flow: MeshFlow) -> FrontTracker {
    let mesh = icosphere(DVec3::splat(0.5), r, 4, 1, 0);
    let params = FrontParams {
        edge_length: Some(0.04),
        ..FrontParams::default()
    };
    let mut tracker = FrontTracker::new(mesh, 2, 0, params).expect("a valid sphere");
    tracker.set_flow(flow);
    tracker
}

fn assert_valid(tracker: &FrontTracker) {
    check(tracker.mesh(), 0.0).expect("closed and label-consistent");
    assert!(self_intersections(tracker.mesh()).is_empty());
}

/// Normal flow of a sphere at speed s: radius r0 + s·t (paper 000 §8.2's expanding sphere).
#[test]
fn normal_flows_grow_a_sphere_at_their_speed() {
    let (r0, s) = (0.2, 0.5);
    let speeds = vec![PairSpeed {
        from: 1,
        into: 0,
        speed: s,
    }];
    for flow in [
        MeshFlow::Normal(speeds.clone()),
        MeshFlow::NormalOffset(speeds),
    ] {
        let mut tracker = sphere_tracker(r0, flow.clone());
        // The inscribed polyhedron's volume radius falls short of the vertex radius by the
        // same fraction at both ends (the remesher keeps the edge length at L relative to
        // r), so compare ratios.
        let start = volume_radius(&tracker);
        let (frames, dt) = (5, 0.04);
        for f in 0..frames {
            tracker
                .advance(&Still, f as f64 * dt, dt)
                .expect("a finite flow");
            assert_valid(&tracker);
        }
        let t = frames as f64 * dt;
        let expected = (r0 + s * t) / r0;
        let ratio = volume_radius(&tracker) / start;
        // Volume within 1 % (the bound) is the radius within a third of that.
        assert!(
            (ratio / expected - 1.0).abs() < 0.01 / 3.0,
            "{flow:?}: radius ratio {ratio} against {expected}"
        );
    }
}

/// Mean-curvature flow of a sphere: r² = r0² − 4t (the area gradient of a sphere is 2/r per
/// unit area, inward), checked at 60 % of the extinction time r0²/4.
#[test]
fn mean_curvature_flow_shrinks_a_sphere_as_r_squared_falls_linearly() {
    let r0 = 0.3;
    let mut tracker = sphere_tracker(r0, MeshFlow::MeanCurvature { rate: 1.0 });
    let start = volume_radius(&tracker);
    let t_end = 0.6 * r0 * r0 / 4.0;
    let frames = 6;
    for f in 0..frames {
        let dt = t_end / frames as f64;
        tracker
            .advance(&Still, f as f64 * dt, dt)
            .expect("a finite flow");
        assert_valid(&tracker);
    }
    let expected = (r0 * r0 - 4.0 * t_end).sqrt() / r0;
    let ratio = volume_radius(&tracker) / start;
    // 2 % of the radius: the extinction-time bound of the issue (2 %) on r² at this point.
    assert!(
        (ratio / expected - 1.0).abs() < 0.02,
        "radius ratio {ratio} against {expected}"
    );
}

/// Curl noise is divergence-free and within its stated speed bound.
#[test]
fn curl_noise_is_divergence_free_and_bounded() {
    let noise = CurlNoise::new(0.3, 0.5, 7);
    let e = 1e-5;
    for i in 0..50 {
        let x = DVec3::new(
            0.37 * i as f64,
            0.11 * i as f64 + 0.2,
            0.5 - 0.07 * i as f64,
        );
        let d = |a: DVec3| {
            (noise.velocity(x + a * e, 0.0) - noise.velocity(x - a * e, 0.0)) / (2.0 * e)
        };
        let div = d(DVec3::X).x + d(DVec3::Y).y + d(DVec3::Z).z;
        // Each derivative is of size amplitude·k ≈ 3.8 (k = 2π/0.5); central differences
        // leave (k·e)²/6 ≈ 7e-8 of it and rounding ~1e-16·0.3/e ≈ 3e-12, so 1e-6 of the
        // derivatives' size is far above both and far below a divergent field's.
        let k = 2.0 * std::f64::consts::PI / 0.5;
        assert!(div.abs() < 1e-6 * 0.3 * k, "divergence {div} at {x}");
        assert!(noise.velocity(x, 0.0).length() <= noise.max_speed());
    }
}

/// Mean-curvature flow of a sphere to extinction: r² = r0² − 4t gives t = r0²/4 (measured
/// +0.5 %); the sphere goes as one region when its volume falls below the T2 bound (a cube of half an edge
/// length, then ~1e-4 of its start), the region count dropping by exactly one. Within 2 % of
/// the extinction time (the bound; the radius at 60 % of it is within 1 %).
#[test]
fn mean_curvature_flow_extinguishes_a_sphere_on_time() {
    let r0 = 0.3;
    let mut tracker = sphere_tracker(r0, MeshFlow::MeanCurvature { rate: 1.0 });
    assert_eq!(tracker.region_count(), Some(2));
    let extinction = r0 * r0 / 4.0;
    let dt = extinction / 100.0;
    let mut t = 0.0;
    while tracker.region_count() == Some(2) && t < 1.5 * extinction {
        tracker.advance(&Still, t, dt).expect("a finite flow");
        t += dt;
        assert_valid(&tracker);
    }
    assert_eq!(
        tracker.region_count(),
        Some(1),
        "the sphere is still there at {t}"
    );
    assert!(tracker.phase_volumes()[1].abs() < 1e-12);
    // It went during the last step: its midpoint, to within half a step (0.5 %).
    let gone = t - 0.5 * dt;
    assert!(
        (gone / extinction - 1.0).abs() < 0.02,
        "gone at {gone}, r² = r0² − 4t says {extinction}"
    );
}
