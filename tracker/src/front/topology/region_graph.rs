//! The region graph of a vertex (paper 000 §5.1.3, Fig. 8): one node per region (phase)
//! incident to the vertex, one arc per pair of regions that share a triangle incident to the
//! vertex. A vertex is regular (a film, a triple curve or a quadruple point, Fig. 6) exactly
//! when its graph is complete; each missing arc is a pair of regions touching at the vertex
//! without sharing an interface there, which vertex separation ([`super::separate`]) resolves.
//!
//! `OUTSIDE` is a node like any phase: the domain wall is a region a film can end on, so a film
//! meeting the wall (phases A, B and the wall, all pairwise incident) is regular, and two
//! bubbles touching each other only at a point of the wall show the missing arc between them
//! as they would anywhere else. Leaving the wall out would instead hide a bubble that touches
//! the wall at a single vertex (its arc to `OUTSIDE` is missing there).

use polyphase_grid::PhaseId;

use crate::front::connectivity::Connectivity;

/// The pairs `[a, b]` (`a < b`) of regions incident to vertex `v` that share no triangle
/// incident to `v`, sorted: the missing arcs of `v`'s region graph (§5.1.3). Empty for a
/// regular vertex and for a vertex without triangles.
pub fn missing_arcs(c: &Connectivity, v: u32) -> Vec<[PhaseId; 2]> {
    let nodes = c.vertex_regions(v);
    let mut arcs: Vec<[PhaseId; 2]> = c
        .vertex_triangles(v)
        .iter()
        .map(|&t| {
            let [f, b] = c.labels(t);
            [f.min(b), f.max(b)]
        })
        .collect();
    arcs.sort_unstable();
    arcs.dedup();
    let mut missing = Vec::new();
    for (i, &a) in nodes.iter().enumerate() {
        for &b in &nodes[i + 1..] {
            if arcs.binary_search(&[a, b]).is_err() {
                missing.push([a, b]);
            }
        }
    }
    missing
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use polyphase_grid::OUTSIDE;

    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh};
    use crate::mesh::LabeledMesh;

    /// The vertex of `c` at `p` (exact lattice coordinates).
    fn vertex_at(c: &Connectivity, p: DVec3) -> u32 {
        c.mesh
            .vertices
            .iter()
            .position(|q| (*q - p).length() < 1e-12)
            .expect("the lattice has a vertex there") as u32
    }

    #[test]
    fn films_triple_curves_and_quadruple_points_are_complete() {
        // Every vertex of a sphere separates the same two phases.
        let sphere = Connectivity::new(icosphere(DVec3::ZERO, 1.0, 1, 1, 0));
        for v in 0..sphere.mesh.vertices.len() as u32 {
            assert!(missing_arcs(&sphere, v).is_empty(), "sphere vertex {v}");
        }
        // Three slabs of a 2×2×2 lattice meeting along z = y = 1/2 ... phases by (i, j):
        // (0,0)→0, (1,0)→1, (·,1)→2 give a triple curve along x = 1/2, y = 1/2.
        let c = Connectivity::new(lattice_mesh(
            2,
            |i, j, _| if j == 1 { 2 } else { i as PhaseId },
        ));
        let v = vertex_at(&c, DVec3::new(0.5, 0.5, 0.5));
        assert_eq!(c.vertex_regions(v), vec![0, 1, 2]);
        assert!(missing_arcs(&c, v).is_empty());
        // Its end on the wall: three phases and the wall, all pairwise incident.
        let end = vertex_at(&c, DVec3::new(0.5, 0.5, 0.0));
        assert_eq!(c.vertex_regions(end), vec![0, 1, 2, OUTSIDE]);
        assert!(missing_arcs(&c, end).is_empty());
        // A quadruple point: octants (i, j, k) with k = 1 one phase, k = 0 split in three
        // as above: four phases, all six pairs share a wall at the centre.
        let c = Connectivity::new(lattice_mesh(2, |i, j, k| {
            if k == 1 {
                3
            } else if j == 1 {
                2
            } else {
                i as PhaseId
            }
        }));
        let v = vertex_at(&c, DVec3::splat(0.5));
        assert_eq!(c.vertex_regions(v), vec![0, 1, 2, 3]);
        assert!(missing_arcs(&c, v).is_empty());
    }

    #[test]
    fn regions_touching_at_a_vertex_or_across_a_quadruple_edge_miss_an_arc() {
        // Two tetrahedra of phases 1 and 2 in phase 0 sharing only their apex at the origin.
        let mut mesh = LabeledMesh {
            vertices: vec![
                DVec3::ZERO,
                DVec3::new(1.0, 0.0, 1.0),
                DVec3::new(-0.5, 0.8, 1.0),
                DVec3::new(-0.5, -0.8, 1.0),
                DVec3::new(1.0, 0.0, -1.0),
                DVec3::new(-0.5, 0.8, -1.0),
                DVec3::new(-0.5, -0.8, -1.0),
            ],
            ..LabeledMesh::default()
        };
        for (tet, phase, inner) in [([0, 1, 2, 3], 1, 0.5), ([0, 4, 5, 6], 2, -0.5)] {
            let centre = DVec3::new(0.0, 0.0, inner);
            for k in 0..4 {
                let mut f = [tet[k], tet[(k + 1) % 4], tet[(k + 2) % 4]];
                f.sort_unstable();
                crate::mesh::fixtures::push_oriented(&mut mesh, f, centre, 0, phase);
            }
        }
        crate::invariants::check(&mesh, 0.0).expect("two closed tetrahedra");
        let c = Connectivity::new(mesh);
        assert_eq!(missing_arcs(&c, 0), vec![[1, 2]]);
        assert!(missing_arcs(&c, 1).is_empty());
        // Four quarter-boxes around x = y = 1/2: diagonal quadrants share no wall.
        let c = Connectivity::new(lattice_mesh(2, |i, j, _| (i + 2 * j) as PhaseId));
        let v = vertex_at(&c, DVec3::splat(0.5));
        assert_eq!(missing_arcs(&c, v), vec![[0, 3], [1, 2]]);
    }
}
