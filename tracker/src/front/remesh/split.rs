//! Edge splitting (paper 000 Appendix A.2, Fig. 25): every triangle on the edge, however many
//! (non-manifold edges included), is cut in two at a new vertex on the edge, the children
//! inheriting their parent's labels. The new vertex is the edge midpoint, so the surface does
//! not move and no volume changes (the modified butterfly position is not used).

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
        for (_, [a, b]) in long {
            if self.try_split(a, b) {
                self.stats.splits += 1;
                done += 1;
                self.verify_now("split");
            }
        }
        done
    }

    /// Splits edge `(a, b)` at its midpoint if the bounds allow; `false` if cancelled or the
    /// edge no longer exists.
    pub(super) fn try_split(&mut self, a: u32, b: u32) -> bool {
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
        true
    }
}
