//! Edge → triangles and vertex → per-phase pseudonormal tables for the indicator query
//! (paper 004 §4.1), in compressed-sparse-row layout built by sorting (deterministic).

use glam::DVec3;
use polyphase_grid::PhaseId;
use rayon::prelude::*;

/// Undirected edges of the triangles, with the triangles around each.
#[derive(Clone, Debug, Default)]
pub(crate) struct Edges {
    /// `tri_edges[t][k]`: edge id of edge `k` (corner `k` → corner `(k + 1) % 3`) of triangle `t`.
    pub(crate) tri_edges: Vec<[u32; 3]>,
    /// Triangles of edge `e`: `tris[offsets[e] .. offsets[e + 1]]`, ascending.
    pub(crate) offsets: Vec<u32>,
    pub(crate) tris: Vec<u32>,
}

impl Edges {
    /// Builds the table by sorting `(min vertex, max vertex, triangle)` records.
    pub(crate) fn build(triangles: &[[u32; 3]]) -> Edges {
        let mut records: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(triangles.len() * 3);
        for (t, tri) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (u, v) = (tri[k], tri[(k + 1) % 3]);
                records.push((u.min(v), u.max(v), t as u32, k as u8));
            }
        }
        // Keys are unique (triangle and corner included): the order is thread-independent.
        records.par_sort_unstable();
        let mut edges = Edges {
            tri_edges: vec![[0; 3]; triangles.len()],
            offsets: Vec::with_capacity(records.len() / 2 + 1),
            tris: Vec::with_capacity(records.len()),
        };
        for (i, r) in records.iter().enumerate() {
            if i == 0 || (records[i - 1].0, records[i - 1].1) != (r.0, r.1) {
                edges.offsets.push(edges.tris.len() as u32);
            }
            edges.tri_edges[r.2 as usize][r.3 as usize] = edges.offsets.len() as u32 - 1;
            edges.tris.push(r.2);
        }
        edges.offsets.push(edges.tris.len() as u32);
        edges
    }

    /// Triangles sharing edge `e`, ascending.
    #[inline]
    pub(crate) fn triangles(&self, e: u32) -> &[u32] {
        let e = e as usize;
        &self.tris[self.offsets[e] as usize..self.offsets[e + 1] as usize]
    }
}

/// The triangle corners at each vertex (corner `c = 3 t + k`: corner `k` of triangle `t`), in
/// compressed-sparse-row layout, ascending.
#[derive(Clone, Debug, Default)]
pub(crate) struct VertexCorners {
    offsets: Vec<u32>,
    corners: Vec<u32>,
}

impl VertexCorners {
    /// Buckets each corner under its vertex (counting sort: deterministic, O(N)).
    pub(crate) fn build(n_vertices: usize, triangles: &[[u32; 3]]) -> VertexCorners {
        let mut offsets = vec![0u32; n_vertices + 1];
        for tri in triangles {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..n_vertices {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut corners = vec![0u32; triangles.len() * 3];
        for (t, tri) in triangles.iter().enumerate() {
            for (k, &v) in tri.iter().enumerate() {
                corners[fill[v as usize] as usize] = (3 * t + k) as u32;
                fill[v as usize] += 1;
            }
        }
        VertexCorners { offsets, corners }
    }

    /// (triangle, corner index in it) of every corner at vertex `v`, by ascending triangle.
    #[inline]
    pub(crate) fn of(&self, v: u32) -> impl Iterator<Item = (usize, usize)> + '_ {
        let v = v as usize;
        self.corners[self.offsets[v] as usize..self.offsets[v + 1] as usize]
            .iter()
            .map(|&c| (c as usize / 3, c as usize % 3))
    }
}

/// Per vertex, one unit angle-weighted pseudonormal per incident phase, pointing out of that
/// phase (paper 004 §4.1, Fig. 3; Bærentzen & Aanæs): `N_p = Σ θ_t n_t` over the triangles
/// `t` at the vertex that carry `p`, with `n_t` flipped when `p` is `t`'s front label.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pseudonormals {
    /// Entries of vertex `v`: `entries[offsets[v] .. offsets[v + 1]]`, by ascending phase.
    offsets: Vec<u32>,
    entries: Vec<(PhaseId, DVec3)>,
}

impl Pseudonormals {
    /// Builds the table for every vertex of `around` from the triangles' corner positions,
    /// unit normals and `[front, back]` labels: each vertex sums its contributions in (phase,
    /// triangle) order, in parallel over vertices, so the result does not depend on the
    /// thread count.
    pub(crate) fn build(
        around: &VertexCorners,
        corners: &[[DVec3; 3]],
        normals: &[DVec3],
        labels: &[[PhaseId; 2]],
    ) -> Pseudonormals {
        let n_vertices = around.offsets.len() - 1;
        let per_vertex: Vec<Vec<(PhaseId, DVec3)>> = (0..n_vertices)
            .into_par_iter()
            .map(|v| {
                let mut contrib: Vec<(PhaseId, u32, DVec3)> = Vec::new();
                for (t, k) in around.of(v as u32) {
                    let p = &corners[t];
                    let e1 = p[(k + 1) % 3] - p[k];
                    let e2 = p[(k + 2) % 3] - p[k];
                    // atan2 of |cross| and dot: accurate for all angles, finite for zero edges.
                    let w = e1.cross(e2).length().atan2(e1.dot(e2)) * normals[t];
                    contrib.push((labels[t][1], t as u32, w));
                    contrib.push((labels[t][0], t as u32, -w));
                }
                contrib.sort_unstable_by_key(|&(phase, t, _)| (phase, t));
                let mut out: Vec<(PhaseId, DVec3)> = Vec::new();
                for (phase, _, w) in contrib {
                    match out.last_mut() {
                        Some((p, sum)) if *p == phase => *sum += w,
                        _ => out.push((phase, w)),
                    }
                }
                for (_, n) in &mut out {
                    *n = n.normalize_or_zero();
                }
                out
            })
            .collect();
        let mut table = Pseudonormals {
            offsets: Vec::with_capacity(n_vertices + 1),
            entries: Vec::with_capacity(corners.len() * 2),
        };
        for list in per_vertex {
            table.offsets.push(table.entries.len() as u32);
            table.entries.extend(list);
        }
        table.offsets.push(table.entries.len() as u32);
        table
    }

    /// `(phase, unit pseudonormal)` pairs of vertex `v`, by ascending phase.
    #[inline]
    pub(crate) fn of(&self, v: u32) -> &[(PhaseId, DVec3)] {
        let v = v as usize;
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}
