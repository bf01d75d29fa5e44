//! Collision safety of the second pseudo-motion of a vertex separation (paper 000 §5.1.8):
//! after `v` has moved to `vb` (checked by CCD), `va` leaves `vb` carrying the triangles of
//! region A, and the gap triangles `va vb w` are the sweeps of the edges `vb w`. Its elements
//! start on `vb`, trivially touching what they leave, so CCD cannot judge it; instead the final
//! state is checked statically and the swept volumes are checked for tunnelling.

use std::cmp::Ordering;

use glam::DVec3;

use super::plan::Plan;
use crate::front::intersection::pair_intersects;
use crate::front::predicates::{orient3d, point_in_triangle, segment_triangle};
use crate::front::remesh::Remesher;

impl Plan {
    /// Is the separation just applied to `r` (new vertex `va`, A's triangles re-attached as
    /// `moved`) free of collisions? Three exact tests, any failure cancels:
    /// 1. every triangle at `va` (A's and the gap triangles) in its final position against
    ///    every live triangle near it, by the exact shared-vertex-aware pair test of the
    ///    intersection checker (this covers the paper's "final triangles incident on A
    ///    against all mesh edges, and final edges incident on A against all mesh triangles");
    /// 2. tunnelling (§5.1.8): no mesh vertex in the closed tetrahedron `vb va p q` swept by
    ///    each moved triangle `va p q`;
    /// 3. no mesh edge through a side `vb va w` of those tetrahedra, swept by the edge `va w`
    ///    (an edge can cross a swept tetrahedron with no vertex inside it, through two of its
    ///    sides; where a gap triangle fills the side, test 1 already covers it). This test is
    ///    ours, not the paper's: without it a thin sheet could be swept through.
    pub(super) fn second_motion_is_safe(&self, r: &Remesher, va: u32, moved: &[u32]) -> bool {
        let c = &*r.c;
        let mut near = Vec::new();
        let mut at_va = c.vertex_triangles(va).to_vec();
        at_va.sort_unstable();
        for &t in &at_va {
            let (lo, hi) = crate::front::remesh::tri_box(c, t);
            r.grid.query(lo, hi, &mut near);
            if near
                .iter()
                .any(|&s| s != t && c.is_live(s) && pair_intersects(&c.mesh, s, t))
            {
                return false;
            }
        }
        let (pa, pb) = (self.pa, self.pb);
        for &t in moved {
            let others: Vec<u32> = c.triangle(t).into_iter().filter(|&u| u != va).collect();
            let [p, q] = others[..] else {
                return false;
            };
            let tet = [pb, pa, c.position(p), c.position(q)];
            let lo = tet.iter().fold(DVec3::INFINITY, |m, x| m.min(*x));
            let hi = tet.iter().fold(DVec3::NEG_INFINITY, |m, x| m.max(*x));
            r.grid.query(lo, hi, &mut near);
            let skip = [va, self.v, p, q];
            let inside = near
                .iter()
                .filter(|&&s| c.is_live(s))
                .flat_map(|&s| c.triangle(s))
                .filter(|u| !skip.contains(u))
                .any(|u| in_closed_tet(tet, c.position(u)));
            if inside {
                return false;
            }
            for w in [p, q] {
                let side = [pb, pa, c.position(w)];
                let lo = side.iter().fold(DVec3::INFINITY, |m, x| m.min(*x));
                let hi = side.iter().fold(DVec3::NEG_INFINITY, |m, x| m.max(*x));
                r.grid.query(lo, hi, &mut near);
                let skip = [va, self.v, w];
                let crossed = near.iter().filter(|&&s| c.is_live(s)).any(|&s| {
                    let tri = c.triangle(s);
                    (0..3).any(|k| {
                        let (e0, e1) = (tri[k], tri[(k + 1) % 3]);
                        !skip.contains(&e0)
                            && !skip.contains(&e1)
                            && segment_triangle(
                                c.position(e0),
                                c.position(e1),
                                side[0],
                                side[1],
                                side[2],
                            )
                    })
                });
                if crossed {
                    return false;
                }
            }
        }
        true
    }
}

/// Does `x` lie in the closed tetrahedron `t` (exact)? A flat tetrahedron (a triangle moving
/// in its own plane) sweeps the union of its four faces.
fn in_closed_tet(t: [DVec3; 4], x: DVec3) -> bool {
    let whole = orient3d(t[0], t[1], t[2], t[3]);
    if whole == Ordering::Equal {
        return (0..4).any(|k| point_in_triangle(x, t[k], t[(k + 1) % 4], t[(k + 2) % 4]));
    }
    // `x` is inside when, replacing each corner by `x` in turn, no orientation flips sign.
    (0..4).all(|k| {
        let mut s = t;
        s[k] = x;
        orient3d(s[0], s[1], s[2], s[3]) != whole.reverse()
    })
}
