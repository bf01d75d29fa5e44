//! The vertex snap of merging (paper 000 §6.2): two vertices that share no edge become one at
//! their average position, the triangles of one re-attached to the other with no relabeling,
//! like an edge collapse without a vanishing edge. Checked as the pseudo-motion of both
//! vertices to the average, treated as one vertex by the collision check, and against the
//! quality bounds of mesh improvement; a snap can only leave coincident triangle pairs behind
//! as degeneracies, which §5.2 removes.

use super::proximity::Prim;
use super::Merger;
use crate::front::remesh::Tri;

impl Merger<'_> {
    /// Snaps vertices `u` and `w` into the lower-indexed one if they share no edge, satisfy
    /// the fold rule, turn no triangle over, lengthen no edge past the maximum (unless it was
    /// longer already), create no angle or area outside the bounds and collide with nothing on
    /// the way. `false` (mesh untouched) otherwise.
    pub(crate) fn try_snap(&mut self, u: u32, w: u32) -> bool {
        let c = &*self.r.c;
        if u == w || c.vertex_triangles(u).is_empty() || c.vertex_triangles(w).is_empty() {
            return false;
        }
        let (keep, gone) = (u.min(w), u.max(w));
        let neighbours = [c.neighbours(keep), c.neighbours(gone)];
        if neighbours[0].binary_search(&gone).is_ok()
            || !self.fold_allows(&Prim::Vertex(keep), &Prim::Vertex(gone))
        {
            return false;
        }
        let p = 0.5 * (self.position(keep) + self.position(gone));
        let around: Vec<u32> = c
            .vertex_triangles(keep)
            .iter()
            .chain(c.vertex_triangles(gone))
            .copied()
            .collect();
        let old: Vec<Tri> = around.iter().map(|&t| self.r.tri(t)).collect();
        let new: Vec<Tri> = around
            .iter()
            .zip(&old)
            .map(|(&t, before)| Tri {
                p: c.triangle(t).map(|v| {
                    if v == keep || v == gone {
                        p
                    } else {
                        self.position(v)
                    }
                }),
                labels: before.labels,
            })
            .collect();
        let turned = old
            .iter()
            .zip(&new)
            .any(|(o, n)| o.area_normal().dot(n.area_normal()) <= 0.0);
        let too_long = [keep, gone].iter().zip(&neighbours).any(|(&v, ns)| {
            ns.iter().any(|&n| {
                let q = self.position(n);
                q.distance(p) > self.r.b.max_edge.max(q.distance(self.position(v)))
            })
        });
        if turned || too_long {
            self.r.stats.bound_cancelled += 1;
            return false;
        }
        // Merging closes the gap between the surfaces, a volume change bounded by the area
        // around the two vertices times half their distance (below the merge distance): it is
        // the purpose of the operation, so only the angle and area bounds apply.
        if !self.r.bounds_allow_volume(&old, &new, f64::INFINITY)
            || !self
                .r
                .pseudo_motion_is_safe(&[keep, gone], &[p, p], Some([keep, gone]))
        {
            return false;
        }
        let moved: Vec<u32> = self.r.c.vertex_triangles(gone).to_vec();
        for t in moved {
            let tri = self
                .r
                .c
                .triangle(t)
                .map(|v| if v == gone { keep } else { v });
            let labels = self.r.c.labels(t);
            self.r.remove_triangle(t);
            self.r.add_triangle(tri, labels);
        }
        self.r.move_vertex(keep, p);
        true
    }
}
