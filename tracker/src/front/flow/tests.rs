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
        MeshFlow::Normal {
            speeds: speeds.clone(),
            reverse_at: None,
        },
        MeshFlow::NormalOffset {
            speeds,
            reverse_at: None,
        },
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

/// Normal flow reversed at `reverse_at` (paper 000 §8.2's reversed Fig. 15): a sphere grown at
/// speed s until T shrinks at s after it, radius r0 + s·T − s·(t − T). The reversal falls
/// inside a frame, which the flow splits there: taken whole either way, the radius at the end
/// of that frame would be 0.02 (8 %) off, against the third of a percent held here.
#[test]
fn a_reversed_normal_flow_shrinks_a_sphere_back_from_the_reversal() {
    let (r0, s, turn) = (0.2, 0.5, 0.1);
    let flow = MeshFlow::Normal {
        speeds: vec![PairSpeed {
            from: 1,
            into: 0,
            speed: s,
        }],
        reverse_at: Some(turn),
    };
    let mut tracker = sphere_tracker(r0, flow);
    let start = volume_radius(&tracker);
    let dt = 0.04;
    for f in 0..5 {
        let t = f as f64 * dt;
        tracker.advance(&Still, t, dt).expect("a finite flow");
        assert_valid(&tracker);
        let end = t + dt;
        let expected = (r0 + s * (turn - (end - turn).abs())) / r0;
        let ratio = volume_radius(&tracker) / start;
        // Volume within 1 % (as the growing sphere's test) is the radius within a third.
        assert!(
            (ratio / expected - 1.0).abs() < 0.01 / 3.0,
            "t = {end}: radius ratio {ratio} against {expected}"
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

/// Two tetrahedra of phases 1 and 2 glued on a common face in the plane z = 0, apexes at
/// heights `up` and `-down`, in phase 0: the common face's three edges are a triple curve.
/// Each triangle is oriented with its normal into `front`.
fn glued_tetrahedra(up: f64, down: f64) -> crate::mesh::LabeledMesh {
    let vertices = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.3, 0.3, up),
        DVec3::new(0.3, 0.3, -down),
    ];
    let centroid = |ids: [u32; 4]| ids.iter().map(|&i| vertices[i as usize]).sum::<DVec3>() / 4.0;
    let (upper, lower) = (centroid([0, 1, 2, 3]), centroid([0, 1, 2, 4]));
    let mut triangles = Vec::new();
    let mut labels = Vec::new();
    // (triangle, phase inside, phase outside, centroid of the inside tetrahedron)
    let faces = [
        ([0, 1, 2], 2, 1, lower),
        ([0, 1, 3], 1, 0, upper),
        ([1, 2, 3], 1, 0, upper),
        ([2, 0, 3], 1, 0, upper),
        ([0, 1, 4], 2, 0, lower),
        ([1, 2, 4], 2, 0, lower),
        ([2, 0, 4], 2, 0, lower),
    ];
    for (t, inside, outside, c) in faces {
        let [a, b, d] = t.map(|i: u32| vertices[i as usize]);
        let outward = (b - a).cross(d - a).dot((a + b + d) / 3.0 - c) > 0.0;
        triangles.push(t);
        labels.push(if outward {
            [outside, inside]
        } else {
            [inside, outside]
        });
    }
    crate::mesh::LabeledMesh {
        vertices,
        triangles,
        labels,
    }
}

/// Per sheet around vertex `v` of `c`: the pair, Σ area normals oriented from the lower phase
/// into the higher, Σ area.
fn sheets_at(c: &crate::front::connectivity::Connectivity, v: u32) -> Vec<([u16; 2], DVec3, f64)> {
    let mut sheets: Vec<([u16; 2], DVec3, f64)> = Vec::new();
    for &t in c.vertex_triangles(v) {
        let [front, back] = c.labels(t);
        let [a, b, d] = c.triangle(t).map(|i| c.position(i));
        let n = (b - a).cross(d - a);
        let key = [front.min(back), front.max(back)];
        let oriented = if front == key[1] { n } else { -n };
        match sheets.iter_mut().find(|s| s.0 == key) {
            Some(s) => {
                s.1 += oriented;
                s.2 += 0.5 * n.length();
            }
            None => sheets.push((key, oriented, 0.5 * n.length())),
        }
    }
    sheets
}

/// Normal flow where sheets meet (a lens of two shrinking liquids in air, the reversed
/// `merge2`): the triple curve moves so that each sheet around it moves at its own speed,
/// where the speeds allow it (two mirror-image tetrahedra shrinking alike beside a standing
/// interface between them: d·nₖ = sₖ exactly for every sheet), and in the least-squares sense
/// where they do not (Σ Aₖ (d·nₖ − sₖ) nₖ = 0: the normal equations); a vertex on one sheet
/// moves at its sheet's speed along its normal. The area-weighted mean of the sheets' motions,
/// used before, moved the symmetric curve too slowly (0.068 against 0.1 along the sheets'
/// normals here, the standing sheet counting as standing still), and a shrinking lens of two
/// spheres lagged its exact volume by 19 % at the moment it should have become two balls.
#[test]
fn normal_flow_moves_a_triple_curve_with_every_sheet_at_its_speed() {
    let speed = |from, speed| PairSpeed {
        from,
        into: 0,
        speed,
    };
    for (up, down, s2, exact) in [(1.0, 1.0, -0.1, true), (1.0, 0.7, 0.2, false)] {
        let c = crate::front::connectivity::Connectivity::new(glued_tetrahedra(up, down));
        let velocity = normal::velocities(&c, &[speed(1, -0.1), speed(2, s2)], 1.0);
        for v in 0..5 {
            let d = velocity[v as usize];
            let sheets = sheets_at(&c, v);
            let mut residual = DVec3::ZERO;
            for (key, n, area) in &sheets {
                // Along the lower-to-higher orientation: from 1 into 0 at −0.1 is 0 into 1 at
                // +0.1; the 1–2 interface has no speed.
                let s = match key {
                    [0, 1] => 0.1,
                    [0, 2] => -s2,
                    _ => 0.0,
                };
                let n = n.normalize();
                let along = d.dot(n);
                // A 3×3 eigen-solve in f64: round-off far below 1e-12 m/s.
                if exact {
                    assert!(
                        (along - s).abs() < 1e-12,
                        "vertex {v}, sheet {key:?}: {along} against {s}"
                    );
                }
                residual += *area * (along - s) * n;
            }
            assert!(
                residual.length() < 1e-12,
                "vertex {v}: normal equations {residual}"
            );
            if let [(_, n, _)] = &sheets[..] {
                assert!(d.cross(n.normalize()).length() < 1e-12, "vertex {v} drifts");
            }
        }
    }
}
