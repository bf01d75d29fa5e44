//! Proximity pairs of snap-based merging (paper 000 §6.2): vertex–vertex, vertex–triangle and
//! edge–edge pairs of primitives sharing no vertex and closer than the merge distance, found
//! through the remesher's broad phase, and the fold rule that keeps a surface from snapping
//! within its own plane.

use glam::DVec3;

use super::Merger;
use crate::front::response::proximity::{point_triangle_closest, segment_segment_closest};

/// A mesh primitive: a vertex, an edge (ends ascending) or a triangle (slot and the vertices it
/// held when found, so that a reused slot is not mistaken for it).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Prim {
    /// A vertex.
    Vertex(u32),
    /// An edge, ends ascending.
    Edge([u32; 2]),
    /// A triangle slot and its vertices.
    Triangle(u32, [u32; 3]),
}

impl Prim {
    /// The primitive's vertices.
    pub(crate) fn vertices(&self) -> &[u32] {
        match self {
            Prim::Vertex(v) => std::slice::from_ref(v),
            Prim::Edge(e) => e,
            Prim::Triangle(_, t) => t,
        }
    }

    /// Do the two primitives have a vertex in common?
    pub(crate) fn shares_vertex(&self, other: &Prim) -> bool {
        self.vertices().iter().any(|v| other.vertices().contains(v))
    }
}

/// A proximity pair found at the start of a pass: the two primitives and their distance then.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pair {
    /// Distance between the primitives when found (the sort key).
    pub(crate) distance: f64,
    /// One primitive (the vertex of a vertex–triangle pair).
    pub(crate) a: Prim,
    /// The other primitive.
    pub(crate) b: Prim,
}

impl Merger<'_> {
    /// Every proximity pair of the live mesh once, closest first (ties by the primitives'
    /// indices, so the order is deterministic). Pairs are gathered from the triangle pairs the
    /// broad phase reports within the distance of each other, as `(vertex, vertex)`,
    /// `(vertex, triangle)` and `(edge, edge)`.
    pub(crate) fn proximity_pairs(&self) -> Vec<Pair> {
        let c = &*self.r.c;
        let d = DVec3::splat(self.distance);
        let mut pairs = Vec::new();
        let mut near = Vec::new();
        for t in 0..c.mesh.triangles.len() as u32 {
            if !c.is_live(t) {
                continue;
            }
            let tv = c.triangle(t);
            let (lo, hi) = crate::front::remesh::tri_box(c, t);
            self.r.grid.query(lo - d, hi + d, &mut near);
            for &s in near.iter().filter(|&&s| s > t && c.is_live(s)) {
                // The grid reports whole cells: triangles whose boxes are farther apart than
                // the distance hold no pair.
                let (slo, shi) = crate::front::remesh::tri_box(c, s);
                if (slo - hi).max(lo - shi).max_element() > self.distance * (1.0 + 1e-9) {
                    continue;
                }
                let sv = c.triangle(s);
                let mut candidates = [(Prim::Vertex(0), Prim::Vertex(0)); 24];
                let mut k = 0;
                for (p, q, qv) in [(tv, s, sv), (sv, t, tv)] {
                    for v in p {
                        candidates[k] = (Prim::Vertex(v), Prim::Triangle(q, qv));
                        k += 1;
                    }
                }
                for i in 0..3 {
                    let e = edge(tv[i], tv[(i + 1) % 3]);
                    for j in 0..3 {
                        let f = edge(sv[j], sv[(j + 1) % 3]);
                        let (u, w) = (tv[i].min(sv[j]), tv[i].max(sv[j]));
                        candidates[k] = (Prim::Edge(e.min(f)), Prim::Edge(e.max(f)));
                        candidates[k + 1] = (Prim::Vertex(u), Prim::Vertex(w));
                        k += 2;
                    }
                }
                for (a, b) in candidates {
                    if a.shares_vertex(&b) || self.boxes_apart(&a, &b) {
                        continue;
                    }
                    let (pa, pb) = self.closest_points(&a, &b);
                    let distance = pa.distance(pb);
                    if distance <= self.distance {
                        pairs.push(Pair { distance, a, b });
                    }
                }
            }
        }
        pairs.sort_by_key(|x| (x.a, x.b));
        pairs.dedup_by(|x, y| (x.a, x.b) == (y.a, y.b));
        pairs.sort_by(|x, y| {
            x.distance
                .total_cmp(&y.distance)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        });
        pairs
    }

    /// Are the bounding boxes of `a` and `b` farther apart than the merge distance? Closest
    /// points lie in the boxes, so such primitives are too (the margin covers rounding): a
    /// cheap test that spares most candidates the exact distance (`balls` at 64 with merging,
    /// to t = 0.4 s: the merge stage 10.8 → 8.4 s, the same frames to the bit).
    fn boxes_apart(&self, a: &Prim, b: &Prim) -> bool {
        let bounds = |p: &Prim| {
            p.vertices()
                .iter()
                .map(|&v| self.position(v))
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let ((alo, ahi), (blo, bhi)) = (bounds(a), bounds(b));
        let gap = (blo - ahi).max(alo - bhi).max(DVec3::ZERO);
        gap.length() > self.distance * (1.0 + 1e-9)
    }

    /// Is primitive `p` still in the mesh (vertex used, edge or triangle live)?
    pub(crate) fn exists(&self, p: &Prim) -> bool {
        let c = &*self.r.c;
        match *p {
            Prim::Vertex(v) => !c.vertex_triangles(v).is_empty(),
            Prim::Edge([a, b]) => c.edge_valence(a, b) > 0,
            Prim::Triangle(t, tri) => c.is_live(t) && c.triangle(t) == tri,
        }
    }

    /// Closest points of primitives `a` and `b` (pairs as [`Self::proximity_pairs`] makes
    /// them: a vertex with anything, or two edges).
    pub(crate) fn closest_points(&self, a: &Prim, b: &Prim) -> (DVec3, DVec3) {
        match (a, b) {
            (Prim::Edge([a0, a1]), Prim::Edge([b0, b1])) => {
                let [p0, p1, q0, q1] = [*a0, *a1, *b0, *b1].map(|v| self.position(v));
                let (s, t) = segment_segment_closest(p0, p1, q0, q1);
                (p0 + s * (p1 - p0), q0 + t * (q1 - q0))
            }
            (Prim::Vertex(v), _) => {
                let p = self.position(*v);
                (p, self.closest_to(b, p))
            }
            (_, Prim::Vertex(v)) => {
                let q = self.position(*v);
                (self.closest_to(a, q), q)
            }
            _ => unreachable!("proximity pairs pair a vertex with anything, or two edges"),
        }
    }

    /// The point of primitive `p` closest to `x`.
    pub(crate) fn closest_to(&self, p: &Prim, x: DVec3) -> DVec3 {
        match *p {
            Prim::Vertex(v) => self.position(v),
            Prim::Edge([a, b]) => {
                let (pa, pb) = (self.position(a), self.position(b));
                let (s, _) = segment_segment_closest(pa, pb, x, x);
                pa + s * (pb - pa)
            }
            Prim::Triangle(_, [a, b, c]) => {
                let [pa, pb, pc] = [a, b, c].map(|v| self.position(v));
                let w = point_triangle_closest(x, pa, pb, pc);
                w[0] * pa + w[1] * pb + w[2] * pc
            }
        }
    }

    /// The fold rule of §6.2: components of triangles that share an edge may snap only if the
    /// angle between the triangles is under 90°, which lets folded sheets merge but keeps a
    /// surface from snapping within its own plane. Checked for every triangle holding `a` and
    /// every triangle holding `b` that share an edge: the interior angle is under 90° when the
    /// two apexes, taken perpendicular to the shared edge, point the same way.
    pub(crate) fn fold_allows(&self, a: &Prim, b: &Prim) -> bool {
        let ta = self.holders(a);
        let tb = self.holders(b);
        for &s in &ta {
            let sv = self.r.c.triangle(s);
            for &t in &tb {
                let tv = self.r.c.triangle(t);
                let shared: Vec<u32> = sv.iter().copied().filter(|v| tv.contains(v)).collect();
                let [x, y] = shared[..] else {
                    continue;
                };
                let apex = |tri: [u32; 3]| tri.into_iter().find(|&v| v != x && v != y);
                let (Some(p), Some(q)) = (apex(sv), apex(tv)) else {
                    continue;
                };
                let (px, py) = (self.position(x), self.position(y));
                let axis = (py - px).normalize_or_zero();
                let perp = |v: u32| {
                    let d = self.position(v) - px;
                    d - d.dot(axis) * axis
                };
                if perp(p).dot(perp(q)) <= 0.0 {
                    return false;
                }
            }
        }
        true
    }

    /// Do the two sides face each other across the gap? The fold rule above covers triangles
    /// that share an edge; pairs farther apart along the mesh can still be two sheets of one
    /// junction (Plateau's 120° wedge) or a film standing on a domain wall (90°), which must
    /// not snap. Across a wedge of interior angle θ the gap between two points at equal
    /// distance from its apex makes θ/2 with each sheet's normal, so both sides need a holding
    /// triangle whose normal is within 30° of the gap direction `pb − pa`: only wedges under
    /// 60° close (two surfaces meeting head-on are within a few degrees). Measured on
    /// `mcf_t1`: at 60° vertices beside a 106° junction were snapped across it, hundreds per
    /// frame. Touching points (gap below a billionth of the merge distance) have no direction
    /// and pass.
    pub(crate) fn facing(&self, a: &Prim, b: &Prim, pa: DVec3, pb: DVec3) -> bool {
        let gap = pb - pa;
        if gap.length() <= 1e-9 * self.distance {
            return true;
        }
        let d = gap.normalize();
        let faces = |p: &Prim| {
            self.holders(p).iter().any(|&t| {
                let [x, y, z] = self.r.c.triangle(t).map(|v| self.position(v));
                (y - x).cross(z - x).normalize_or_zero().dot(d).abs() >= FACING
            })
        };
        faces(a) && faces(b)
    }

    /// Does the gap between `pa` (on `a`) and `pb` (on `b`) hold only the phase
    /// [`Merger::across`] allows? Each side's phase toward the other is read off its holding
    /// triangles that face the gap (within the 30° of [`Merger::facing`]): the label on the
    /// side the gap direction points to. Touching points have no gap to read and pass.
    pub(crate) fn gap_allowed(&self, a: &Prim, b: &Prim, pa: DVec3, pb: DVec3) -> bool {
        let Some(phase) = self.across else {
            return true;
        };
        let gap = pb - pa;
        if gap.length() <= 1e-9 * self.distance {
            return true;
        }
        let d = gap.normalize();
        let toward = |p: &Prim, d: DVec3| {
            self.holders(p).into_iter().all(|t| {
                let [x, y, z] = self.r.c.triangle(t).map(|v| self.position(v));
                let along = (y - x).cross(z - x).normalize_or_zero().dot(d);
                let [front, back] = self.r.c.labels(t);
                along.abs() < FACING || phase == if along > 0.0 { front } else { back }
            })
        };
        toward(a, d) && toward(b, -d)
    }

    /// Live triangles containing every vertex of `p`.
    fn holders(&self, p: &Prim) -> Vec<u32> {
        let c = &*self.r.c;
        match *p {
            Prim::Vertex(v) => c.vertex_triangles(v).to_vec(),
            Prim::Edge([a, b]) => {
                let mut out = Vec::new();
                c.edge_triangles(a, b, &mut out);
                out
            }
            Prim::Triangle(t, _) => vec![t],
        }
    }
}

/// Edge `(a, b)` with its ends ascending.
fn edge(a: u32, b: u32) -> [u32; 2] {
    [a.min(b), a.max(b)]
}

/// Cosine of the largest angle between a side's normal and the gap direction (30°).
const FACING: f64 = 0.866;
