//! Response tests: colliding spheres end intersection-free, identical on 1 and 2 threads.

use super::*;
use crate::front::collision::detect;
use crate::front::intersection::self_intersections;
use crate::front::predicates::tests::Rng;
use crate::mesh::fixtures::two_spheres;
use crate::LabeledMesh;

/// Left sphere moves by `+d` in x, the right one by `-d`, plus jitter of size `jitter`.
fn driven(m: &LabeledMesh, d: f64, jitter: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = Rng(seed);
    m.vertices
        .iter()
        .map(|&p| p + DVec3::new(if p.x < 0.0 { d } else { -d }, 0.0, 0.0) + jitter * rng.v())
        .collect()
}

fn assert_clean(m: &LabeledMesh, x0: &[DVec3], x1: &[DVec3]) {
    assert!(detect(&m.triangles, x0, x1).is_empty());
    let end = LabeledMesh {
        vertices: x1.to_vec(),
        ..m.clone()
    };
    assert!(self_intersections(&end).is_empty());
}

#[test]
fn spheres_driven_into_each_other_end_intersection_free() {
    let mut m = two_spheres(0.02, 2);
    // A removed slot (connectivity::DEAD) must be ignored by resolve and the checker.
    m.triangles.push(crate::front::connectivity::DEAD);
    m.labels.push([0, 0]);
    let x0 = m.vertices.clone();
    // Head-on, 0.1 each: the spheres would overlap by 0.18 of their 0.5 diameters.
    let mut x1 = driven(&m, 0.1, 0.0, 1);
    assert!(!self_intersections(&LabeledMesh {
        vertices: x1.clone(),
        ..m.clone()
    })
    .is_empty());
    let stats = resolve(&m.triangles, &x0, &mut x1, &CollisionParams::default()).expect("resolved");
    assert!(stats.contacts > 0);
    assert_clean(&m, &x0, &x1);
    // With jitter (sliding, tangential motion) and a larger thickness.
    let params = CollisionParams {
        thickness: 0.005,
        ..CollisionParams::default()
    };
    let mut x1 = driven(&m, 0.1, 0.01, 2);
    resolve(&m.triangles, &x0, &mut x1, &params).expect("resolved");
    assert_clean(&m, &x0, &x1);
}

#[test]
fn tunnelling_motion_is_stopped() {
    // The left sphere jumps right past the right one: the end state alone would be clean.
    let m = two_spheres(0.02, 1);
    let x0 = m.vertices.clone();
    let mut x1: Vec<DVec3> = x0
        .iter()
        .map(|&p| {
            if p.x < 0.0 {
                p + DVec3::new(1.2, 0.0, 0.0)
            } else {
                p
            }
        })
        .collect();
    assert!(self_intersections(&LabeledMesh {
        vertices: x1.clone(),
        ..m.clone()
    })
    .is_empty());
    assert!(!detect(&m.triangles, &x0, &x1).is_empty());
    resolve(&m.triangles, &x0, &mut x1, &CollisionParams::default()).expect("resolved");
    assert_clean(&m, &x0, &x1);
}

#[test]
fn free_motion_is_untouched_and_bad_input_is_rejected() {
    let m = two_spheres(0.1, 2);
    let x0 = m.vertices.clone();
    let mut x1 = driven(&m, -0.01, 0.001, 3);
    let before = x1.clone();
    let stats = resolve(&m.triangles, &x0, &mut x1, &CollisionParams::default()).expect("free");
    assert_eq!(x1, before);
    assert_eq!(stats.contacts, 0);
    x1[5].y = f64::NAN;
    let err = resolve(&m.triangles, &x0, &mut x1, &CollisionParams::default()).unwrap_err();
    assert_eq!(err.cause, UnresolvedCause::NonFinite { vertex: 5 });
}

#[test]
fn resolution_is_identical_on_one_and_two_threads() {
    let m = two_spheres(0.02, 2);
    let x0 = m.vertices.clone();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                let mut x1 = driven(&m, 0.1, 0.01, 4);
                let stats = resolve(&m.triangles, &x0, &mut x1, &CollisionParams::default());
                (x1, stats)
            })
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert!(sa.is_ok());
    assert_eq!(sa, sb);
    assert!(a
        .iter()
        .zip(&b)
        .all(|(p, q)| p.to_array().map(f64::to_bits) == q.to_array().map(f64::to_bits)));
}

#[test]
fn proximity_repulsion_stops_approach_inside_the_thickness() {
    // Gap 0.002 inside the thickness 0.005; each sphere moves 0.0005 toward the other, which
    // would close the gap to 0.001 without any contact. Repulsion forbids approach for pairs
    // already closer than h / 2, so the closest vertex–triangle distance across the gap stays
    // near 0.002 (Gauss–Seidel over pairs sharing vertices leaves a small residual).
    let m = two_spheres(0.002, 2);
    let x0 = m.vertices.clone();
    let mut x1 = driven(&m, 0.0005, 0.0, 5);
    let params = CollisionParams {
        thickness: 0.005,
        ..CollisionParams::default()
    };
    let stats = resolve(&m.triangles, &x0, &mut x1, &params).expect("resolved");
    assert!(stats.proximity_pairs > 0);
    let half = m.triangles.len() / 2;
    let gap = |x: &[DVec3]| {
        let left = m.triangles[..half].iter().flatten().copied();
        left.map(|v| {
            m.triangles[half..]
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| x[i as usize]);
                    proximity::point_triangle_distance(x[v as usize], a, b, c)
                })
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
    };
    let (before, after) = (gap(&x0), gap(&x1));
    assert!((before - 0.002).abs() < 1e-9, "{before}");
    assert!(after > 0.0018, "{after}");
}

#[test]
fn pinned_coordinates_take_no_share_of_an_impulse() {
    let m = two_spheres(0.02, 2);
    let x0 = m.vertices.clone();
    // The right sphere's x coordinates are held (as a vertex sliding on a wall x = const).
    let pinned: Vec<[bool; 3]> = x0.iter().map(|p| [p.x > 0.0, false, false]).collect();
    let mut x1 = driven(&m, 0.1, 0.0, 1);
    let proposed = x1.clone();
    let stats = resolve_pinned(
        &m.triangles,
        &x0,
        &mut x1,
        &pinned,
        &CollisionParams::default(),
    )
    .expect("resolved");
    assert!(stats.contacts > 0);
    assert_clean(&m, &x0, &x1);
    for (v, p) in pinned.iter().enumerate() {
        if p[0] {
            assert_eq!(x1[v].x, proposed[v].x, "vertex {v}");
        }
    }
    // Unpinned, the same motion moves the right sphere's x too.
    let mut free = proposed.clone();
    resolve(&m.triangles, &x0, &mut free, &CollisionParams::default()).expect("resolved");
    assert!((0..free.len()).any(|v| pinned[v][0] && free[v].x != proposed[v].x));
}

#[test]
fn impact_zones_slide_along_pinned_coordinates_only_when_asked() {
    // Impact zones alone (no impulse sweeps): each zone moves by its members' mean motion. The
    // left sphere is driven into the right one, whose x is held where it is (as the tracker
    // holds a vertex on a wall); a zone spanning both then moves the held x, unless zones
    // slide.
    let m = two_spheres(0.02, 2);
    let x0 = m.vertices.clone();
    let pinned: Vec<[bool; 3]> = x0.iter().map(|p| [p.x > 0.0, false, false]).collect();
    let mut proposed = driven(&m, 0.1, 0.0, 1);
    for (p, (q, pin)) in proposed.iter_mut().zip(x0.iter().zip(&pinned)) {
        if pin[0] {
            p.x = q.x;
        }
    }
    let zones_only = CollisionParams {
        impulse_iterations: 0,
        ..CollisionParams::default()
    };
    let mut x1 = proposed.clone();
    let failed = resolve_pinned(&m.triangles, &x0, &mut x1, &pinned, &zones_only);
    assert!(
        matches!(
            failed,
            Err(Unresolved {
                cause: UnresolvedCause::PinnedMoved { .. }
            })
        ),
        "{failed:?}"
    );
    let sliding = CollisionParams {
        pinned_zones_slide: true,
        ..zones_only
    };
    let mut x1 = proposed.clone();
    let stats = resolve_pinned(&m.triangles, &x0, &mut x1, &pinned, &sliding).expect("resolved");
    assert!(stats.impact_zones > 0);
    assert_clean(&m, &x0, &x1);
    for (v, p) in pinned.iter().enumerate() {
        if p[0] {
            assert_eq!(x1[v].x, proposed[v].x, "vertex {v}");
        }
    }
}

#[test]
fn a_pair_held_within_the_near_miss_distance_does_not_fail_the_motion() {
    // The 256-region foam at t = 0.038: vertex 0 on the box edge x = y = 0 (held), 5e-10 from
    // the edge 2–3 of a wall triangle on y = 0 whose vertex 3 slides along z. The CCD reports
    // the pair as a near miss whatever the impulses do, and the impact zone that stops it
    // leaves it where it started; the rest of the mesh (triangle 6 7 8) must still move.
    let x0 = vec![
        DVec3::new(0.0, 0.0, 0.9014165969122023),
        DVec3::new(0.009233792638306924, 0.0, 0.957884231120184),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(7.312652915928558e-10, 0.0, 0.8547044261482681),
        DVec3::new(0.0, 0.03, 0.95),
        DVec3::new(0.0, 0.02, 0.88),
        DVec3::new(0.5, 0.5, 0.5),
        DVec3::new(0.6, 0.5, 0.5),
        DVec3::new(0.5, 0.6, 0.5),
    ];
    let triangles = vec![[1, 2, 3], [0, 4, 5], [6, 7, 8]];
    let pinned = vec![
        [true; 3],
        [false, true, false],
        [true; 3],
        [true, true, false],
        [true, false, false],
        [true, false, false],
        [false; 3],
        [false; 3],
        [false; 3],
    ];
    let mut x1 = x0.clone();
    x1[3].z += 1.8e-4;
    for p in &mut x1[6..] {
        *p += DVec3::splat(0.01);
    }
    let params = CollisionParams {
        pinned_zones_slide: true,
        ..CollisionParams::default()
    };
    let proposed = x1.clone();
    resolve_pinned(&triangles, &x0, &mut x1, &pinned, &params).expect("resolved");
    assert_eq!(&x1[6..], &proposed[6..]);
    assert!(detect(&triangles, &x0, &x1).is_empty());
}

#[test]
fn a_contact_within_a_wall_is_resolved_by_impulses_along_the_wall() {
    // Two triangles lying in the wall z = 0 (z held, as the tracker holds wall vertices), the
    // second sliding into the first across its long edge: the contact normal is the held z,
    // so an impulse along it moves nothing. With impact zones switched off the motion must
    // still resolve, by impulses within the wall.
    let x0 = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.6, 0.6, 0.0),
        DVec3::new(1.2, 0.6, 0.0),
        DVec3::new(0.6, 1.2, 0.0),
    ];
    let triangles = vec![[0, 1, 2], [3, 4, 5]];
    let pinned = vec![[false, false, true]; 6];
    let mut x1 = x0.clone();
    for p in &mut x1[3..] {
        *p -= DVec3::new(0.3, 0.3, 0.0);
    }
    let impulses_only = CollisionParams {
        zone_iterations: 0,
        ..CollisionParams::default()
    };
    let stats =
        resolve_pinned(&triangles, &x0, &mut x1, &pinned, &impulses_only).expect("resolved");
    assert!(stats.contacts > 0);
    assert!(detect(&triangles, &x0, &x1).is_empty());
    assert!(x1.iter().all(|p| p.z == 0.0));
}
