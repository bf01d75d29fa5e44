//! One proposed vertex separation (paper 000 §5.1.4, §5.1.6): which triangles follow `va`,
//! the separation direction, the new positions and the gap-filling triangles with their
//! labels, computed without touching the mesh so that it can be scored first; then performed
//! atomically ([`Plan::perform`]).

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use super::SeparationStrength;
use crate::front::connectivity::Connectivity;
use crate::front::remesh::Remesher;

/// A separation of vertex `v` with region `a` going to the new vertex `va`.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    /// The irregular vertex; it stays as `vb`.
    pub v: u32,
    /// Unit separation direction, from region B's one-ring centroid toward region A's.
    pub d: DVec3,
    /// Offset ε: `va = v + ε d`, `vb = v − ε d`.
    pub eps: f64,
    /// Position of the new vertex `va`, `v + ε d`.
    pub pa: DVec3,
    /// Position `v` moves to as `vb`, `v − ε d`.
    pub pb: DVec3,
    /// Triangles around `v` incident to region A (they move to `va`), sorted.
    pub to_a: Vec<u32>,
    /// The other triangles around `v` (they stay on `v`, which becomes `vb`), sorted.
    pub to_b: Vec<u32>,
    /// Gap triangles `[va, vb, w]` as `(w, [front, back])`, sorted by `w`.
    pub fills: Vec<(u32, [PhaseId; 2])>,
}

impl Plan {
    /// The separation of missing arc {`a`, `b`} at `v` with `a`'s triangles on `va`, offset
    /// `eps`; `None` when it is not well defined: no triangle on one side, coinciding one-ring
    /// centroids, a domain wall at `v` that is not flat, or an opened edge `vw` where region A
    /// is not a single wedge of exactly two triangles (the paper's rule of §5.1.4 names "the
    /// two triangles incident on the edge vw and the region A"; other cases are left alone).
    pub fn new(c: &Connectivity, v: u32, a: PhaseId, b: PhaseId, eps: f64) -> Option<Plan> {
        let mut tris = c.vertex_triangles(v).to_vec();
        tris.sort_unstable();
        let (to_a, to_b): (Vec<u32>, Vec<u32>) =
            tris.iter().partition(|&&t| c.labels(t).contains(&a));
        if to_a.is_empty() || to_b.is_empty() {
            return None;
        }
        let d = direction(c, v, a, b)?;
        let p = c.position(v);
        let (pa, pb) = (p + eps * d, p - eps * d);
        let mut fills = Vec::new();
        let mut ring: Vec<u32> = to_a
            .iter()
            .flat_map(|&t| c.triangle(t))
            .filter(|&w| w != v)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        let mut edge = Vec::new();
        for w in ring {
            c.edge_triangles(v, w, &mut edge);
            edge.sort_unstable();
            let on_a: Vec<u32> = edge
                .iter()
                .copied()
                .filter(|&t| c.labels(t).contains(&a))
                .collect();
            if on_a.len() == edge.len() {
                // The whole edge follows `va`; nothing opens.
                continue;
            }
            let [t1, t2] = on_a[..] else {
                return None;
            };
            fills.extend(fill(c, v, w, a, t1, t2)?.map(|l| (w, l)));
        }
        Some(Plan {
            v,
            d,
            eps,
            pa,
            pb,
            to_a,
            to_b,
            fills,
        })
    }

    /// Separation strength of this plan (§5.1.6, see [`SeparationStrength`]).
    pub fn strength(&self, c: &Connectivity, s: &SeparationStrength) -> f64 {
        match s {
            SeparationStrength::Velocity(field, time) => {
                let p = c.position(self.v);
                let du = (field.velocity(p + self.eps * self.d, *time)
                    - field.velocity(p - self.eps * self.d, *time))
                    / (2.0 * self.eps);
                du.dot(self.d)
            }
            SeparationStrength::AreaDecrease => {
                let before: f64 = self
                    .to_a
                    .iter()
                    .chain(&self.to_b)
                    .map(|&t| tri_area(c.triangle(t).map(|u| c.position(u))))
                    .sum();
                let after: f64 = self.new_triangles(c).iter().map(|p| tri_area(*p)).sum();
                before - after
            }
        }
    }

    /// Corner positions after the separation of every triangle it moves or creates: the
    /// triangles of A at `va`, the others at `vb`, then the gap triangles (in `fills` order).
    pub fn new_triangles(&self, c: &Connectivity) -> Vec<[DVec3; 3]> {
        let moved = |t: u32, q: DVec3| {
            c.triangle(t)
                .map(|u| if u == self.v { q } else { c.position(u) })
        };
        self.to_a
            .iter()
            .map(|&t| moved(t, self.pa))
            .chain(self.to_b.iter().map(|&t| moved(t, self.pb)))
            .chain(
                self.fills
                    .iter()
                    .map(|&(w, _)| [self.pa, self.pb, c.position(w)]),
            )
            .collect()
    }

    /// Performs the separation if no triangle it moves or creates is degenerate and it is
    /// collision-safe (§5.1.8, [`super::safety`]); otherwise leaves the mesh as it was (an
    /// unused vertex aside, removed by compaction). Returns whether it was performed.
    pub fn perform(&self, r: &mut Remesher) -> bool {
        if self
            .new_triangles(r.c)
            .iter()
            .any(|p| tri_area(*p).is_nan() || tri_area(*p) <= 0.0)
        {
            r.stats.bound_cancelled += 1;
            return false;
        }
        // First pseudo-motion: `v` (all its triangles) to `vb`, by CCD.
        if !r.pseudo_motion_is_safe(&[self.v], &[self.pb], None) {
            return false;
        }
        let p0 = r.c.position(self.v);
        let va = r.add_vertex(self.pa);
        let removed: Vec<([u32; 3], [PhaseId; 2])> = self
            .to_a
            .iter()
            .map(|&t| (r.c.triangle(t), r.c.labels(t)))
            .collect();
        let mut added = Vec::with_capacity(removed.len() + self.fills.len());
        for &t in &self.to_a {
            r.remove_triangle(t);
        }
        for &(tri, labels) in &removed {
            let tri = tri.map(|u| if u == self.v { va } else { u });
            added.push(r.add_triangle(tri, labels));
        }
        let n_moved = added.len();
        for &(w, labels) in &self.fills {
            added.push(r.add_triangle([va, self.v, w], labels));
        }
        r.move_vertex(self.v, self.pb);
        // Second pseudo-motion: `va` from `vb` to its place, checked statically (§5.1.8).
        if self.second_motion_is_safe(r, va, &added[..n_moved]) {
            return true;
        }
        r.stats.unsafe_cancelled += 1;
        for t in added {
            r.remove_triangle(t);
        }
        for (tri, labels) in removed {
            r.add_triangle(tri, labels);
        }
        r.move_vertex(self.v, p0);
        false
    }
}

/// The separation direction of §5.1.6: the unit vector from the centroid of `v`'s one-ring
/// vertices incident to region `b` to that of those incident to region `a` (incident through
/// a triangle around `v`). Where `v` lies on the domain wall, the direction is projected onto
/// the wall's plane so that the wall keeps its shape (exactly for an axis-aligned wall); `None`
/// if the wall triangles at `v` are not coplanar (an edge or corner of the domain) or the
/// direction vanishes.
fn direction(c: &Connectivity, v: u32, a: PhaseId, b: PhaseId) -> Option<DVec3> {
    let centroid = |phase: PhaseId| {
        let mut ring: Vec<u32> = c
            .vertex_triangles(v)
            .iter()
            .filter(|&&t| c.labels(t).contains(&phase))
            .flat_map(|&t| c.triangle(t))
            .filter(|&w| w != v)
            .collect();
        ring.sort_unstable();
        ring.dedup();
        ring.iter().map(|&w| c.position(w)).sum::<DVec3>() / ring.len().max(1) as f64
    };
    let mut d = centroid(a) - centroid(b);
    let mut walls = c
        .vertex_triangles(v)
        .iter()
        .filter(|&&t| c.labels(t).contains(&OUTSIDE))
        .map(|&t| c.mesh.normal(t as usize));
    if let Some(n) = walls.next() {
        // Unit normals of a flat wall agree up to sign and rounding (1e-9 is far above the
        // rounding of a normalised cross product and far below any real fold).
        if walls.any(|m| m.cross(n).length() > 1e-9) {
            return None;
        }
        d -= d.dot(n) * n;
        // Exact zeros for an axis-aligned wall: drop the rounding left along its normal.
        for k in 0..3 {
            if n[k] == 0.0 {
                continue;
            }
            if n[(k + 1) % 3] == 0.0 && n[(k + 2) % 3] == 0.0 {
                d[k] = 0.0;
            }
        }
    }
    let len = d.length();
    (len > 0.0 && len.is_finite()).then(|| d / len)
}

/// The gap triangle `[va, vb, w]` opened at edge `vw` (§5.1.4): `Some(Some(labels))` with its
/// `[front, back]`, `Some(None)` when the regions beside A agree (no triangle needed, it would
/// have the same phase on both sides), `None` when the two triangles disagree on the
/// orientation (an inconsistent mesh; the plan is refused). `t1`, `t2`: the two triangles of
/// the edge bordering region `a`; `x`, `y` their labels outside A. Derivation (the paper
/// says only "with proper labels"): around the edge `va w` the new triangle lies between `t1`
/// (A|X) and `t2` (Y|A), so region X is bounded there by `t1` and the new triangle, which must
/// traverse the edge in opposite directions when both are oriented with X behind them (the
/// closure rule of [`crate::invariants::check`]). `[va, vb, w]` traverses it from `w` to `va`,
/// so X is its back exactly when `t1`, oriented with X behind, runs from `v` to `w`; Y's side
/// through `t2` gives the complementary answer on a consistent mesh.
fn fill(
    c: &Connectivity,
    v: u32,
    w: u32,
    a: PhaseId,
    t1: u32,
    t2: u32,
) -> Option<Option<[PhaseId; 2]>> {
    // For triangle `t` bordering A: its other label, and whether, oriented with that label
    // behind it, it runs from `v` to `w`.
    let side = |t: u32| {
        let [f, b] = c.labels(t);
        let tri = c.triangle(t);
        let forward = (0..3).any(|k| tri[k] == v && tri[(k + 1) % 3] == w);
        // The winding has the back label behind it; reversed when the label is in front.
        if b == a {
            (f, !forward)
        } else {
            (b, forward)
        }
    };
    let (x, x_back) = side(t1);
    let (y, y_back) = side(t2);
    if x == y {
        return Some(None);
    }
    if x_back == y_back {
        return None;
    }
    Some(Some(if x_back { [y, x] } else { [x, y] }))
}

/// Area of the triangle with corners `p`.
fn tri_area(p: [DVec3; 3]) -> f64 {
    0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
}
