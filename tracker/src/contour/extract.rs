//! Contouring the MD tree (paper 004 §5, §6.3): stencils on the interface cells, boundary
//! closure, shared vertices, and the final labelled mesh.
//!
//! Determinism: polygons are generated per interface cell in sorted cell order (then the
//! closure in cell order), vertex keys are sorted and deduplicated before any position is
//! computed, and each position is a function of its key alone (nodes in sorted order; a triple
//! point's also of its face's edge crossings, themselves functions of their keys), so vertex
//! ids, positions and triangle order do not depend on the thread count.

use glam::DVec3;
use polyphase_grid::PhaseId;
use rayon::iter::Either;
use rayon::prelude::*;

use super::bisect::{clamp_to_triangle, edge_crossing, junction, triple_point};
use super::sampler::PhaseSampler;
use super::stencils::{corner_offset, Poly, Simplex, VKey, KUHN};
use super::tree::MdTree;
use super::triple_choice::{settle, TriplePoints};
use super::untangle::take_back_tangles;
use crate::mesh::LabeledMesh;

/// The polygons' distinct vertex keys, sorted: lattice nodes (the closure's, most of a
/// slab's keys) sorted as plain ids, which is cheaper than sorting them among the others.
struct VertexKeys {
    nodes: Vec<u64>,
    others: Vec<VKey>,
    /// `nodes` as keys, then `others`: the sorted order, as `Node` is `VKey`'s first variant.
    all: Vec<VKey>,
}

impl VertexKeys {
    fn of(polys: &[Poly]) -> VertexKeys {
        let (mut nodes, mut others): (Vec<u64>, Vec<VKey>) = polys
            .par_iter()
            .flat_map_iter(|p| p.verts.into_iter().take(p.len as usize))
            .partition_map(|k| match k {
                VKey::Node(n) => Either::Left(n),
                k => Either::Right(k),
            });
        nodes.par_sort_unstable();
        nodes.dedup();
        others.par_sort_unstable();
        others.dedup();
        let all = nodes
            .iter()
            .map(|&n| VKey::Node(n))
            .chain(others.iter().copied())
            .collect();
        VertexKeys { nodes, others, all }
    }
}

impl MdTree {
    /// Multiphase marching tetrahedra with bisection on exact φ, χ, watertight, closed at the
    /// domain boundary (boundary faces are labelled `[OUTSIDE, phase]` and face outward).
    pub fn contour(&self, sampler: &dyn PhaseSampler) -> LabeledMesh {
        self.contour_with(sampler, TriplePoints::Sampled)
    }

    /// [`MdTree::contour`], with the triple points of faces whose crossing collapsed onto a
    /// node placed as `triples` says.
    pub fn contour_with(&self, sampler: &dyn PhaseSampler, triples: TriplePoints) -> LabeledMesh {
        let mut polys: Vec<Poly> = self
            .interface
            .par_iter()
            .flat_map_iter(|&c| self.cell_polys(c))
            .collect();
        self.closure_polys(&mut polys);
        let VertexKeys {
            nodes: node_keys,
            others: other_keys,
            all: keys,
        } = VertexKeys::of(&polys);
        // Triple points wait for the edge crossings: each is then kept inside the triangle of
        // its face's three crossings (paper 004 §5.2 finds it from them; Fig. 5's stencils
        // assume it there). A junction whose three angles are all below 180° (a 120° Y) lies
        // inside anyway; where one phase spans 180° or more (a smooth surface cut by a plane:
        // `enright`'s sphere and wedges) our line intersection puts it on or beyond a side, the
        // sheets from the triple line to the crossings then cross, the phase regions around it
        // fold inside out, and the query reads the wrong phase off them up to the far field
        // (`enright` 64³: 12 of 376 triple-line edges at the start, a third of one liquid
        // detached by t = T). Kept inside, none folds (`triple_lines_do_not_fold`); the cost is
        // at most 7 more wrong points per million in the first step's indicator (Table 2).
        // Where a crossing has collapsed onto a node (an interface through a lattice node),
        // `triple_choice` may place the point elsewhere in the face, and `untangle` takes it
        // back wherever that tangles the mesh.
        let mut vertices: Vec<DVec3> = keys
            .par_iter()
            .map(|&k| match k {
                VKey::Face(..) => DVec3::ZERO,
                _ => self.vertex_position(k, sampler),
            })
            .collect();
        let index = |k: &VKey| match k {
            VKey::Node(n) => node_keys.binary_search(n).ok(),
            _ => other_keys
                .binary_search(k)
                .ok()
                .map(|i| node_keys.len() + i),
        };
        let crossing = |a: u64, b: u64| index(&VKey::Edge(a, b)).map(|i| vertices[i]);
        let triple_points: Vec<(usize, DVec3, Option<DVec3>)> = keys
            .par_iter()
            .enumerate()
            .filter_map(|(i, &k)| {
                let VKey::Face(a, b, c) = k else {
                    return None;
                };
                let x = self.vertex_position(k, sampler);
                // A face with three phases has a crossing on each edge; should one be missing,
                // the triple point stays where the search put it.
                Some(match (crossing(b, c), crossing(a, c), crossing(a, b)) {
                    (Some(p), Some(q), Some(r)) if triples == TriplePoints::Searched => {
                        (i, clamp_to_triangle(x, [p, q, r]), None)
                    }
                    (Some(p), Some(q), Some(r)) => {
                        let corners = [a, b, c].map(|n| self.lattice.pos(n));
                        let phases = [a, b, c].map(|n| self.nodes.value(n).unwrap_or((0.0, 0)).1);
                        let (t, inside) =
                            settle(sampler, corners, phases, [p, q, r], x, self.lattice.h);
                        (i, t, inside)
                    }
                    _ => (i, x, None),
                })
            })
            .collect();
        let mut moved: Vec<(u32, DVec3)> = Vec::new();
        for (i, x, inside) in triple_points {
            vertices[i] = x;
            if let Some(inside) = inside {
                moved.push((i as u32, inside));
            }
        }
        let id = |k: &VKey| index(k).map_or(0, |i| i as u32);
        let tris: Vec<([u32; 3], [PhaseId; 2])> = polys
            .par_iter()
            .flat_map_iter(|p| {
                let v = p.verts.map(|k| id(&k));
                let mut out = Vec::with_capacity(2);
                if p.len == 3 {
                    out.push(([v[0], v[1], v[2]], p.labels));
                } else {
                    let pos = v.map(|i| vertices[i as usize]);
                    let along_02 = p.fixed_diagonal
                        || pos[0].distance_squared(pos[2]) <= pos[1].distance_squared(pos[3]);
                    if along_02 {
                        out.push(([v[0], v[1], v[2]], p.labels));
                        out.push(([v[0], v[2], v[3]], p.labels));
                    } else {
                        out.push(([v[0], v[1], v[3]], p.labels));
                        out.push(([v[1], v[2], v[3]], p.labels));
                    }
                }
                out
            })
            .collect();
        let (triangles, labels) = tris.into_iter().unzip();
        let mut mesh = LabeledMesh {
            vertices,
            triangles,
            labels,
        };
        take_back_tangles(&mut mesh, &moved);
        mesh
    }

    /// Stencil polygons of interface cell `c`: its 6 tets, and its tet faces on the boundary.
    fn cell_polys(&self, c: u32) -> Vec<Poly> {
        let lat = self.lattice;
        let cell = self.cells[c as usize];
        let nodes: [u64; 8] = std::array::from_fn(|k| lat.id(cell.corner(k)));
        let labels = cell.slots.map(|s| self.nodes.chi[s as usize]);
        let mut out = Vec::new();
        for (t, tet) in KUHN.iter().enumerate() {
            Simplex {
                nodes: tet.map(|k| nodes[k]),
                local: tet.map(corner_offset),
                labels: tet.map(|k| labels[k]),
                tet_key: VKey::Tet(c, t as u8),
            }
            .tet_stencil(&mut out);
        }
        for axis in 0..3 {
            for side in 0..2u64 {
                if cell.min[axis] + side != side * lat.dims[axis] {
                    continue;
                }
                let (u, v) = (1 << ((axis + 1) % 3), 1 << ((axis + 2) % 3));
                let lo = (side as usize) << axis;
                let mut outward = DVec3::ZERO;
                outward[axis] = if side == 0 { -1.0 } else { 1.0 };
                for mid in [lo | u, lo | v] {
                    let face = [lo, mid, lo | u | v, lo];
                    Simplex {
                        nodes: face.map(|k| nodes[k]),
                        local: face.map(corner_offset),
                        labels: face.map(|k| labels[k]),
                        tet_key: VKey::Tet(c, 0),
                    }
                    .boundary_face(outward, &mut out);
                }
            }
        }
        out
    }

    /// The position of a vertex key (computed once per key, from the key alone).
    fn vertex_position(&self, k: VKey, sampler: &dyn PhaseSampler) -> DVec3 {
        let lat = &self.lattice;
        let val = |n: u64| self.nodes.value(n).unwrap_or((0.0, 0));
        match k {
            VKey::Node(n) => lat.pos(n),
            VKey::Edge(a, b) => {
                edge_crossing(sampler, lat.pos(a), lat.pos(b), val(a), val(b), lat.h)
            }
            VKey::Face(a, b, c) => triple_point(
                sampler,
                [a, b, c].map(|n| lat.pos(n)),
                [a, b, c].map(val),
                lat.h,
            ),
            VKey::Tet(c, t) => {
                let cell = self.cells[c as usize];
                let ids = KUHN[t as usize].map(|k| lat.id(cell.corner(k)));
                junction(sampler, ids.map(|n| lat.pos(n)), ids.map(val), lat.h)
            }
            VKey::Centre(c, f) => self.face_centre(c, f),
        }
    }
}
