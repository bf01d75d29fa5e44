//! Tests of the intersection checker on clean, touching and intersecting meshes.

use super::*;
use crate::front::predicates::tests::Rng;
use crate::mesh::fixtures::{icosphere, lattice_mesh};

fn mesh(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> LabeledMesh {
    let labels = vec![[0, 1]; triangles.len()];
    LabeledMesh {
        vertices,
        triangles,
        labels,
    }
}

#[test]
fn clean_meshes_have_no_intersections() {
    assert!(self_intersections(&icosphere(DVec3::ZERO, 1.0, 3, 1, 0)).is_empty());
    // Non-manifold: three phases meeting along lattice edges.
    let lattice = lattice_mesh(3, |i, j, k| ((i + 2 * j + k) % 3) as u16);
    assert!(self_intersections(&lattice).is_empty());
    // Nested spheres.
    let mut nested = icosphere(DVec3::ZERO, 1.0, 2, 1, 0);
    nested.append(&icosphere(DVec3::splat(0.01), 0.9, 2, 2, 1));
    assert!(self_intersections(&nested).is_empty());
}

#[test]
fn touching_and_overlapping_spheres_are_reported() {
    let a = icosphere(DVec3::ZERO, 1.0, 2, 1, 0);
    let mx = a.vertices.iter().map(|p| p.x).fold(f64::MIN, f64::max);
    let shifted = |dx: f64| {
        let mut m = a.clone();
        let mut b = a.clone();
        for p in &mut b.vertices {
            p.x += dx;
        }
        m.append(&b);
        m
    };
    // The icosphere is symmetric in x, so shifting by 2 mx makes its leftmost vertices land
    // exactly on the rightmost ones: touching counts. One ulp further apart is clean.
    assert!(!self_intersections(&shifted(2.0 * mx)).is_empty());
    assert!(self_intersections(&shifted((2.0 * mx).next_up())).is_empty());
    let deep = self_intersections(&shifted(1.0));
    assert!(deep.len() > 10);
    assert!(deep.windows(2).all(|w| w[0] < w[1]));
    assert!(deep.iter().all(|&(s, t)| s < t));
}

#[test]
fn adjacent_pairs_are_judged_beyond_their_shared_simplex() {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let base = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
    let with = |p: DVec3, tri: [u32; 3]| {
        let mut vs = base.clone();
        vs.push(p);
        self_intersections(&mesh(vs, vec![[0, 1, 2], tri]))
    };
    // Shared edge 0-1: folded flat onto the first triangle (same side) vs. opened flat
    // (opposite side) vs. bent out of the plane.
    assert_eq!(with(v(0.5, 0.5, 0.0), [1, 0, 3]), vec![(0, 1)]);
    assert!(with(v(0.5, -0.5, 0.0), [1, 0, 3]).is_empty());
    assert!(with(v(0.5, 0.5, 1e-300), [1, 0, 3]).is_empty());
    // Degenerate second triangle lying along the shared edge's line.
    assert!(with(v(2.0, 0.0, 0.0), [1, 0, 3]).is_empty());
    // Shared vertex 0: a triangle piercing the first, one only touching it at the vertex,
    // one whose edge lies on the first's edge.
    let mut vs = base.clone();
    vs.extend([v(0.2, 0.2, -1.0), v(0.3, 0.1, 1.0)]);
    assert_eq!(
        self_intersections(&mesh(vs.clone(), vec![[0, 1, 2], [0, 3, 4]])),
        vec![(0, 1)]
    );
    vs[3] = v(-1.0, -1.0, 1.0);
    vs[4] = v(-1.0, 0.0, 1.0);
    assert!(self_intersections(&mesh(vs.clone(), vec![[0, 1, 2], [0, 3, 4]])).is_empty());
    vs[3] = v(0.5, 0.0, 0.0);
    vs[4] = v(0.0, -1.0, 1.0);
    assert_eq!(
        self_intersections(&mesh(vs, vec![[0, 1, 2], [0, 3, 4]])),
        vec![(0, 1)]
    );
    // Duplicate triangle.
    assert_eq!(
        self_intersections(&mesh(base, vec![[0, 1, 2], [2, 1, 0]])),
        vec![(0, 1)]
    );
}

#[test]
fn matches_all_pairs_on_jittered_meshes_on_one_and_two_threads() {
    let mut rng = Rng(17);
    let mut m = icosphere(DVec3::ZERO, 1.0, 2, 1, 0);
    for p in &mut m.vertices {
        *p += 0.3 * rng.v();
    }
    let all: Vec<(u32, u32)> = (0..m.triangles.len() as u32)
        .flat_map(|s| ((s + 1)..m.triangles.len() as u32).map(move |t| (s, t)))
        .filter(|&(s, t)| pair_intersects(&m, s, t))
        .collect();
    assert!(!all.is_empty());
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| self_intersections(&m))
    };
    assert_eq!(run(1), all);
    assert_eq!(run(2), all);
}
