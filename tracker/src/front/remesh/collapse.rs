//! Edge collapsing (paper 000 Appendix A.2): the triangles on the edge vanish, one endpoint is
//! removed and its triangles are re-attached to the other, with no relabeling. The position
//! kept follows the feature priority (peak > ridge > smooth, then non-manifold > manifold);
//! equal vertices meet at the midpoint; either is then moved to keep every phase's volume
//! (`volume.rs`, issue 12). Checked as the pseudo-motion of both endpoints to the final
//! position with the vanishing triangles left out.

use glam::DVec3;

use super::features::Kind;
use super::volume::volume_preserving;
use super::{Remesher, Tri};
use crate::front::connectivity::DEAD;

/// Edges shorter than this fraction of the collapse bound collapse even between two features
/// or corners: at that size a "feature" is noise. The contoured start puts clusters of such
/// edges (about `MARGIN` = 1e-3 of its spacing) around every grid node a surface passes
/// through exactly, which the feature rule and the area bound otherwise kept for the whole run
/// (`enright` at edge 0.01: 729 edges under 0.01 L at t = 0.3, 15 with this rule and the area
/// exception of [`FrontParams::min_area`]; at 0.1 instead of 0.01 the 32³ full period came back
/// 0.90 h off instead of 0.63 h).
///
/// [`FrontParams::min_area`]: crate::front::params::FrontParams::min_area
const TINY_EDGE: f64 = 0.01;

impl Remesher<'_> {
    /// Collapses edges shorter than the minimum length, shortest first, repeating while that
    /// makes progress (at most 4 rounds).
    pub(super) fn collapse_pass(&mut self) {
        for _ in 0..4 {
            if self.collapse_round() == 0 {
                break;
            }
        }
    }

    /// One round over the edges too short at its start; returns the number of collapses.
    fn collapse_round(&mut self) -> usize {
        let mut done = 0;
        let mut short: Vec<(f64, [u32; 2])> = self
            .c
            .edges()
            .into_iter()
            .map(|[a, b]| ((self.c.position(a) - self.c.position(b)).length(), [a, b]))
            .filter(|(l, _)| *l < self.b.min_edge)
            .collect();
        short.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        for (_, [a, b]) in short {
            let l = (self.c.position(a) - self.c.position(b)).length();
            if l < self.b.min_edge && self.try_collapse(a, b) {
                self.stats.collapses += 1;
                done += 1;
                self.verify_now("collapse");
            }
        }
        done
    }

    /// Where edge `(a, b)` collapses to: `(kept vertex, removed vertex, position)`, or `None`
    /// when the collapse would merge two different features (both endpoints on features or
    /// non-manifold curves, joined by an ordinary edge). The fail-safe pass allows it, and so
    /// does a junction collapse ([`Remesher::junction`], paper 000 §5.1.7).
    pub(crate) fn collapse_target(&self, a: u32, b: u32) -> Option<(u32, u32, DVec3)> {
        let (va, vb) = (self.vertex_features(a), self.vertex_features(b));
        let (pa, pb) = (self.c.position(a), self.c.position(b));
        match va.rank().cmp(&vb.rank()) {
            std::cmp::Ordering::Greater => Some((a, b, pa)),
            std::cmp::Ordering::Less => Some((b, a, pb)),
            std::cmp::Ordering::Equal => {
                let joined = va.feature_neighbours.contains(&b);
                let separate_features = (va.kind != Kind::Smooth || va.non_manifold) && !joined;
                let tiny = (pa - pb).length() < TINY_EDGE * self.b.min_edge;
                if separate_features && !self.failsafe && !self.junction && !tiny {
                    None
                } else if va.kind == Kind::Peak && !self.failsafe && !tiny {
                    // Two corners: either position destroys one of them.
                    None
                } else {
                    Some((a, b, 0.5 * (pa + pb)))
                }
            }
        }
    }

    /// Collapses edge `(a, b)` if it is topologically valid, within bounds and collision-safe.
    pub(crate) fn try_collapse(&mut self, a: u32, b: u32) -> bool {
        let Some((keep, gone, p)) = self.collapse_target(a, b) else {
            self.stats.bound_cancelled += 1;
            return false;
        };
        self.try_collapse_to(keep, gone, p)
    }

    /// Collapses edge `(keep, gone)` into `keep` placed at `p` (moved on to keep volumes, as
    /// in [`Self::try_collapse`]) if it is topologically valid, within bounds and
    /// collision-safe.
    pub(crate) fn try_collapse_to(&mut self, keep: u32, gone: u32, p: DVec3) -> bool {
        let mut edge_tris = Vec::new();
        self.c.edge_triangles(keep, gone, &mut edge_tris);
        if edge_tris.is_empty() {
            return false;
        }
        // Link condition: the only vertices adjacent to both ends are the apexes of the
        // triangles on the edge (waived for a vanishing region, [`Remesher::coincident`]).
        let apexes: Vec<u32> = {
            let mut v: Vec<u32> = edge_tris
                .iter()
                .flat_map(|&t| self.c.triangle(t))
                .filter(|&v| v != keep && v != gone)
                .collect();
            v.sort_unstable();
            v.dedup();
            v
        };
        let nk = self.c.neighbours(keep);
        let ng = self.c.neighbours(gone);
        if !self.coincident
            && nk.iter().any(|v| {
                *v != gone && ng.binary_search(v).is_ok() && apexes.binary_search(v).is_err()
            })
        {
            return false;
        }
        // Surviving triangles with `gone` renamed `keep`; none may duplicate another unless
        // the caller resolves coincident pairs.
        let moved: Vec<u32> = self
            .c
            .vertex_triangles(gone)
            .iter()
            .copied()
            .filter(|t| !edge_tris.contains(t))
            .collect();
        let renamed: Vec<[u32; 3]> = moved
            .iter()
            .map(|&t| self.c.triangle(t).map(|v| if v == gone { keep } else { v }))
            .collect();
        let mut keys: Vec<[u32; 3]> = self
            .c
            .vertex_triangles(keep)
            .iter()
            .filter(|t| !edge_tris.contains(t))
            .map(|&t| self.c.triangle(t))
            .chain(renamed.iter().copied())
            .map(|mut t| {
                t.sort_unstable();
                t
            })
            .collect();
        keys.sort_unstable();
        if !self.coincident && keys.windows(2).any(|w| w[0] == w[1]) {
            return false;
        }
        // Geometry before and after: every triangle around either end.
        let after: Vec<(u32, [u32; 3])> = self
            .c
            .vertex_triangles(keep)
            .iter()
            .filter(|t| !edge_tris.contains(t))
            .map(|&t| (t, self.c.triangle(t)))
            .chain(moved.iter().copied().zip(renamed.iter().copied()))
            .collect();
        let old: Vec<Tri> = edge_tris
            .iter()
            .chain(after.iter().map(|(t, _)| t))
            .map(|&t| self.tri(t))
            .collect();
        let new_at = |p: DVec3| -> Vec<Tri> {
            after
                .iter()
                .map(|&(t, tri)| Tri {
                    p: tri.map(|v| if v == keep { p } else { self.c.position(v) }),
                    labels: self.c.labels(t),
                })
                .collect()
        };
        // The kept vertex then moves to the nearest position where no phase's volume
        // changes, a feature vertex too (by a fraction of the edge at most): plain
        // positions lost 2–5 % of each liquid over `enright`'s period at 32³, most of it here.
        // Topology changes (a T1's junction collapse, a T2 shrinking its region away), the
        // fail-safe and remeshing that was asked not to ([`super::improve`]) keep their plain
        // positions.
        let p = if !self.keep_volumes || self.junction || self.coincident || self.failsafe {
            p
        } else {
            let length = (self.c.position(keep) - self.c.position(gone)).length();
            volume_preserving(&old, &new_at, p, length)
        };
        let new = new_at(p);
        // No triangle may turn over.
        if old[edge_tris.len()..]
            .iter()
            .zip(&new)
            .any(|(before, after)| before.area_normal().dot(after.area_normal()) <= 0.0)
        {
            self.stats.bound_cancelled += 1;
            return false;
        }
        if !self.failsafe {
            let too_long = nk
                .iter()
                .chain(&ng)
                .filter(|&&v| v != keep && v != gone)
                .any(|&v| (self.c.position(v) - p).length() > self.b.max_edge);
            if too_long {
                self.stats.bound_cancelled += 1;
                return false;
            }
        }
        if !self.bounds_allow(&old, &new) {
            return false;
        }
        if !self.end_state_checked && !self.safe_pseudo_collapse(&edge_tris, keep, gone, p) {
            return false;
        }
        for &t in &edge_tris {
            self.remove_triangle(t);
        }
        for (&t, tri) in moved.iter().zip(renamed) {
            let labels = self.c.labels(t);
            self.remove_triangle(t);
            self.add_triangle(tri, labels);
        }
        self.move_vertex(keep, p);
        true
    }

    /// Is the pseudo-motion of `keep` and `gone` to `p` collision-free, with the triangles
    /// `edge_tris` on the edge (which vanish) hidden from the check?
    fn safe_pseudo_collapse(&mut self, edge_tris: &[u32], keep: u32, gone: u32, p: DVec3) -> bool {
        let hidden: Vec<[u32; 3]> = edge_tris.iter().map(|&t| self.c.triangle(t)).collect();
        for &t in edge_tris {
            self.grid.remove(t);
            self.c.mesh.triangles[t as usize] = DEAD;
        }
        let safe = self.pseudo_motion_is_safe(&[keep, gone], &[p, p], Some([keep, gone]));
        for (&t, &tri) in edge_tris.iter().zip(&hidden) {
            self.c.mesh.triangles[t as usize] = tri;
            let (lo, hi) = super::tri_box(self.c, t);
            self.grid.insert(t, lo, hi);
        }
        safe
    }
}
