//! Tests of [`super::detect`] and [`super::local_motion_is_safe`] against brute force.

use super::*;
use crate::front::predicates::tests::Rng;
use crate::mesh::fixtures::two_spheres;
use std::collections::BTreeSet;

/// All pairs, no broad phase.
fn brute_force(triangles: &[[u32; 3]], x0: &[DVec3], x1: &[DVec3]) -> BTreeSet<Contact> {
    let mut out = BTreeSet::new();
    let (edges, _) = edges_of(triangles);
    for v in 0..x0.len() as u32 {
        for (t, tri) in triangles.iter().enumerate() {
            if !tri.contains(&v) && vertex_triangle_moves_into(v, tri, x0, x1) {
                out.insert(Contact::VertexTriangle {
                    vertex: v,
                    triangle: t as u32,
                });
            }
        }
    }
    for (i, a) in edges.iter().enumerate() {
        for b in &edges[i + 1..] {
            if !shares_vertex(a, b) && edge_edge_moves_into(a, b, x0, x1) {
                out.insert(Contact::EdgeEdge { a: *a, b: *b });
            }
        }
    }
    out
}

#[test]
fn detect_matches_brute_force_and_is_sorted() {
    let m = two_spheres(0.02, 2);
    let x0 = m.vertices.clone();
    let n = x0.len();
    let mut rng = Rng(21);
    // The left sphere moves right into the right one, with some jitter everywhere.
    let x1: Vec<DVec3> = (0..n)
        .map(|i| {
            let push = if x0[i].x < 0.0 {
                DVec3::new(0.08, 0.0, 0.0)
            } else {
                DVec3::ZERO
            };
            x0[i] + push + 0.003 * rng.v()
        })
        .collect();
    let found = detect(&m.triangles, &x0, &x1);
    let mut sorted = found.clone();
    sorted.sort();
    assert_eq!(found, sorted);
    let expected = brute_force(&m.triangles, &x0, &x1);
    assert!(!expected.is_empty());
    assert_eq!(found.iter().copied().collect::<BTreeSet<_>>(), expected);
    // Removed slots (connectivity::DEAD) anywhere in the list are ignored.
    let mut holes = m.triangles.clone();
    holes.push(crate::front::connectivity::DEAD);
    assert_eq!(detect(&holes, &x0, &x1), found);
    // Static and a tiny motion: nothing.
    assert!(detect(&m.triangles, &x0, &x0).is_empty());
    let small: Vec<DVec3> = x0.iter().map(|&p| p + 1e-4 * rng.v()).collect();
    assert!(detect(&m.triangles, &x0, &small).is_empty());
}

#[test]
fn detect_is_identical_on_one_and_two_threads() {
    let m = two_spheres(0.01, 2);
    let x0 = m.vertices.clone();
    let mut rng = Rng(4);
    let x1: Vec<DVec3> = x0.iter().map(|&p| p + 0.06 * rng.v()).collect();
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| detect(&m.triangles, &x0, &x1))
    };
    let one = run(1);
    assert!(!one.is_empty());
    assert_eq!(one, run(2));
}

#[test]
fn local_motion_agrees_with_full_detection() {
    let m = two_spheres(0.01, 2);
    let x0 = m.vertices.clone();
    let mut grid = TriangleGrid::new(0.1);
    for (t, tri) in m.triangles.iter().enumerate() {
        let (lo, hi) = swept_triangle_box(tri, &x0, &x0);
        grid.insert(t as u32, lo, hi);
    }
    let mut rng = Rng(8);
    let (mut safe, mut unsafe_) = (0, 0);
    for _ in 0..300 {
        // Move one or two random vertices by up to 0.2 (three edge lengths): often into the other sphere or
        // through a neighbouring face, often harmlessly.
        let k = 1 + (rng.next_u64() % 2) as usize;
        let moving: Vec<u32> = (0..k)
            .map(|_| (rng.next_u64() % x0.len() as u64) as u32)
            .collect();
        let mut x1 = x0.clone();
        for &v in &moving {
            x1[v as usize] += 0.2 * rng.v();
        }
        let expected = detect(&m.triangles, &x0, &x1).is_empty();
        assert_eq!(
            local_motion_is_safe(&grid, &m.triangles, &x0, &x1, &moving),
            expected
        );
        if expected {
            safe += 1
        } else {
            unsafe_ += 1
        }
    }
    assert!(safe > 20 && unsafe_ > 20, "{safe} {unsafe_}");
}

#[test]
fn detect_changed_finds_every_contact_of_changed_vertices() {
    let m = two_spheres(0.02, 2);
    let x0 = m.vertices.clone();
    let mut rng = Rng(8);
    let x1: Vec<DVec3> = x0
        .iter()
        .map(|&p| p + DVec3::new(if p.x < 0.0 { 0.05 } else { 0.0 }, 0.0, 0.0) + 0.003 * rng.v())
        .collect();
    // Change the end positions of every third vertex of the left sphere.
    let mut x2 = x1.clone();
    let mut changed = vec![false; x0.len()];
    for i in (0..x0.len()).step_by(3).filter(|&i| x0[i].x < 0.0) {
        x2[i] += DVec3::new(0.04, 0.0, 0.0);
        changed[i] = true;
    }
    let detector = Detector::new(&m.triangles, x0.len());
    let full = detector.detect(&x0, &x2);
    let touched = |c: &Contact| {
        let ids = match *c {
            Contact::VertexTriangle { vertex, triangle } => {
                let [a, b, c] = m.triangles[triangle as usize];
                [vertex, a, b, c]
            }
            Contact::EdgeEdge { a, b } => [a[0], a[1], b[0], b[1]],
        };
        ids.iter().any(|&v| changed[v as usize])
    };
    // Every contact with a changed vertex is found again; whatever else comes back (pairs
    // of untouched primitives on touched triangles) is a real contact too.
    let expected: BTreeSet<Contact> = full.iter().copied().filter(|c| touched(c)).collect();
    assert!(!expected.is_empty());
    let found: BTreeSet<Contact> = detector
        .detect_changed(&x0, &x2, &changed)
        .into_iter()
        .collect();
    let all: BTreeSet<Contact> = full.into_iter().collect();
    assert!(expected.is_subset(&found) && found.is_subset(&all));
    // Nothing flagged: nothing to re-test.
    assert!(detector
        .detect_changed(&x0, &x2, &vec![false; x0.len()])
        .is_empty());
}
