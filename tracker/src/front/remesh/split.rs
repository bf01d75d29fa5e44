//! Edge splitting (paper 000 Appendix A.2, Fig. 25): every triangle on the edge, however many
//! (non-manifold edges included), is cut in two at a new vertex on the edge midpoint, the
//! children inheriting their parent's labels, which moves no surface. With
//! [`FrontParams::butterfly`](crate::front::params::FrontParams::butterfly), on a smooth
//! regular patch the new vertex then moves to the butterfly subdivision point (Dyn, Levin &
//! Gregory 1990), so refinement follows the curved surface instead of its facets; that move is
//! checked like any other (bounds, CCD). Feature, non-manifold and irregular neighbourhoods
//! keep the midpoint (paper 000 treats feature and non-manifold edges as boundaries of the
//! scheme).

use glam::DVec3;

use super::features::Kind;
use super::{starting_with, Remesher, Tri};

impl Remesher<'_> {
    /// Splits edges longer than the maximum length, longest first, repeating while new long
    /// edges remain (at most 8 rounds: each halves the lengths).
    pub(super) fn split_pass(&mut self) {
        for _ in 0..8 {
            if self.split_round() == 0 {
                break;
            }
        }
    }

    /// One round over the edges too long at its start; returns the number of splits.
    fn split_round(&mut self) -> usize {
        let mut done = 0;
        let mut long: Vec<(f64, [u32; 2])> = self
            .c
            .edges()
            .into_iter()
            .map(|[a, b]| ((self.c.position(a) - self.c.position(b)).length(), [a, b]))
            .filter(|(l, _)| *l > self.b.max_edge)
            .collect();
        // Longest first; ties by index, so the order is deterministic.
        long.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        // Butterfly points from the mesh as the round starts, as the subdivision scheme
        // defines them: splitting one edge makes its neighbours' stencils irregular, but moves
        // no surface, so the points stay the smooth surface's.
        let smooth: Vec<Option<DVec3>> = long
            .iter()
            .map(|(_, [a, b])| {
                self.butterfly
                    .then(|| self.butterfly_point(*a, *b))
                    .flatten()
            })
            .collect();
        for ((_, [a, b]), smooth) in long.into_iter().zip(smooth) {
            if self.try_split(a, b, smooth) {
                self.stats.splits += 1;
                done += 1;
                self.verify_now("split");
            }
        }
        done
    }

    /// Splits edge `(a, b)` at its midpoint if the bounds allow, then moves the new vertex to
    /// `smooth` (its butterfly point) if that is allowed too; `false` if cancelled or the edge
    /// no longer exists.
    pub(crate) fn try_split(&mut self, a: u32, b: u32, smooth: Option<DVec3>) -> bool {
        let mut tris = Vec::new();
        self.c.edge_triangles(a, b, &mut tris);
        if tris.is_empty() {
            return false;
        }
        let m_pos = 0.5 * (self.c.position(a) + self.c.position(b));
        // Each parent [u, v, w] with {u, v} = {a, b} becomes [u, m, w] and [m, v, w].
        let rotated: Vec<[u32; 3]> = tris
            .iter()
            .map(|&t| {
                let tri = self.c.triangle(t);
                starting_with(tri, a, b)
                    .or_else(|| starting_with(tri, b, a))
                    .unwrap_or(tri)
            })
            .collect();
        let old: Vec<Tri> = tris.iter().map(|&t| self.tri(t)).collect();
        let mut new = Vec::with_capacity(2 * tris.len());
        for (r, o) in rotated.iter().zip(&old) {
            let [u, v, w] = r.map(|i| self.c.position(i));
            new.push(Tri {
                p: [u, m_pos, w],
                labels: o.labels,
            });
            new.push(Tri {
                p: [m_pos, v, w],
                labels: o.labels,
            });
        }
        if !self.bounds_allow(&old, &new) {
            return false;
        }
        let m = self.add_vertex(m_pos);
        for (&t, [u, v, w]) in tris.iter().zip(rotated) {
            let labels = self.c.labels(t);
            self.remove_triangle(t);
            self.add_triangle([u, m, w], labels);
            self.add_triangle([m, v, w], labels);
        }
        if let Some(p) = smooth {
            // Edges to the apexes may still be too long here (later rounds split them), and
            // may lengthen by the butterfly offset; none may pass the parents' longest edge.
            let longest = old
                .iter()
                .flat_map(|t| [(t.p[0], t.p[1]), (t.p[1], t.p[2]), (t.p[2], t.p[0])])
                .map(|(x, y)| (x - y).length())
                .fold(0.0, f64::max);
            self.try_move(m, p, longest);
        }
        true
    }

    /// The butterfly point of edge `(a, b)`: ½(a + b) + ⅛(c + d) − 1/16 Σ wings, with `c`,
    /// `d` the apexes of its two triangles and the wings the apexes across their four outer
    /// edges. `None` unless the whole stencil is one smooth manifold patch between the same two
    /// phases and `a`, `b` have valence 6 (the regular case, where the scheme is C¹).
    fn butterfly_point(&self, a: u32, b: u32) -> Option<DVec3> {
        let mut tris = Vec::with_capacity(2);
        self.c.edge_triangles(a, b, &mut tris);
        let [t1, t2] = tris[..] else {
            return None;
        };
        let labels = sorted(self.c.labels(t1));
        let regular = |v: u32| {
            let f = self.vertex_features(v);
            f.kind == Kind::Smooth && !f.non_manifold && self.c.neighbours(v).len() == 6
        };
        if sorted(self.c.labels(t2)) != labels || !regular(a) || !regular(b) {
            return None;
        }
        let apex =
            |t: u32, u: u32, v: u32| self.c.triangle(t).into_iter().find(|&x| x != u && x != v);
        let (c, d) = (apex(t1, a, b)?, apex(t2, a, b)?);
        // The triangle across outer edge (u, v) of triangle t, and its apex.
        let wing = |t: u32, u: u32, v: u32| -> Option<u32> {
            let mut across = Vec::with_capacity(2);
            self.c.edge_triangles(u, v, &mut across);
            let [s1, s2] = across[..] else {
                return None;
            };
            let s = if s1 == t { s2 } else { s1 };
            (sorted(self.c.labels(s)) == labels && !self.is_feature_edge(u, v))
                .then(|| apex(s, u, v))
                .flatten()
        };
        let wings = [
            wing(t1, a, c)?,
            wing(t1, b, c)?,
            wing(t2, a, d)?,
            wing(t2, b, d)?,
        ];
        let p = |v: u32| self.c.position(v);
        let sum_wings: DVec3 = wings.iter().map(|&w| p(w)).sum();
        let mid = 0.5 * (p(a) + p(b));
        let point = mid + 0.125 * (p(c) + p(d)) - sum_wings / 16.0;
        // On a surface resolved by its edges the offset is a sagitta, L²/8R; an offset above a
        // tenth of the edge means a curvature radius near L (a sheet folding within a few
        // edges), where the scheme overshoots: keep the midpoint there.
        ((point - mid).length() <= 0.1 * (p(a) - p(b)).length()).then_some(point)
    }
}

/// A label pair in ascending order, to compare sides regardless of orientation.
fn sorted(l: [u16; 2]) -> [u16; 2] {
    [l[0].min(l[1]), l[0].max(l[1])]
}
