//! Contact detection for a whole mesh motion ([`detect`]) and for the local pseudo-motions of
//! remeshing ([`local_motion_is_safe`]): broad phase on swept boxes, then the conservative CCD
//! of [`super::ccd`] on every vertex–triangle and edge–edge pair that shares no vertex.

use super::broadphase::{StaticGrid, TriangleGrid};
use super::ccd::{self, boxes_overlap};
use glam::DVec3;
use rayon::prelude::*;

/// A (possible) contact during a motion: a vertex against a triangle (by index), or two edges
/// given by their vertices (each `[lo, hi]`, and `a < b` lexicographically).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Contact {
    VertexTriangle { vertex: u32, triangle: u32 },
    EdgeEdge { a: [u32; 2], b: [u32; 2] },
}

/// A removed triangle slot ([`super::connectivity::DEAD`]): every function of the collision
/// modules skips such entries, so callers may pass a triangle list with holes.
pub fn is_removed(tri: &[u32; 3]) -> bool {
    *tri == super::connectivity::DEAD
}

/// The unique edges of a triangle list, sorted, and for each triangle the indices of its
/// three edges (edge `k` joins corners `k` and `k + 1`; `u32::MAX` for removed triangles).
pub fn edges_of(triangles: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<[u32; 3]>) {
    let mut all: Vec<([u32; 2], u32)> = triangles
        .par_iter()
        .enumerate()
        .filter(|(_, tri)| !is_removed(tri))
        .flat_map_iter(|(t, tri)| {
            (0..3).map(move |k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                ([a.min(b), a.max(b)], (3 * t + k) as u32)
            })
        })
        .collect();
    all.par_sort_unstable();
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(all.len() / 2 + 1);
    let mut tri_edges = vec![[u32::MAX; 3]; triangles.len()];
    for (e, slot) in all {
        if edges.last() != Some(&e) {
            edges.push(e);
        }
        tri_edges[slot as usize / 3][slot as usize % 3] = (edges.len() - 1) as u32;
    }
    (edges, tri_edges)
}

fn sweep_box(points: impl Iterator<Item = DVec3>) -> (DVec3, DVec3) {
    points.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.min(p), hi.max(p)),
    )
}

/// Box of triangle `tri` swept from `x0` to `x1`; empty (`lo = +∞`, `hi = −∞`, overlapping
/// nothing) for a removed triangle.
pub fn swept_triangle_box(tri: &[u32; 3], x0: &[DVec3], x1: &[DVec3]) -> (DVec3, DVec3) {
    if is_removed(tri) {
        return sweep_box(std::iter::empty());
    }
    sweep_box(tri.iter().flat_map(|&v| [x0[v as usize], x1[v as usize]]))
}

/// Cell size for a grid of the given boxes: 1.5 times their mean largest extent (deterministic:
/// summed in index order), so that a typical box spans one or two cells per axis.
pub fn cell_size_for(boxes: &[(DVec3, DVec3)]) -> f64 {
    let sum: f64 = boxes.iter().map(|(l, h)| (*h - *l).max_element()).sum();
    1.5 * sum / boxes.len().max(1) as f64
}

fn shares_vertex(a: &[u32], b: &[u32]) -> bool {
    a.iter().any(|x| b.contains(x))
}

/// Every contact of the linear motion `x0 → x1` of the mesh `triangles` (vertex–triangle and
/// edge–edge pairs sharing a vertex are skipped): vertex–triangle contacts sorted by vertex
/// then triangle, then edge–edge contacts sorted by edge. The same on any number of threads.
pub fn detect(triangles: &[[u32; 3]], x0: &[DVec3], x1: &[DVec3]) -> Vec<Contact> {
    Detector::new(triangles, x0.len()).detect(x0, x1)
}

/// The topology [`detect`] needs, built once for repeated detections on the same triangles
/// (as in collision response iterations): edges, used vertices, and an owner triangle for
/// every vertex and edge (the lowest-index triangle containing it). Each primitive pair is
/// tested exactly once, from the pair of its owners: a primitive's swept box lies inside its
/// owner's, so overlapping primitive boxes imply overlapping owner boxes.
pub struct Detector<'a> {
    triangles: &'a [[u32; 3]],
    vertices: Vec<u32>,
    edges: Vec<[u32; 2]>,
    tri_edges: Vec<[u32; 3]>,
    vertex_owner: Vec<u32>,
    edge_owner: Vec<u32>,
}

impl<'a> Detector<'a> {
    /// Topology of `triangles` over `n_vertices` vertices (indices must be in range).
    pub fn new(triangles: &'a [[u32; 3]], n_vertices: usize) -> Self {
        let mut vertex_owner = vec![u32::MAX; n_vertices];
        for (t, tri) in triangles.iter().enumerate().rev() {
            if is_removed(tri) {
                continue;
            }
            for &v in tri {
                vertex_owner[v as usize] = t as u32;
            }
        }
        let vertices = (0..n_vertices as u32)
            .filter(|&v| vertex_owner[v as usize] != u32::MAX)
            .collect();
        let (edges, tri_edges) = edges_of(triangles);
        let mut edge_owner = vec![u32::MAX; edges.len()];
        for (t, te) in tri_edges.iter().enumerate().rev() {
            if is_removed(&triangles[t]) {
                continue;
            }
            for &e in te {
                edge_owner[e as usize] = t as u32;
            }
        }
        Detector {
            triangles,
            vertices,
            edges,
            tri_edges,
            vertex_owner,
            edge_owner,
        }
    }

    /// The unique edges, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// The vertices used by some triangle, ascending.
    pub fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// Edge indices of each triangle.
    pub fn tri_edges(&self) -> &[[u32; 3]] {
        &self.tri_edges
    }

    /// [`detect`] for the motion `x0 → x1`: every triangle queries the grid of swept boxes once;
    /// for each overlapping triangle it tests its own vertices against that triangle and, for
    /// higher-index triangles, its own edges against that triangle's own edges.
    pub fn detect(&self, x0: &[DVec3], x1: &[DVec3]) -> Vec<Contact> {
        self.detect_among(x0, x1, None)
    }

    /// [`Detector::detect`] restricted to pairs with at least one vertex flagged in `changed`:
    /// after a detection, pairs whose vertices all kept their end positions keep their
    /// verdict, so collision response iterations need only re-test the pairs they touched.
    pub fn detect_changed(&self, x0: &[DVec3], x1: &[DVec3], changed: &[bool]) -> Vec<Contact> {
        self.detect_among(x0, x1, Some(changed))
    }

    /// Every contact of pairs with a vertex flagged in `changed` (all pairs when `None`).
    /// A full detection queries a grid of every swept box from every triangle. A restricted
    /// one (collision response rounds, where few vertices changed) queries a grid of only the
    /// touched triangles' boxes, so each triangle finds just its touched neighbours; a pair
    /// with one touched triangle is then seen from the other triangle only, which tests it
    /// both ways ([`Pair::test`]). Either way each primitive pair is tested once, and
    /// the sorted result is the same.
    fn detect_among(&self, x0: &[DVec3], x1: &[DVec3], changed: Option<&[bool]>) -> Vec<Contact> {
        let triangles = self.triangles;
        let boxes: Vec<(DVec3, DVec3)> = triangles
            .par_iter()
            .map(|t| swept_triangle_box(t, x0, x1))
            .collect();
        let edge_boxes: Vec<(DVec3, DVec3)> = self
            .edges
            .par_iter()
            .map(|e| sweep_box(e.iter().flat_map(|&v| [x0[v as usize], x1[v as usize]])))
            .collect();
        let touched: Option<Vec<bool>> = changed.map(|c| {
            triangles
                .par_iter()
                .map(|tri| !is_removed(tri) && tri.iter().any(|&v| c[v as usize]))
                .collect()
        });
        // The grid's triangles: all of them, or the touched ones (`ids` maps grid entries back).
        let ids: Option<Vec<u32>> = touched.as_ref().map(|touched| {
            (0..triangles.len() as u32)
                .filter(|&t| touched[t as usize])
                .collect()
        });
        let cell = cell_size_for(&boxes);
        let (grid, kept_boxes) = match &ids {
            None => (StaticGrid::build(boxes, cell), None),
            Some(ids) => {
                let grid_boxes = ids.iter().map(|&t| boxes[t as usize]).collect();
                (StaticGrid::build(grid_boxes, cell), Some(boxes))
            }
        };
        // Every triangle's swept box: the grid's own in a full detection, else kept aside.
        let boxes: &[(DVec3, DVec3)] = kept_boxes.as_deref().unwrap_or(grid.boxes());
        let pair = Pair {
            detector: self,
            x0,
            x1,
            boxes,
            edge_boxes: &edge_boxes,
        };
        let per_triangle: Vec<(Vec<Contact>, Vec<Contact>)> = (0..triangles.len() as u32)
            .into_par_iter()
            .map_init(Vec::new, |cand, t| {
                let (mut vt, mut ee) = (Vec::new(), Vec::new());
                if is_removed(&triangles[t as usize]) {
                    return (vt, ee);
                }
                let (lo, hi) = boxes[t as usize];
                grid.query(lo, hi, cand);
                // A triangle outside the grid meets only touched ones, none of which sees it.
                let both_ways = touched.as_ref().is_some_and(|touched| !touched[t as usize]);
                for &entry in cand.iter() {
                    let s = ids.as_ref().map_or(entry, |ids| ids[entry as usize]);
                    if s != t {
                        pair.test(t, s, both_ways, &mut vt, &mut ee);
                    }
                }
                (vt, ee)
            })
            .collect();
        let (mut vt, mut ee): (Vec<Contact>, Vec<Contact>) = (Vec::new(), Vec::new());
        for (a, b) in per_triangle {
            vt.extend(a);
            ee.extend(b);
        }
        vt.par_sort_unstable();
        ee.par_sort_unstable();
        vt.extend(ee);
        vt
    }

    /// The vertices and edges `t` owns.
    fn owned(
        &self,
        t: u32,
    ) -> (
        impl Iterator<Item = u32> + '_,
        impl Iterator<Item = u32> + '_,
    ) {
        let vertices = self.triangles[t as usize]
            .into_iter()
            .filter(move |&v| self.vertex_owner[v as usize] == t);
        let edges = self.tri_edges[t as usize]
            .into_iter()
            .filter(move |&e| self.edge_owner[e as usize] == t);
        (vertices, edges)
    }
}

/// One detection's motion and swept boxes, for testing the primitives of triangle pairs.
struct Pair<'d, 'a> {
    detector: &'d Detector<'a>,
    x0: &'d [DVec3],
    x1: &'d [DVec3],
    boxes: &'d [(DVec3, DVec3)],
    edge_boxes: &'d [(DVec3, DVec3)],
}

impl Pair<'_, '_> {
    /// Tests the primitives `t` owns against `s`: its vertices against triangle `s`, and its
    /// edges against the edges `s` owns when `s > t` (the lower triangle tests a pair's edges).
    /// `both_ways`: also `s`'s vertices against `t`, and the edges whatever the order, for a
    /// pair that is seen from `t` only.
    fn test(&self, t: u32, s: u32, both_ways: bool, vt: &mut Vec<Contact>, ee: &mut Vec<Contact>) {
        self.vertices_against(t, s, vt);
        if both_ways {
            self.vertices_against(s, t, vt);
        }
        if !(both_ways || s > t) {
            return;
        }
        let d = self.detector;
        let (_, own_edges) = d.owned(t);
        for e in own_edges {
            let ea = d.edges[e as usize];
            let (elo, ehi) = self.edge_boxes[e as usize];
            let (_, other_edges) = d.owned(s);
            for f in other_edges {
                let eb = d.edges[f as usize];
                let (flo, fhi) = self.edge_boxes[f as usize];
                if !shares_vertex(&ea, &eb)
                    && boxes_overlap(elo, ehi, flo, fhi)
                    && edge_edge_moves_into(&ea, &eb, self.x0, self.x1)
                {
                    ee.push(Contact::EdgeEdge {
                        a: ea.min(eb),
                        b: ea.max(eb),
                    });
                }
            }
        }
    }

    /// The vertices `t` owns against triangle `s`.
    fn vertices_against(&self, t: u32, s: u32, vt: &mut Vec<Contact>) {
        let d = self.detector;
        let other = d.triangles[s as usize];
        let (slo, shi) = self.boxes[s as usize];
        let (own_vertices, _) = d.owned(t);
        for v in own_vertices {
            let (p, q) = (self.x0[v as usize], self.x1[v as usize]);
            if !other.contains(&v)
                && boxes_overlap(p.min(q), p.max(q), slo, shi)
                && vertex_triangle_moves_into(v, &other, self.x0, self.x1)
            {
                vt.push(Contact::VertexTriangle {
                    vertex: v,
                    triangle: s,
                });
            }
        }
    }
}

fn gather(ids: [u32; 4], x: &[DVec3]) -> [DVec3; 4] {
    ids.map(|i| x[i as usize])
}

/// Does none of the four vertices move? The start `x0` is contact-free (every caller's
/// precondition), so such a pair keeps its start configuration and can make no contact,
/// whatever the CCD's near-miss tolerance would report for it. Without this, a pair that
/// had drifted within that tolerance (a 256-region foam at t = 0.038: a box-edge vertex
/// 5e-10 from a wall triangle's edge) failed every motion of the mesh, the smallest halving
/// included, even after impact zones had stopped all four vertices.
fn static_pair(ids: [u32; 4], x0: &[DVec3], x1: &[DVec3]) -> bool {
    ids.iter().all(|&i| x0[i as usize] == x1[i as usize])
}

/// CCD of vertex `v` against triangle `tri` under `x0 → x1`.
pub fn vertex_triangle_moves_into(v: u32, tri: &[u32; 3], x0: &[DVec3], x1: &[DVec3]) -> bool {
    let ids = [v, tri[0], tri[1], tri[2]];
    !static_pair(ids, x0, x1) && ccd::vertex_triangle(&gather(ids, x0), &gather(ids, x1))
}

/// CCD of edge `a` against edge `b` under `x0 → x1`.
pub fn edge_edge_moves_into(a: &[u32; 2], b: &[u32; 2], x0: &[DVec3], x1: &[DVec3]) -> bool {
    let ids = [a[0], a[1], b[0], b[1]];
    !static_pair(ids, x0, x1) && ccd::edge_edge(&gather(ids, x0), &gather(ids, x1))
}

/// Any contact between the primitives of triangles `t` and `s` (pairs sharing a vertex skipped).
fn triangle_pair_collides(t: &[u32; 3], s: &[u32; 3], x0: &[DVec3], x1: &[DVec3]) -> bool {
    let vt = |p: &[u32; 3], q: &[u32; 3]| {
        p.iter()
            .any(|&v| !q.contains(&v) && vertex_triangle_moves_into(v, q, x0, x1))
    };
    if vt(t, s) || vt(s, t) {
        return true;
    }
    (0..3).any(|i| {
        let ea = [t[i], t[(i + 1) % 3]];
        (0..3).any(|j| {
            let eb = [s[j], s[(j + 1) % 3]];
            !shares_vertex(&ea, &eb) && edge_edge_moves_into(&ea, &eb, x0, x1)
        })
    })
}

/// `true` if moving the vertices `moving` from `x0` to `x1` (every other vertex must have
/// `x1 == x0`) creates no contact between primitives of `triangles` that share no vertex.
/// Meant for remeshing pseudo-motions (Brochu and Bridson 2009; paper 000 App. A).
///
/// Requirements: every entry of `triangles` is a live triangle, and `grid` holds exactly these
/// triangles, each with a box containing its corners at `x0` (a triangle incident to a moving
/// vertex is found through the grid at that vertex's `x0`). Moving triangles (those with a
/// moving vertex) are tested against the grid with their swept boxes and against each other.
pub fn local_motion_is_safe(
    grid: &TriangleGrid,
    triangles: &[[u32; 3]],
    x0: &[DVec3],
    x1: &[DVec3],
    moving: &[u32],
) -> bool {
    let mut cand = Vec::new();
    let mut moving_tris: Vec<u32> = Vec::new();
    for &v in moving {
        let p = x0[v as usize];
        grid.query(p, p, &mut cand);
        moving_tris.extend(cand.iter().copied().filter(|&t| {
            triangles
                .get(t as usize)
                .is_some_and(|tri| tri.contains(&v))
        }));
    }
    moving_tris.sort_unstable();
    moving_tris.dedup();
    for (i, &t) in moving_tris.iter().enumerate() {
        let tri = triangles[t as usize];
        let (lo, hi) = swept_triangle_box(&tri, x0, x1);
        grid.query(lo, hi, &mut cand);
        for &s in &cand {
            if moving_tris.binary_search(&s).is_ok() {
                continue;
            }
            let Some(other) = triangles.get(s as usize).filter(|t| !is_removed(t)) else {
                continue;
            };
            if triangle_pair_collides(&tri, other, x0, x1) {
                return false;
            }
        }
        for &s in &moving_tris[i + 1..] {
            let other = triangles[s as usize];
            let (olo, ohi) = swept_triangle_box(&other, x0, x1);
            if boxes_overlap(lo, hi, olo, ohi) && triangle_pair_collides(&tri, &other, x0, x1) {
                return false;
            }
        }
    }
    true
}

#[cfg(test)]
mod tests;
