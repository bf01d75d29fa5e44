//! Edge → triangles and vertex → per-phase pseudonormal tables for the indicator query
//! (paper 004 §4.1), in compressed-sparse-row layout, built vertex by vertex in parallel
//! chunks and concatenated in vertex order (deterministic).

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

/// Vertices per parallel task when a table is built vertex by vertex: each task fills its own
/// buffers, concatenated in vertex order, so the result does not depend on the thread count.
const VERTEX_CHUNK: usize = 4096;

/// One chunk's part of a per-vertex table: how many entries each of its vertices has, and
/// the entries in vertex order.
type Chunk<T> = (Vec<u32>, Vec<T>);

/// The vertex ranges of [`VERTEX_CHUNK`] vertices each.
fn vertex_chunks(n_vertices: usize) -> impl IndexedParallelIterator<Item = std::ops::Range<usize>> {
    (0..n_vertices.div_ceil(VERTEX_CHUNK))
        .into_par_iter()
        .map(move |c| c * VERTEX_CHUNK..((c + 1) * VERTEX_CHUNK).min(n_vertices))
}

impl Edges {
    /// Builds the table from the corners at each vertex: edge `(u, v)`, `u < v`, is listed at
    /// `u`, so the edges come out ordered by `(u, v)` and each edge's triangles ascending, as a
    /// global sort of `(min vertex, max vertex, triangle)` records would give, at O(degree)
    /// work per vertex.
    pub(crate) fn build(around: &VertexCorners, triangles: &[[u32; 3]]) -> Edges {
        let n_vertices = around.offsets.len() - 1;
        // Per chunk: (other vertex, triangle, edge index in it) of each edge at its lower
        // vertex, sorted per vertex, and how many records each vertex has.
        let chunks: Vec<Chunk<(u32, u32, u8)>> = vertex_chunks(n_vertices)
            .map(|range| {
                let mut counts = Vec::with_capacity(range.len());
                let mut records = Vec::new();
                for u in range {
                    let start = records.len();
                    for (t, k) in around.of(u as u32) {
                        let tri = triangles[t];
                        // Edge k runs corner k → k + 1, edge k + 2 runs corner k + 2 → k. A
                        // degenerate triangle's edge from u to u is listed once, as edge k.
                        for (v, edge) in [(tri[(k + 1) % 3], k), (tri[(k + 2) % 3], (k + 2) % 3)] {
                            if v as usize > u || (v as usize == u && edge == k) {
                                records.push((v, t as u32, edge as u8));
                            }
                        }
                    }
                    records[start..].sort_unstable();
                    counts.push((records.len() - start) as u32);
                }
                (counts, records)
            })
            .collect();
        let total: usize = chunks.iter().map(|(_, r)| r.len()).sum();
        let mut edges = Edges {
            tri_edges: vec![[0; 3]; triangles.len()],
            offsets: Vec::with_capacity(total / 2 + 1),
            tris: Vec::with_capacity(total),
        };
        for (counts, records) in &chunks {
            let mut at = 0;
            for &n in counts {
                // One lower vertex's records, sorted: a new edge wherever the other vertex
                // changes.
                let group = &records[at..at + n as usize];
                at += n as usize;
                for (i, &(v, t, k)) in group.iter().enumerate() {
                    if i == 0 || group[i - 1].0 != v {
                        edges.offsets.push(edges.tris.len() as u32);
                    }
                    edges.tri_edges[t as usize][k as usize] = edges.offsets.len() as u32 - 1;
                    edges.tris.push(t);
                }
            }
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
        // Per chunk: the entries of its vertices in order, and how many each vertex has.
        let chunks: Vec<Chunk<(PhaseId, DVec3)>> = vertex_chunks(n_vertices)
            .map(|range| {
                let mut counts = Vec::with_capacity(range.len());
                let mut entries: Vec<(PhaseId, DVec3)> = Vec::with_capacity(2 * range.len());
                let mut contrib: Vec<(PhaseId, u32, DVec3)> = Vec::new();
                for v in range {
                    contrib.clear();
                    for (t, k) in around.of(v as u32) {
                        let p = &corners[t];
                        let e1 = p[(k + 1) % 3] - p[k];
                        let e2 = p[(k + 2) % 3] - p[k];
                        // atan2 of |cross| and dot: accurate for all angles, finite for zero
                        // edges.
                        let w = e1.cross(e2).length().atan2(e1.dot(e2)) * normals[t];
                        contrib.push((labels[t][1], t as u32, w));
                        contrib.push((labels[t][0], t as u32, -w));
                    }
                    contrib.sort_unstable_by_key(|&(phase, t, _)| (phase, t));
                    let start = entries.len();
                    for &(phase, _, w) in &contrib {
                        match entries[start..].last_mut() {
                            Some((p, sum)) if *p == phase => *sum += w,
                            _ => entries.push((phase, w)),
                        }
                    }
                    for (_, n) in &mut entries[start..] {
                        *n = n.normalize_or_zero();
                    }
                    counts.push((entries.len() - start) as u32);
                }
                (counts, entries)
            })
            .collect();
        let mut table = Pseudonormals {
            offsets: Vec::with_capacity(n_vertices + 1),
            entries: Vec::with_capacity(chunks.iter().map(|(_, e)| e.len()).sum()),
        };
        let mut end = 0u32;
        for (counts, entries) in chunks {
            for n in counts {
                table.offsets.push(end);
                end += n;
            }
            table.entries.extend(entries);
        }
        table.offsets.push(end);
        table
    }

    /// `(phase, unit pseudonormal)` pairs of vertex `v`, by ascending phase.
    #[inline]
    pub(crate) fn of(&self, v: u32) -> &[(PhaseId, DVec3)] {
        let v = v as usize;
        &self.entries[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::lattice_mesh;

    /// The edge table as a global sort of `(min vertex, max vertex, triangle, edge index)`
    /// records defines it.
    fn sorted_records(triangles: &[[u32; 3]]) -> Vec<(u32, u32, u32, u8)> {
        let mut records: Vec<(u32, u32, u32, u8)> = triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| {
                (0..3).map(move |k| {
                    let (u, v) = (tri[k], tri[(k + 1) % 3]);
                    (u.min(v), u.max(v), t as u32, k as u8)
                })
            })
            .collect();
        records.sort_unstable();
        records
    }

    #[test]
    fn edges_match_the_sorted_records_with_non_manifold_and_degenerate_triangles() {
        // A 3-phase lattice has non-manifold edges; add a triangle with a repeated vertex and
        // one with all three the same, as a damaged mesh read from a file could have.
        let mesh = lattice_mesh(3, |i, j, k| ((i + 2 * j + k) % 3) as PhaseId);
        let mut triangles = mesh.triangles.clone();
        triangles.push([5, 5, 9]);
        triangles.push([7, 7, 7]);
        let n_vertices = mesh.vertices.len();
        let edges = Edges::build(&VertexCorners::build(n_vertices, &triangles), &triangles);
        let records = sorted_records(&triangles);
        // Edge ids number the distinct (min, max) pairs in sorted order; each edge lists its
        // records' triangles in record order.
        let mut id = 0u32;
        let mut tris = Vec::new();
        for (i, &(u, v, t, k)) in records.iter().enumerate() {
            if i > 0 && (records[i - 1].0, records[i - 1].1) != (u, v) {
                id += 1;
            }
            assert_eq!(
                edges.tri_edges[t as usize][k as usize], id,
                "({u}, {v}) of {t}"
            );
            tris.push(t);
        }
        assert_eq!(edges.offsets.len() as u32, id + 2);
        assert_eq!(edges.tris, tris);
    }
}
