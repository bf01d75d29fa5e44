//! Edge flipping toward regular valence (paper 000 Appendix A.1): only manifold, non-feature
//! edges flip; the flipped pair is built with the winding and labels of one reference
//! triangle. A flip is kept when it lowers the squared deviation of the four vertices'
//! valences from the ideal (6 inside a manifold patch, 4 where the patch borders a
//! non-manifold edge or another pair of regions, Eq. 1).
//!
//! Collision safety: the old and the new pair bound the tetrahedron `abcd`; a flip is
//! equivalent to splitting `ab` at its midpoint `m` and moving `m` to the midpoint of `cd`
//! (the four split triangles then cover the flipped pair), so that pseudo-motion is what CCD
//! checks.

use glam::DVec3;

use super::{starting_with, Remesher, Tri};

impl Remesher<'_> {
    /// One pass over all edges in index order.
    pub(super) fn flip_pass(&mut self) {
        for [a, b] in self.c.edges() {
            if self.try_flip(a, b, false) {
                self.stats.flips += 1;
                self.verify_now("flip");
            }
        }
    }

    /// Valence of `v` within the patch of triangles carrying the label set `labels`, and its
    /// ideal value: 6 when every triangle at `v` is in that patch and every edge manifold,
    /// else 4 (non-manifold geometry trimmed off, Appendix A.1).
    fn patch_valence(&self, v: u32, labels: [u16; 2]) -> (i64, i64) {
        let same = |l: [u16; 2]| l == labels || l == [labels[1], labels[0]];
        // Each neighbour with the triangles at `v` it shares within the patch and in all, the
        // latter being the valence of its edge to `v` (the incidence lists hold every live
        // triangle).
        let mut nb: Vec<(u32, u32, u32)> = Vec::with_capacity(16);
        let mut interior = true;
        for &t in self.c.vertex_triangles(v) {
            let in_patch = same(self.c.labels(t)) as u32;
            interior &= in_patch == 1;
            for u in self.c.triangle(t).into_iter().filter(|&u| u != v) {
                match nb.iter_mut().find(|(w, _, _)| *w == u) {
                    Some((_, inside, all)) => {
                        *inside += in_patch;
                        *all += 1;
                    }
                    None => nb.push((u, in_patch, 1)),
                }
            }
        }
        let valence = nb.iter().filter(|&&(_, inside, _)| inside > 0).count() as i64;
        interior &= nb.iter().all(|&(_, _, all)| all == 2);
        (valence, if interior { 6 } else { 4 })
    }

    /// Flips edge `(a, b)` if it is a manifold non-feature edge, the valences improve (or
    /// `force`, in the fail-safe pass), the bounds allow and the flip is collision-safe.
    pub(super) fn try_flip(&mut self, a: u32, b: u32, force: bool) -> bool {
        let mut tris = Vec::with_capacity(4);
        self.c.edge_triangles(a, b, &mut tris);
        let [t1, t2] = tris[..] else {
            return false;
        };
        if self.is_feature_edge(a, b) {
            return false;
        }
        // Reference triangle t1 = [a, b, c] (rename the ends so it traverses a → b).
        let (a, b) = if starting_with(self.c.triangle(t1), a, b).is_some() {
            (a, b)
        } else {
            (b, a)
        };
        let [_, _, c] = starting_with(self.c.triangle(t1), a, b).unwrap_or([a, b, a]);
        let d = self.c.triangle(t2).into_iter().find(|&v| v != a && v != b);
        let Some(d) = d else { return false };
        if c == d || self.c.edge_valence(c, d) != 0 {
            return false;
        }
        let labels = self.c.labels(t1);
        if !force {
            let val = [a, b, c, d].map(|v| self.patch_valence(v, labels));
            let before: i64 = val.iter().map(|(n, o)| (n - o).pow(2)).sum();
            let delta = [-1, -1, 1, 1];
            let after: i64 = val
                .iter()
                .zip(delta)
                .map(|((n, o), dv)| (n + dv - o).pow(2))
                .sum();
            if after >= before {
                return false;
            }
        }
        let pos = |v: u32| self.c.position(v);
        let old = [self.tri(t1), self.tri(t2)];
        let new = [[c, a, d], [c, d, b]].map(|t| Tri {
            p: t.map(pos),
            labels,
        });
        // The new pair must not fold (form a feature edge the old pair lacked), and the new
        // edge must not be one to split.
        let (n1, n2) = (
            new[0].area_normal().normalize_or_zero(),
            new[1].area_normal().normalize_or_zero(),
        );
        let new_length = (self.c.position(c) - self.c.position(d)).length();
        if !force && (n1.dot(n2) < self.b.cos_feature || new_length > self.b.max_edge) {
            self.stats.bound_cancelled += 1;
            return false;
        }
        // Flips only improve connectivity, so they get a hundredth of the volume budget when
        // volumes are kept (a tenth otherwise): on a curved sheet they would erode it step
        // after step. `enright` at edge 0.01 from t = 0 to 0.8: worst liquid −0.10 % with a
        // hundredth, −0.17 % with a tenth; but the refused flips leave worse triangles, and
        // collision handling took 92 s against 55 s (one thread).
        let share = if self.keep_volumes { 0.01 } else { 0.1 };
        if !self.bounds_allow_volume(&old, &new, share * self.b.max_volume_change) {
            return false;
        }
        // Pseudo-motion: split ab at m, move m to the midpoint of cd.
        let mid_ab = 0.5 * (self.c.position(a) + self.c.position(b));
        let mid_cd: DVec3 = 0.5 * (self.c.position(c) + self.c.position(d));
        let old_tris = [self.c.triangle(t1), self.c.triangle(t2)];
        let old_labels = [self.c.labels(t1), self.c.labels(t2)];
        self.remove_triangle(t1);
        self.remove_triangle(t2);
        let m = self.add_vertex(mid_ab);
        let d_tri = starting_with(old_tris[1], b, a)
            .or_else(|| starting_with(old_tris[1], a, b))
            .unwrap_or(old_tris[1]);
        let temp = [
            self.add_triangle([a, m, c], old_labels[0]),
            self.add_triangle([m, b, c], old_labels[0]),
            self.add_triangle([d_tri[0], m, d_tri[2]], old_labels[1]),
            self.add_triangle([m, d_tri[1], d_tri[2]], old_labels[1]),
        ];
        let safe = self.pseudo_motion_is_safe(&[m], &[mid_cd], None);
        for t in temp {
            self.remove_triangle(t);
        }
        if safe {
            self.add_triangle([c, a, d], labels);
            self.add_triangle([c, d, b], labels);
        } else {
            self.add_triangle(old_tris[0], old_labels[0]);
            self.add_triangle(old_tris[1], old_labels[1]);
        }
        safe
    }
}
