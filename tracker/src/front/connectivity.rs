//! Connectivity of a non-manifold labeled mesh under local edits (paper 000 §3, issue 6 item
//! 1): vertex → triangles lists kept up to date by every insertion and removal, from which
//! edge → triangles (any number of them), vertex neighbours and the regions (phases) around a
//! vertex follow in O(valence). Removed triangles and vertices leave tombstones that
//! [`Connectivity::compact`] squeezes out, so indices stay stable during a remeshing pass.

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use crate::mesh::LabeledMesh;

/// Vertex indices of a removed triangle.
pub const DEAD: [u32; 3] = [u32::MAX; 3];

/// A labeled mesh with incidence lists. `mesh.triangles[t] == DEAD` marks a removed triangle;
/// a vertex with no incident triangle is unused.
#[derive(Clone, Debug, Default)]
pub struct Connectivity {
    /// The mesh, tombstones included.
    pub mesh: LabeledMesh,
    /// Live triangles incident to each vertex, in no particular order.
    vertex_triangles: Vec<Vec<u32>>,
    /// Removed triangle slots, reused by [`Connectivity::add_triangle`].
    free_triangles: Vec<u32>,
}

impl Connectivity {
    /// Incidence lists of `mesh` (whose indices must be in range; `DEAD` entries are
    /// skipped), O(N).
    pub fn new(mesh: LabeledMesh) -> Connectivity {
        let mut vertex_triangles = vec![Vec::new(); mesh.vertices.len()];
        for (t, tri) in mesh
            .triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| **t != DEAD)
        {
            for &v in tri {
                vertex_triangles[v as usize].push(t as u32);
            }
        }
        Connectivity {
            mesh,
            vertex_triangles,
            free_triangles: Vec::new(),
        }
    }

    /// Position of vertex `v`.
    pub fn position(&self, v: u32) -> DVec3 {
        self.mesh.vertices[v as usize]
    }

    /// Vertex indices of triangle `t` (`DEAD` when removed).
    pub fn triangle(&self, t: u32) -> [u32; 3] {
        self.mesh.triangles[t as usize]
    }

    /// `[front, back]` labels of triangle `t`.
    pub fn labels(&self, t: u32) -> [PhaseId; 2] {
        self.mesh.labels[t as usize]
    }

    /// Is triangle slot `t` in use?
    pub fn is_live(&self, t: u32) -> bool {
        self.mesh.triangles[t as usize] != DEAD
    }

    /// Live triangles incident to vertex `v`.
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        &self.vertex_triangles[v as usize]
    }

    /// Is vertex `v` on a domain-boundary face (an `OUTSIDE` label)?
    pub fn on_boundary(&self, v: u32) -> bool {
        self.vertex_triangles(v)
            .iter()
            .any(|&t| self.labels(t).contains(&OUTSIDE))
    }

    /// Appends the live triangles containing edge `(a, b)` to `out` (cleared first), in the
    /// order of `a`'s list.
    pub fn edge_triangles(&self, a: u32, b: u32, out: &mut Vec<u32>) {
        out.clear();
        out.extend(
            self.vertex_triangles[a as usize]
                .iter()
                .copied()
                .filter(|&t| self.mesh.triangles[t as usize].contains(&b)),
        );
    }

    /// Number of live triangles containing edge `(a, b)`.
    pub fn edge_valence(&self, a: u32, b: u32) -> usize {
        self.vertex_triangles[a as usize]
            .iter()
            .filter(|&&t| self.mesh.triangles[t as usize].contains(&b))
            .count()
    }

    /// Distinct vertices sharing a live triangle with `v`, sorted.
    pub fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut out: Vec<u32> = self.vertex_triangles[v as usize]
            .iter()
            .flat_map(|&t| self.mesh.triangles[t as usize])
            .filter(|&u| u != v)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Phases (regions' materials, `OUTSIDE` included) on either side of the triangles around
    /// `v`, sorted.
    pub fn vertex_regions(&self, v: u32) -> Vec<PhaseId> {
        let mut out: Vec<PhaseId> = self.vertex_triangles[v as usize]
            .iter()
            .flat_map(|&t| self.mesh.labels[t as usize])
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Adds a vertex at `p` and returns its index.
    pub fn add_vertex(&mut self, p: DVec3) -> u32 {
        self.mesh.vertices.push(p);
        self.vertex_triangles.push(Vec::new());
        self.mesh.vertices.len() as u32 - 1
    }

    /// Adds triangle `tri` with `[front, back]` labels, reusing a removed slot if there is one,
    /// and returns its index.
    pub fn add_triangle(&mut self, tri: [u32; 3], labels: [PhaseId; 2]) -> u32 {
        let t = match self.free_triangles.pop() {
            Some(t) => {
                self.mesh.triangles[t as usize] = tri;
                self.mesh.labels[t as usize] = labels;
                t
            }
            None => {
                self.mesh.triangles.push(tri);
                self.mesh.labels.push(labels);
                self.mesh.triangles.len() as u32 - 1
            }
        };
        for v in tri {
            self.vertex_triangles[v as usize].push(t);
        }
        t
    }

    /// Removes live triangle `t`, leaving a tombstone.
    pub fn remove_triangle(&mut self, t: u32) {
        let tri = std::mem::replace(&mut self.mesh.triangles[t as usize], DEAD);
        debug_assert_ne!(tri, DEAD, "triangle {t} removed twice");
        for v in tri {
            let list = &mut self.vertex_triangles[v as usize];
            if let Some(i) = list.iter().position(|&x| x == t) {
                list.swap_remove(i);
            }
        }
        self.free_triangles.push(t);
    }

    /// Every edge of a live triangle once, as `[a, b]` with `a < b`, sorted.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        // Vertex by vertex, each vertex's higher neighbours: sorted without sorting them all.
        let mut out: Vec<[u32; 2]> = Vec::with_capacity(3 * self.vertex_triangles.len());
        let mut higher: Vec<u32> = Vec::new();
        for (a, list) in self.vertex_triangles.iter().enumerate() {
            let a = a as u32;
            higher.clear();
            higher.extend(
                list.iter()
                    .flat_map(|&t| self.mesh.triangles[t as usize])
                    .filter(|&b| b > a),
            );
            higher.sort_unstable();
            higher.dedup();
            out.extend(higher.iter().map(|&b| [a, b]));
        }
        out
    }

    /// Removes tombstones and unused vertices, renumbering everything in the original order,
    /// and rebuilds the incidence lists.
    pub fn compact(&mut self) {
        let mesh = std::mem::take(&mut self.mesh);
        let mut new_index = vec![u32::MAX; mesh.vertices.len()];
        let mut vertices = Vec::with_capacity(mesh.vertices.len());
        for (v, &p) in mesh.vertices.iter().enumerate() {
            if !self.vertex_triangles[v].is_empty() {
                new_index[v] = vertices.len() as u32;
                vertices.push(p);
            }
        }
        let (triangles, labels) = mesh
            .triangles
            .iter()
            .zip(&mesh.labels)
            .filter(|(t, _)| **t != DEAD)
            .map(|(t, &l)| (t.map(|v| new_index[v as usize]), l))
            .unzip();
        *self = Connectivity::new(LabeledMesh {
            vertices,
            triangles,
            labels,
        });
    }

    /// The incidence lists, each sorted, for comparing with a rebuilt structure in tests.
    #[cfg(test)]
    pub(crate) fn sorted_lists(&self) -> Vec<Vec<u32>> {
        self.vertex_triangles
            .iter()
            .map(|l| {
                let mut l = l.clone();
                l.sort_unstable();
                l
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh, Rng};

    #[test]
    fn lattice_edges_and_regions() {
        // Three slabs: the two inner walls meet the boundary in non-manifold edges.
        let mesh = lattice_mesh(3, |i, _, _| i as PhaseId);
        let c = Connectivity::new(mesh);
        let valences: Vec<usize> = c
            .edges()
            .iter()
            .map(|&[a, b]| c.edge_valence(a, b))
            .collect();
        assert!(valences.iter().all(|&v| v == 2 || v == 3), "{valences:?}");
        // Each wall's square outline on the boundary (4 sides × 3 segments) is non-manifold.
        assert_eq!(valences.iter().filter(|&&v| v == 3).count(), 2 * 4 * 3);
        // The vertex (1/3, 0, 0) touches phases 0, 1 and the outside.
        let v = c
            .mesh
            .vertices
            .iter()
            .position(|p| (*p - DVec3::new(1.0 / 3.0, 0.0, 0.0)).length() < 1e-12)
            .unwrap() as u32;
        assert_eq!(c.vertex_regions(v), vec![0, 1, polyphase_grid::OUTSIDE]);
    }

    #[test]
    fn random_edits_match_a_rebuild() {
        let mut c = Connectivity::new(icosphere(DVec3::ZERO, 1.0, 2, 1, 0));
        let mut rng = Rng(7);
        for _ in 0..300 {
            let live: Vec<u32> = (0..c.mesh.triangles.len() as u32)
                .filter(|&t| c.is_live(t))
                .collect();
            let t = live[(rng.next_f64() * live.len() as f64) as usize];
            if rng.next_f64() < 0.5 {
                // Split the triangle at its centroid: 1 removal, 3 insertions.
                let [a, b, cc] = c.triangle(t);
                let l = c.labels(t);
                let p = (c.position(a) + c.position(b) + c.position(cc)) / 3.0;
                c.remove_triangle(t);
                let m = c.add_vertex(p);
                for tri in [[a, b, m], [b, cc, m], [cc, a, m]] {
                    c.add_triangle(tri, l);
                }
            } else {
                // Remove and re-add with the winding reversed and labels swapped.
                let [a, b, cc] = c.triangle(t);
                let [f, k] = c.labels(t);
                c.remove_triangle(t);
                c.add_triangle([a, cc, b], [k, f]);
            }
            // The live triangles and incidence lists agree with a structure built from scratch.
            let rebuilt = Connectivity::new(c.mesh.clone());
            assert_eq!(c.sorted_lists(), rebuilt.sorted_lists());
        }
        let volume = c.mesh.clone();
        c.compact();
        assert!(c.mesh.triangles.iter().all(|t| *t != DEAD));
        crate::invariants::check(&c.mesh, 0.0).expect("edits keep the sphere closed");
        let live_volume: Vec<f64> = {
            let mut m = volume;
            let keep: Vec<bool> = m.triangles.iter().map(|t| *t != DEAD).collect();
            let mut k = keep.iter();
            m.triangles.retain(|_| *k.next().unwrap());
            let mut k = keep.iter();
            m.labels.retain(|_| *k.next().unwrap());
            m.phase_volumes(2)
        };
        // Compaction renumbers without moving anything: identical volumes up to the order of
        // the bounding-box reference point (same box, so bit-identical sums).
        assert_eq!(c.mesh.phase_volumes(2), live_volume);
    }
}
