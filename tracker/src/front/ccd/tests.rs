//! CCD tests: degenerate configurations, constructed exact contacts, and random trajectories
//! against an exact substepped oracle (contacts) and a Lipschitz certificate (misses).

use super::*;
use crate::front::predicates::tests::Rng;
use crate::front::predicates::{point_in_triangle, segments_intersect};
use crate::front::response::proximity::{point_triangle_distance, segment_segment_distance};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// Unit right triangle in z = 0, static.
fn tri() -> [DVec3; 3] {
    [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
}

fn vt(p0: DVec3, p1: DVec3) -> bool {
    let [a, b, c] = tri();
    vertex_triangle(&[p0, a, b, c], &[p1, a, b, c])
}

#[test]
fn vertex_triangle_degenerate_cases() {
    // Crossing the interior, ending exactly on the face, starting exactly on it.
    assert!(vt(v(0.2, 0.2, 1.0), v(0.2, 0.2, -1.0)));
    assert!(vt(v(0.2, 0.2, 1.0), v(0.2, 0.2, 0.0)));
    assert!(vt(v(0.2, 0.2, 0.0), v(0.2, 0.2, 1.0)));
    // Exactly through the hypotenuse and through a vertex.
    assert!(vt(v(0.5, 0.5, 1.0), v(0.5, 0.5, -1.0)));
    assert!(vt(v(1.0, 0.0, 1.0), v(1.0, 0.0, -1.0)));
    // Misses by 1e-4 (about thirty times the near-miss tolerance √3 δ, δ = 1e-6 × extent 2): stopping above the face,
    // passing beside the hypotenuse; the same hair on the other side is a hit.
    assert!(!vt(v(0.2, 0.2, 1.0), v(0.2, 0.2, 1e-4)));
    assert!(vt(v(0.2, 0.2, 1.0), v(0.2, 0.2, -1e-4)));
    assert!(!vt(v(0.5 + 1e-4, 0.5, 1.0), v(0.5 + 1e-4, 0.5, -1.0)));
    assert!(vt(v(0.5 - 1e-4, 0.5, 1.0), v(0.5 - 1e-4, 0.5, -1.0)));
    // Coplanar motion: entering the triangle within its plane, and sliding past it.
    assert!(vt(v(-1.0, 0.2, 0.0), v(0.1, 0.2, 0.0)));
    assert!(!vt(v(-1.0, -1e-4, 0.0), v(2.0, -1e-4, 0.0)));
    // The triangle sweeps over a static vertex.
    let [a, b, c] = tri();
    let up = v(0.0, 0.0, 2.0);
    let p = v(0.25, 0.25, 1.0);
    assert!(vertex_triangle(&[p, a, b, c], &[p, a + up, b + up, c + up]));
    // A degenerate (zero-area) triangle swept through the vertex.
    let (d, e) = (v(-1.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
    let w = v(0.0, 0.5, 2.0);
    assert!(vertex_triangle(&[p, d, e, e], &[p, d + w, e + w, e + w]));
}

fn ee(a0: [DVec3; 2], b0: [DVec3; 2], b1: [DVec3; 2]) -> bool {
    edge_edge(&[a0[0], a0[1], b0[0], b0[1]], &[a0[0], a0[1], b1[0], b1[1]])
}

#[test]
fn edge_edge_degenerate_cases() {
    let a = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
    let lift = |s: [DVec3; 2], z: f64| s.map(|p| p + v(0.0, 0.0, z));
    // Crossing edges; touching at t = 1; touching at t = 0.
    let cross = [v(0.5, -1.0, 1.0), v(0.5, 1.0, 1.0)];
    assert!(ee(a, cross, lift(cross, -2.0)));
    assert!(ee(a, cross, lift(cross, -1.0)));
    assert!(ee(a, lift(cross, -1.0), cross));
    // Stopping 1e-4 short, and 1e-4 beyond.
    assert!(!ee(a, cross, lift(cross, -1.0 + 1e-4)));
    assert!(ee(a, cross, lift(cross, -1.0 - 1e-4)));
    // Parallel edges coming down onto the x axis: overlapping, end-to-end touching, disjoint.
    let par = |x0: f64, x1: f64| [v(x0, 0.0, 1.0), v(x1, 0.0, 1.0)];
    assert!(ee(a, par(0.5, 2.0), lift(par(0.5, 2.0), -1.0)));
    assert!(ee(a, par(1.0, 2.0), lift(par(1.0, 2.0), -1.0)));
    assert!(!ee(
        a,
        par(1.0 + 1e-4, 2.0),
        lift(par(1.0 + 1e-4, 2.0), -1.0)
    ));
    // Coplanar parallel sliding at a hair's distance, and sliding into collinear overlap.
    let side = |y: f64| [v(-1.0, y, 0.0), v(0.0, y, 0.0)];
    assert!(!ee(a, side(1.0), side(1e-4).map(|p| p + v(1.5, 0.0, 0.0))));
    assert!(ee(a, side(1.0), side(0.0).map(|p| p + v(1.5, 0.0, 0.0))));
    // Passing beside the end of the edge.
    let beside = [v(1.0 + 1e-4, -1.0, 1.0), v(1.0 + 1e-4, 1.0, 1.0)];
    assert!(!ee(a, beside, lift(beside, -2.0)));
}

/// Random dyadic coordinate `k / 1024`, `|k| ≤ 1024`: sums and halvings stay exact.
fn dyadic(rng: &mut Rng) -> DVec3 {
    let k = |rng: &mut Rng| (rng.next_u64() % 2049) as f64 - 1024.0;
    v(k(rng), k(rng), k(rng)) / 1024.0
}

#[test]
fn constructed_exact_contacts_are_found() {
    let mut rng = Rng(11);
    for _ in 0..500 {
        // Vertex–triangle contact exactly at t = 1/2 at barycentric (1/4, 1/4, 1/2).
        let t0: [DVec3; 3] = std::array::from_fn(|_| dyadic(&mut rng));
        let t1: [DVec3; 3] = std::array::from_fn(|_| dyadic(&mut rng));
        let h: [DVec3; 3] = std::array::from_fn(|i| 0.5 * (t0[i] + t1[i]));
        let q = 0.25 * h[0] + 0.25 * h[1] + 0.5 * h[2];
        let p0 = dyadic(&mut rng);
        let p1 = 2.0 * q - p0;
        assert!(vertex_triangle(
            &[p0, t0[0], t0[1], t0[2]],
            &[p1, t1[0], t1[1], t1[2]]
        ));
        // The same vertex arriving exactly on the end triangle.
        let e = 0.5 * t1[0] + 0.25 * t1[1] + 0.25 * t1[2];
        assert!(vertex_triangle(
            &[p0, t0[0], t0[1], t0[2]],
            &[e, t1[0], t1[1], t1[2]]
        ));
        // Edge–edge contact at t = 1/2: edge a's point at 1/4 meets edge b's midpoint.
        let a0: [DVec3; 2] = std::array::from_fn(|_| dyadic(&mut rng));
        let a1: [DVec3; 2] = std::array::from_fn(|_| dyadic(&mut rng));
        let qa = 0.75 * (0.5 * (a0[0] + a1[0])) + 0.25 * (0.5 * (a0[1] + a1[1]));
        let bh0 = dyadic(&mut rng);
        let bh1 = 2.0 * qa - bh0;
        let (b00, b10) = (dyadic(&mut rng), dyadic(&mut rng));
        let (b01, b11) = (2.0 * bh0 - b00, 2.0 * bh1 - b10);
        assert!(edge_edge(
            &[a0[0], a0[1], b00, b10],
            &[a1[0], a1[1], b01, b11]
        ));
    }
}

/// Random trajectories on a coarse integer lattice (so that exact contacts at rational times are
/// common): whenever the exact static predicates find a contact at one of the times `i / N`
/// (positions scaled by `N` are integers, hence exact), CCD must report one.
#[test]
fn lattice_trajectories_never_miss_substep_contacts() {
    const N: i64 = 6;
    let mut rng = Rng(5);
    let lattice = |rng: &mut Rng| {
        let k = |rng: &mut Rng| (rng.next_u64() % 5) as f64 - 2.0;
        v(k(rng), k(rng), k(rng))
    };
    let (mut vt_hits, mut ee_hits) = (0, 0);
    for _ in 0..20_000 {
        let x0: [DVec3; 4] = std::array::from_fn(|_| lattice(&mut rng));
        let x1: [DVec3; 4] = std::array::from_fn(|_| lattice(&mut rng));
        let at = |i: i64| -> [DVec3; 4] {
            std::array::from_fn(|k| N as f64 * x0[k] + i as f64 * (x1[k] - x0[k]))
        };
        let vt_oracle = (0..=N).any(|i| {
            let p = at(i);
            point_in_triangle(p[0], p[1], p[2], p[3])
        });
        let ee_oracle = (0..=N).any(|i| {
            let p = at(i);
            segments_intersect(p[0], p[1], p[2], p[3])
        });
        if vt_oracle {
            vt_hits += 1;
            assert!(vertex_triangle(&x0, &x1), "missed {x0:?} -> {x1:?}");
        }
        if ee_oracle {
            ee_hits += 1;
            assert!(edge_edge(&x0, &x1), "missed {x0:?} -> {x1:?}");
        }
    }
    // Enough contacts that the assertions above were exercised.
    assert!(vt_hits > 500 && ee_hits > 500, "{vt_hits} {ee_hits}");
}

/// Random floating-point trajectories: where fine sampling certifies a miss (the distance at
/// every sample exceeds what the relative motion can close in half a sample interval, plus a
/// margin far above rounding and the near-miss tolerance), CCD must report none.
#[test]
fn certified_misses_are_not_reported() {
    const S: usize = 64;
    let mut rng = Rng(9);
    let (mut vt_checked, mut ee_checked) = (0, 0);
    for _ in 0..4000 {
        let x0: [DVec3; 4] = std::array::from_fn(|_| rng.v());
        let x1: [DVec3; 4] = std::array::from_fn(|i| x0[i] + 0.6 * rng.v());
        let d: [DVec3; 4] = std::array::from_fn(|i| x1[i] - x0[i]);
        let at = |s: usize| -> [DVec3; 4] {
            let t = s as f64 / S as f64;
            std::array::from_fn(|i| x0[i] + t * d[i])
        };
        // Lipschitz constants of the distance in t: the largest relative speed of two points
        // of the pair, which bounds the speed of any convex combination.
        let lip_vt = (1..4).map(|i| (d[0] - d[i]).length()).fold(0.0, f64::max);
        let lip_ee = [(0, 2), (0, 3), (1, 2), (1, 3)]
            .iter()
            .map(|&(i, j)| (d[i] - d[j]).length())
            .fold(0.0, f64::max);
        let min_vt = (0..=S)
            .map(|s| {
                let p = at(s);
                point_triangle_distance(p[0], p[1], p[2], p[3])
            })
            .fold(f64::INFINITY, f64::min);
        let min_ee = (0..=S)
            .map(|s| {
                let p = at(s);
                segment_segment_distance(p[0], p[1], p[2], p[3])
            })
            .fold(f64::INFINITY, f64::min);
        // 1e-5: above the near-miss tolerance (√3 δ with δ = 1e-6 × extent ≤ 3e-6) and far
        // above the float error of the distances (~1e-15).
        if min_vt > lip_vt * 0.5 / S as f64 + 1e-5 {
            vt_checked += 1;
            assert!(!vertex_triangle(&x0, &x1));
        }
        if min_ee > lip_ee * 0.5 / S as f64 + 1e-5 {
            ee_checked += 1;
            assert!(!edge_edge(&x0, &x1));
        }
    }
    assert!(
        vt_checked > 1000 && ee_checked > 1000,
        "{vt_checked} {ee_checked}"
    );
}

#[test]
fn hit_locates_the_contact() {
    // Vertex falling from z = 1 to z = -1 through the face: contact at t = 1/2.
    let [a, b, c] = tri();
    let hit = vertex_triangle_hit(&[v(0.2, 0.2, 1.0), a, b, c], &[v(0.2, 0.2, -1.0), a, b, c])
        .expect("contact");
    // Bisection stops once F varies by at most δ = 2e-6 over the box, and F moves at speed 2
    // in t and 1 in u, v: the accepted box lies within a few δ of the contact.
    assert!(hit.t <= 0.5 && hit.t > 0.5 - 1e-4, "{hit:?}");
    assert!(
        (hit.u - 0.2).abs() < 1e-4 && (hit.v - 0.2).abs() < 1e-4,
        "{hit:?}"
    );
}

/// The closest-point direction only ever settles pairs the search would settle too (its
/// doc's argument), on pairs that move nearly together as neighbours on a moving surface do:
/// a common translation, small relative motions, many within the near-miss range or touching.
#[test]
fn closest_point_separation_never_contradicts_the_search() {
    let mut rng = Rng(21);
    let (mut settled, mut contacts) = (0, 0);
    for i in 0..20000 {
        let common = 0.5 * rng.v();
        // Relative motions from large down to a thousandth of the primitives' size.
        let relative = [0.5, 0.05, 1e-3][i % 3];
        let mut x0: [DVec3; 4] = std::array::from_fn(|_| rng.v());
        if i % 2 == 0 {
            // Nearly coplanar, as neighbours on a smooth surface.
            for p in &mut x0 {
                p.z *= 1e-3;
            }
        }
        let x1: [DVec3; 4] = std::array::from_fn(|k| x0[k] + common + relative * rng.v());
        for kind in [Kind::VertexTriangle, Kind::EdgeEdge] {
            let found = search(kind, &x0, &x1).is_some();
            contacts += found as usize;
            if separated_by_closest_points(kind, &x0, &x1) {
                settled += 1;
                assert!(!found, "{x0:?} -> {x1:?}");
            }
        }
    }
    // Both verdicts were exercised.
    assert!(settled > 10000 && contacts > 1000, "{settled} {contacts}");
}
