//! Exact unsigned distance and phase indicator of a point with respect to the interfaces of a
//! [`LabeledMesh`] (paper 004 §4, Algorithm 1): nearest point through a bounding-box tree,
//! then the phase from the feature the nearest point lies on — face: sign of
//! `E = (x − y) · n`; edge: the triangle around the (possibly non-manifold) edge with the
//! largest `|E|`; vertex: the incident triangle nearest in angle to `x − y`
//! ([`MeshQuery::nearest_in_angle`]) instead of the paper's per-phase angle-weighted
//! pseudonormals (§4.1, Fig. 3), which hold only where each phase's region is convex at the
//! vertex. Every case reads the phase off the sheets around the nearest point, so it needs
//! them in the order their labels assume: where sheets cross (a fold), the local picture
//! contradicts the mesh's regions and the answer is wrong however far `x` is. Contouring keeps
//! triple lines fold-free (`contour::extract`; issue 17).

mod adjacency;
mod bvh;
mod triangle;

use crate::mesh::LabeledMesh;
use adjacency::{Edges, Pseudonormals, VertexCorners};
use bvh::Bvh;
use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};
use triangle::{closest_point, Region};

/// Result of a query: distance to the nearest interface point, the phase at the query point
/// and the nearest point itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// Unsigned distance φ (infinite when the mesh has no interface faces).
    pub distance: f64,
    /// Indicator χ.
    pub phase: PhaseId,
    /// Nearest interface point (the query point itself when there is none).
    pub point: DVec3,
}

/// The mesh feature a nearest point lies on (indices into the source mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Feature {
    /// Interior of source triangle `t`.
    Face(usize),
    /// Edge between source vertices `a < b`.
    Edge(u32, u32),
    /// Source vertex.
    Vertex(u32),
}

/// Corner positions and unit normal (zero when degenerate) of one triangle, kept together
/// (96 bytes, aligned) so that testing a triangle touches as few cache lines as possible.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
struct Tri {
    corners: [DVec3; 3],
    normal: DVec3,
}

/// Distance + indicator oracle over the interface faces of a mesh (faces with an `OUTSIDE`
/// label are not interfaces between phases and are left out). Owns its data, immutable after
/// construction, `Send + Sync`: share one across threads for parallel sampling.
#[derive(Clone, Debug)]
pub struct MeshQuery {
    background: PhaseId,
    bvh: Bvh,
    /// Geometry, in tree order.
    tris: Vec<Tri>,
    /// `[front, back]`, in tree order.
    labels: Vec<[PhaseId; 2]>,
    /// Source vertex indices, in tree order.
    triangles: Vec<[u32; 3]>,
    /// Source triangle index of each tree-order triangle.
    source: Vec<u32>,
    edges: Edges,
    /// Smooth normals for the curved query.
    pseudonormals: Pseudonormals,
    /// Triangle corners (tree order) at each source vertex, for the vertex case's indicator.
    around: VertexCorners,
}

impl MeshQuery {
    /// Builds the oracle for `mesh`; `background` is the phase reported everywhere when the
    /// mesh has no interface faces. O(N log N). Panics if a triangle index is out of range or
    /// the label count differs (meshes from [`crate::ply::read_ply`] and trackers satisfy
    /// [`crate::invariants::check`]).
    pub fn new(mesh: &LabeledMesh, background: PhaseId) -> MeshQuery {
        assert_eq!(
            mesh.labels.len(),
            mesh.triangles.len(),
            "one label pair per triangle"
        );
        let interface: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&t| !mesh.labels[t as usize].contains(&OUTSIDE))
            .collect();
        let input_corners: Vec<[DVec3; 3]> = interface
            .iter()
            .map(|&t| mesh.corners(t as usize))
            .collect();
        let mut bvh = Bvh::build(&input_corners);
        let source: Vec<u32> = bvh.order.iter().map(|&i| interface[i as usize]).collect();
        let corners: Vec<[DVec3; 3]> = bvh
            .order
            .iter()
            .map(|&i| input_corners[i as usize])
            .collect();
        bvh.order = Vec::new();
        let normals: Vec<DVec3> = corners
            .iter()
            .map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize_or_zero())
            .collect();
        let labels: Vec<[PhaseId; 2]> = source.iter().map(|&t| mesh.labels[t as usize]).collect();
        let triangles: Vec<[u32; 3]> = source.iter().map(|&t| mesh.triangles[t as usize]).collect();
        let around = VertexCorners::build(mesh.vertices.len(), &triangles);
        let edges = Edges::build(&around, &triangles);
        let pseudonormals = Pseudonormals::build(&around, &corners, &normals, &labels);
        let tris = corners
            .iter()
            .zip(&normals)
            .map(|(&corners, &normal)| Tri { corners, normal })
            .collect();
        MeshQuery {
            background,
            bvh,
            tris,
            labels,
            triangles,
            source,
            edges,
            pseudonormals,
            around,
        }
    }

    /// Number of interface triangles the oracle answers for.
    pub fn interface_triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Distance and phase at `x`, exact up to floating-point rounding.
    pub fn query(&self, x: DVec3) -> Nearest {
        self.locate(x, f64::INFINITY)
            .map(|(n, _, _)| n)
            .unwrap_or(Nearest {
                distance: f64::INFINITY,
                phase: self.background,
                point: x,
            })
    }

    /// Like [`MeshQuery::query`], but only when an interface point lies within `max_distance`
    /// of `x` (`None` otherwise). Much cheaper far from the interface, where the tree prunes
    /// almost everything: suits "is φ below a threshold" tests.
    pub fn query_within(&self, x: DVec3, max_distance: f64) -> Option<Nearest> {
        self.locate(x, max_distance * max_distance)
            .map(|(n, _, _)| n)
    }

    /// The source mesh's index of the interface triangle nearest to `x` (`None` without
    /// interfaces): the volume correction traces components back through it.
    pub fn nearest_triangle(&self, x: DVec3) -> Option<usize> {
        self.locate(x, f64::INFINITY)
            .map(|(_, _, t)| self.source[t] as usize)
    }

    /// Unsigned distance from `x` to the nearest interface point (infinite without interfaces).
    pub fn distance(&self, x: DVec3) -> f64 {
        let mut best = None;
        let d2 = self.bvh.nearest(x, f64::INFINITY, |i, bound2| {
            let Tri {
                corners: [a, b, c],
                normal,
            } = self.tris[i];
            let plane = (x - a).dot(normal);
            if plane * plane > bound2 {
                return bound2;
            }
            let (y, _) = closest_point(x, a, b, c);
            let d2 = (x - y).length_squared();
            if d2 < bound2 {
                best = Some(i);
                d2
            } else {
                bound2
            }
        });
        match best {
            Some(_) => d2.sqrt(),
            None => f64::INFINITY,
        }
    }

    /// Like [`MeshQuery::query`], but against the curved surface the mesh approximates: each
    /// interface triangle is bulged by the Phong-tessellation offset with α = ½,
    /// `δ(y) = ½ Σᵢ bᵢ ((vᵢ − y)·mᵢ) mᵢ` (bᵢ barycentric, mᵢ the corner's smooth normal), which
    /// reproduces the sagitta of a circle through the corners to second order. The
    /// semi-Lagrangian step samples the previous mesh at points that are not its vertices;
    /// against flat facets every resampling would cut the chord sagitta, ~h²/(8R), off convex
    /// regions (and add it to concave ones), a volume drift of O((h/R)²) per step that the
    /// paper's text does not address. Corners whose smooth normal is more than 25° from the
    /// facet's (sharp features, junction lines) keep the flat facet there, so features stay sharp.
    pub fn query_curved(&self, x: DVec3) -> Nearest {
        self.query_shifted(x, &|_| 0.0)
    }

    /// [`MeshQuery::query_curved`] with every interface triangle `t` (its index in the source
    /// mesh) moved along its normal, towards its front phase, by `shift(t)` (negative: towards
    /// the back phase), as a level-set offset of the signed distance: the volume correction of
    /// [`crate::volume_correction`].
    pub fn query_shifted(&self, x: DVec3, shift: &dyn Fn(usize) -> f64) -> Nearest {
        self.query_shifted_within(x, f64::INFINITY, shift)
            .unwrap_or_else(|| self.query(x))
    }

    /// [`MeshQuery::query_shifted`] when a flat interface point lies within `max_distance` of
    /// `x`, the same answer to the bit (the search starts from a finite bound, which prunes
    /// but does not change which triangle is nearest); `None` otherwise.
    pub fn query_shifted_within(
        &self,
        x: DVec3,
        max_distance: f64,
        shift: &dyn Fn(usize) -> f64,
    ) -> Option<Nearest> {
        let (n, _, t) = self.locate(x, max_distance * max_distance)?;
        let [front, back] = self.labels[t];
        let signed = if n.phase == front {
            n.distance
        } else if n.phase == back {
            -n.distance
        } else {
            return Some(n);
        };
        let normal = self.tris[t].normal;
        let bulge = self.bulge(t, n.point) + shift(self.source[t] as usize);
        let curved = signed - bulge;
        Some(Nearest {
            distance: curved.abs(),
            phase: if curved > 0.0 { front } else { back },
            point: n.point + bulge * normal,
        })
    }

    /// The Phong offset (α = ½) of the point `y` of tree triangle `t`, along its normal.
    fn bulge(&self, t: usize, y: DVec3) -> f64 {
        /// cos 25°: beyond this a corner is a feature and contributes no bulge.
        const SMOOTH_COS: f64 = 0.906_307_787_036_649_9;
        let Tri { corners, normal } = self.tris[t];
        let [a, b, c] = corners;
        let area = (b - a).cross(c - a).dot(normal);
        if area <= 0.0 {
            return 0.0;
        }
        let bary = [
            (b - y).cross(c - y).dot(normal) / area,
            (c - y).cross(a - y).dot(normal) / area,
            (a - y).cross(b - y).dot(normal) / area,
        ];
        let back = self.labels[t][1];
        let mut offset = DVec3::ZERO;
        for (k, &v) in self.triangles[t].iter().enumerate() {
            let smooth = self
                .pseudonormals
                .of(v)
                .iter()
                .find(|(p, _)| *p == back)
                .map_or(normal, |&(_, m)| m);
            if smooth.dot(normal) < SMOOTH_COS {
                continue;
            }
            offset += bary[k].clamp(0.0, 1.0) * (corners[k] - y).dot(smooth) * smooth;
        }
        0.5 * offset.dot(normal)
    }

    /// The triangle at vertex `v` nearest in angle to the direction `d` (on a small sphere
    /// around `v`, each triangle is an arc): the region `d` points into is bounded by that
    /// triangle, on the side `d · n` gives. Ties (the nearest point is an edge direction that
    /// several triangles share) go to the largest `|d · n|`, the edge rule, then to the lowest
    /// index. Per-phase pseudonormals (paper 004 §4.1) decide this only for regions that are
    /// convex at `v`; on the first `enright` 64³ mesh they picked the wrong phase up to 0.4
    /// away (issue 17).
    fn nearest_in_angle(&self, v: u32, d: DVec3) -> Option<usize> {
        let d = d.normalize_or_zero();
        let mut best: Option<(f64, f64, usize)> = None;
        for (s, j) in self.around.of(v) {
            let Tri { corners, normal } = self.tris[s];
            if normal == DVec3::ZERO {
                continue;
            }
            let u1 = (corners[(j + 1) % 3] - corners[j]).normalize_or_zero();
            let u2 = (corners[(j + 2) % 3] - corners[j]).normalize_or_zero();
            let dn = d.dot(normal);
            let p = d - dn * normal;
            // Inside the wedge u1 → u2 (counter-clockwise about the normal) the arc's nearest
            // point is the foot of d on its great circle; outside, one of its ends.
            let inside = u1.cross(p).dot(normal) >= 0.0 && p.cross(u2).dot(normal) >= 0.0;
            let angle = if inside {
                dn.abs().min(1.0).asin()
            } else {
                let c = d.dot(u1).max(d.dot(u2)).clamp(-1.0, 1.0);
                c.acos()
            };
            let better = best.is_none_or(|(a, e, _)| angle < a || (angle == a && dn.abs() > e));
            if better {
                best = Some((angle, dn.abs(), s));
            }
        }
        best.map(|(_, _, s)| s)
    }

    /// Nearest point within squared distance `bound2` and its feature, with the indicator.
    /// Among triangles at exactly the same distance the lowest tree index wins, so the answer
    /// does not depend on the visiting order; the phase is then decided by the shared
    /// edge or vertex tables, never by which of the incident triangles was found.
    pub(crate) fn locate(&self, x: DVec3, bound2: f64) -> Option<(Nearest, Feature, usize)> {
        let mut best: Option<(usize, DVec3, Region)> = None;
        let d2 = self.bvh.nearest(x, bound2, |i, bound2| {
            let Tri {
                corners: [a, b, c],
                normal,
            } = self.tris[i];
            // The distance to the plane bounds the distance to the triangle from below.
            let plane = (x - a).dot(normal);
            if plane * plane > bound2 {
                return bound2;
            }
            let (y, region) = closest_point(x, a, b, c);
            let d2 = (x - y).length_squared();
            let better = d2 < bound2 || (d2 == bound2 && best.is_none_or(|(j, _, _)| i < j));
            if better {
                best = Some((i, y, region));
                d2
            } else {
                bound2
            }
        });
        let (t, y, region) = best?;
        let side = |t: usize, e: f64| {
            let [front, back] = self.labels[t];
            if e > 0.0 {
                front
            } else {
                back
            }
        };
        let (phase, feature) = match region {
            Region::Face => (
                side(t, (x - y).dot(self.tris[t].normal)),
                Feature::Face(self.source[t] as usize),
            ),
            Region::Edge(k) => {
                let e = self.edges.tri_edges[t][k as usize];
                let mut chosen = (t, 0.0f64);
                let mut max_abs = -1.0;
                for &s in self.edges.triangles(e) {
                    let s = s as usize;
                    let e_s = (x - y).dot(self.tris[s].normal);
                    if e_s.abs() > max_abs {
                        max_abs = e_s.abs();
                        chosen = (s, e_s);
                    }
                }
                let (u, v) = (
                    self.triangles[t][k as usize],
                    self.triangles[t][(k as usize + 1) % 3],
                );
                (side(chosen.0, chosen.1), Feature::Edge(u.min(v), u.max(v)))
            }
            Region::Vertex(k) => {
                let v = self.triangles[t][k as usize];
                let s = self.nearest_in_angle(v, x - y).unwrap_or(t);
                let phase = side(s, (x - y).dot(self.tris[s].normal));
                (phase, Feature::Vertex(v))
            }
        };
        Some((
            Nearest {
                distance: d2.sqrt(),
                phase,
                point: y,
            },
            feature,
            t,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::invariants::check;
    use crate::mesh::fixtures::{icosphere, lattice_mesh, push_oriented, Rng};

    /// Cells per axis and the phase of each cell.
    type LatticeCase = (usize, fn(usize, usize, usize) -> PhaseId);

    fn assert_send_sync<T: Send + Sync>() {}

    /// Distance by testing every interface triangle.
    fn brute_distance(mesh: &LabeledMesh, x: DVec3) -> f64 {
        (0..mesh.triangle_count())
            .filter(|&t| !mesh.labels[t].contains(&OUTSIDE))
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (x - closest_point(x, a, b, c).0).length_squared()
            })
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }

    /// A tetrahedron `[a, b, c, d]` cut through `c`, `d` and the midpoint of `ab` into phase 1
    /// (the half at `a`) and phase 2 (at `b`) inside phase 0. Edge `cd` is a triple line; `c`
    /// and `d` are non-manifold vertices at convex corners.
    fn split_tet(
        a: DVec3,
        b: DVec3,
        c: DVec3,
        d: DVec3,
    ) -> (LabeledMesh, impl Fn(DVec3) -> PhaseId) {
        let m = 0.5 * (a + b);
        let mut mesh = LabeledMesh {
            vertices: vec![a, b, c, d, m],
            ..LabeledMesh::default()
        };
        let t1 = [a, m, c, d];
        let t2 = [m, b, c, d];
        let c1 = (a + m + c + d) / 4.0;
        let c2 = (m + b + c + d) / 4.0;
        for (tri, inner, phase) in [
            ([0, 4, 2], c1, 1),
            ([0, 4, 3], c1, 1),
            ([0, 2, 3], c1, 1),
            ([4, 1, 2], c2, 2),
            ([4, 1, 3], c2, 2),
            ([1, 2, 3], c2, 2),
        ] {
            push_oriented(&mut mesh, tri, inner, 0, phase);
        }
        push_oriented(&mut mesh, [4, 2, 3], c1, 2, 1);
        let inside = |t: [DVec3; 4], x: DVec3| {
            let vol = |p: DVec3, q: DVec3, r: DVec3, s: DVec3| (q - p).dot((r - p).cross(s - p));
            let total = vol(t[0], t[1], t[2], t[3]).signum();
            [
                vol(x, t[1], t[2], t[3]),
                vol(t[0], x, t[2], t[3]),
                vol(t[0], t[1], x, t[3]),
                vol(t[0], t[1], t[2], x),
            ]
            .iter()
            .all(|v| v * total > 0.0)
        };
        let phase = move |x: DVec3| {
            if inside(t1, x) {
                1
            } else if inside(t2, x) {
                2
            } else {
                0
            }
        };
        (mesh, phase)
    }

    /// Phase of a point in the lattice configuration `phase` on `n³` cells of the unit cube.
    fn lattice_phase(
        n: usize,
        phase: impl Fn(usize, usize, usize) -> PhaseId,
    ) -> impl Fn(DVec3) -> PhaseId {
        move |x: DVec3| {
            let c = |v: f64| ((v * n as f64).floor() as usize).min(n - 1);
            phase(c(x.x), c(x.y), c(x.z))
        }
    }

    /// Random points: uniform in `[lo, hi]` plus clusters of radius `r` around every vertex
    /// and edge midpoint of the interface, where edge and vertex cases occur.
    fn probe_points(
        mesh: &LabeledMesh,
        lo: DVec3,
        hi: DVec3,
        r: f64,
        per: usize,
        seed: u64,
    ) -> Vec<DVec3> {
        let mut rng = Rng(seed);
        let mut pts: Vec<DVec3> = (0..2000).map(|_| rng.point(lo, hi)).collect();
        let mut anchors = Vec::new();
        for t in 0..mesh.triangle_count() {
            if mesh.labels[t].contains(&OUTSIDE) {
                continue;
            }
            let [a, b, c] = mesh.corners(t);
            anchors.extend([a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)]);
        }
        for p in anchors {
            for _ in 0..per {
                let x = rng.point(p - DVec3::splat(r), p + DVec3::splat(r));
                if x.cmpgt(lo).all() && x.cmplt(hi).all() {
                    pts.push(x);
                }
            }
        }
        pts
    }

    /// Checks the indicator against `truth` at every point farther than 1e-6 from the
    /// interface; returns how many points fell in the face, edge and vertex cases.
    fn check_indicator(
        mesh: &LabeledMesh,
        truth: impl Fn(DVec3) -> PhaseId,
        points: &[DVec3],
    ) -> [usize; 3] {
        let q = MeshQuery::new(mesh, 0);
        let mut cases = [0; 3];
        for &x in points {
            let (n, feature, _) = q.locate(x, f64::INFINITY).unwrap();
            if n.distance <= 1e-6 {
                continue;
            }
            assert_eq!(
                n.phase,
                truth(x),
                "x = {x}, feature {feature:?}, distance {}",
                n.distance
            );
            cases[match feature {
                Feature::Face(_) => 0,
                Feature::Edge(..) => 1,
                Feature::Vertex(_) => 2,
            }] += 1;
        }
        cases
    }

    #[test]
    fn query_is_send_and_sync() {
        assert_send_sync::<MeshQuery>();
    }

    #[test]
    fn distance_matches_brute_force() {
        let (tet, _) = split_tet(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.3, 0.9, 0.1),
            DVec3::new(0.4, 0.2, 0.7),
        );
        let meshes = [
            icosphere(DVec3::new(0.1, 0.2, 0.3), 0.8, 3, 1, 0),
            lattice_mesh(4, |i, j, k| ((i * 7 + j * 3 + k * 5) % 3) as PhaseId),
            tet,
        ];
        let mut rng = Rng(7);
        for mesh in &meshes {
            let q = MeshQuery::new(mesh, 0);
            for _ in 0..3000 {
                let x = rng.point(DVec3::splat(-1.5), DVec3::splat(1.5));
                let brute = brute_distance(mesh, x);
                let n = q.query(x);
                // Same closest-point arithmetic and an exact minimum: the tree must find the
                // very same value, not just a close one.
                assert_eq!(n.distance, brute, "x = {x}");
                assert_eq!(q.distance(x), brute);
                // The reported point realises the distance (rounding of one subtraction).
                assert!((n.point.distance(x) - brute).abs() <= 1e-12);
            }
        }
    }

    #[test]
    fn build_is_thread_count_independent() {
        // Large enough (> PARALLEL_MIN triangles) for the parallel tree build to split.
        let mesh = icosphere(DVec3::ZERO, 1.0, 4, 1, 0);
        let build = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| MeshQuery::new(&mesh, 0))
        };
        let (one, two) = (build(1), build(2));
        assert_eq!(one.source, two.source);
        let mut rng = Rng(11);
        for _ in 0..500 {
            let x = rng.point(DVec3::splat(-1.2), DVec3::splat(1.2));
            assert_eq!(one.locate(x, f64::INFINITY), two.locate(x, f64::INFINITY));
        }
    }

    #[test]
    fn bounded_query_agrees() {
        let mesh = icosphere(DVec3::ZERO, 1.0, 2, 1, 0);
        let q = MeshQuery::new(&mesh, 0);
        let mut rng = Rng(3);
        for _ in 0..1000 {
            let x = rng.point(DVec3::splat(-2.0), DVec3::splat(2.0));
            let full = q.query(x);
            match q.query_within(x, 0.3) {
                Some(n) => assert_eq!(n, full),
                None => assert!(full.distance > 0.3),
            }
        }
    }

    #[test]
    fn degenerate_triangles_give_finite_answers() {
        // A sliver fan: one triangle of zero area, one of area ~1e-300, around a shared edge.
        let mesh = LabeledMesh {
            vertices: vec![
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.5, 0.0, 0.0),
                DVec3::new(0.5, 1e-300, 0.0),
                DVec3::new(0.5, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 1, 3], [0, 1, 4]],
            labels: vec![[1, 0], [1, 0], [1, 0]],
        };
        let q = MeshQuery::new(&mesh, 0);
        let mut rng = Rng(5);
        for _ in 0..2000 {
            let x = rng.point(DVec3::splat(-1.0), DVec3::splat(2.0));
            let n = q.query(x);
            assert!(n.distance.is_finite() && n.point.is_finite(), "{x}: {n:?}");
            assert!(n.phase <= 1);
            assert_eq!(n.distance, brute_distance(&mesh, x));
        }
    }

    #[test]
    fn empty_interface_gives_background() {
        // Only OUTSIDE faces: a single-phase box.
        let mesh = lattice_mesh(1, |_, _, _| 3);
        let q = MeshQuery::new(&mesh, 3);
        assert_eq!(q.interface_triangle_count(), 0);
        let n = q.query(DVec3::splat(0.5));
        assert_eq!((n.distance, n.phase), (f64::INFINITY, 3));
        assert_eq!(q.query_within(DVec3::ZERO, 1.0), None);
    }

    #[test]
    fn indicator_two_phase_cube() {
        let f = |i: usize, _: usize, _: usize| i as PhaseId;
        let mesh = lattice_mesh(2, f);
        let pts = probe_points(&mesh, DVec3::ZERO, DVec3::ONE, 0.05, 20, 1);
        let cases = check_indicator(&mesh, lattice_phase(2, f), &pts);
        assert!(cases[0] > 1000, "{cases:?}");
    }

    #[test]
    fn indicator_slabs_quadrants_and_triple_lines() {
        let configs: [LatticeCase; 3] = [
            (3, |i, _, _| i as PhaseId),
            (2, |i, j, _| (i + 2 * j) as PhaseId),
            (2, |i, j, _| if i == 0 { 0 } else { 1 + j as PhaseId }),
        ];
        for (seed, (n, f)) in configs.into_iter().enumerate() {
            let mesh = lattice_mesh(n, f);
            assert_eq!(check(&mesh, 0.0), Ok(()));
            let pts = probe_points(&mesh, DVec3::ZERO, DVec3::ONE, 0.05, 20, seed as u64);
            check_indicator(&mesh, lattice_phase(n, f), &pts);
        }
    }

    #[test]
    fn indicator_at_box_corners_and_staircases() {
        let configs: [LatticeCase; 3] = [
            // A cube inside another phase: convex corners and edges.
            (3, |i, j, k| PhaseId::from(i == 1 && j == 1 && k == 1)),
            // A staircase: convex, reflex and saddle vertices.
            (4, |i, j, k| PhaseId::from(i + j + k <= 3)),
            // Three phases scattered: non-manifold edges and vertices, pinched regions.
            (4, |i, j, k| {
                ((i * 7 + j * 3 + k * 5 + i * j) % 3) as PhaseId
            }),
        ];
        let mut total = [0; 3];
        for (seed, (n, f)) in configs.into_iter().enumerate() {
            let mesh = lattice_mesh(n, f);
            assert_eq!(check(&mesh, 0.0), Ok(()));
            let pts = probe_points(&mesh, DVec3::ZERO, DVec3::ONE, 0.08, 6, 10 + seed as u64);
            let cases = check_indicator(&mesh, lattice_phase(n, f), &pts);
            for k in 0..3 {
                total[k] += cases[k];
            }
        }
        // The probes must exercise every branch of Algorithm 1.
        assert!(total.iter().all(|&c| c > 100), "{total:?}");
    }

    #[test]
    fn indicator_at_non_manifold_vertices_and_edges() {
        let tets = [
            (
                DVec3::ZERO,
                DVec3::X,
                DVec3::new(0.3, 0.9, 0.1),
                DVec3::new(0.4, 0.2, 0.7),
            ),
            // Flat and sharp: small dihedral angles along the triple line.
            (
                DVec3::ZERO,
                DVec3::new(1.0, 0.1, 0.0),
                DVec3::new(0.6, 0.05, 0.08),
                DVec3::new(0.5, 0.9, 0.02),
            ),
        ];
        for (seed, (a, b, c, d)) in tets.into_iter().enumerate() {
            let (mesh, truth) = split_tet(a, b, c, d);
            assert_eq!(check(&mesh, 0.0), Ok(()));
            let q = MeshQuery::new(&mesh, 0);
            // Vertices c and d carry one pseudonormal per phase.
            assert_eq!(q.pseudonormals.of(2).len(), 3);
            let pts = probe_points(
                &mesh,
                DVec3::splat(-1.0),
                DVec3::splat(2.0),
                0.1,
                200,
                20 + seed as u64,
            );
            let cases = check_indicator(&mesh, truth, &pts);
            assert!(cases[1] > 100 && cases[2] > 100, "{cases:?}");
        }
    }
}
