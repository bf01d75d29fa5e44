//! Collision check of a remeshing pseudo-motion (Brochu & Bridson 2009, cited in paper 000
//! §4.2 and Appendix A): the vertices `moving` go linearly from their positions to `x1`, and
//! every vertex–triangle and edge–edge pair with at least one moving primitive is tested by
//! exact CCD against the live triangles the broad phase finds near the swept boxes. Pairs
//! sharing a vertex are skipped (they touch by construction), and so are pairs joining the
//! two ends of an edge being collapsed, which meet on purpose.

use glam::DVec3;

use super::Remesher;
use crate::front::ccd::{boxes_overlap, edge_edge, vertex_triangle};

impl Remesher<'_> {
    /// Is the motion of `moving` to `targets` collision-free? `merging`: the two ends of a
    /// collapsing edge, treated as one vertex. Counts a cancellation when it is not.
    pub(crate) fn pseudo_motion_is_safe(
        &mut self,
        moving: &[u32],
        targets: &[DVec3],
        merging: Option<[u32; 2]>,
    ) -> bool {
        for (&v, &p) in moving.iter().zip(targets) {
            self.x1[v as usize] = p;
        }
        let safe = self.check_motion(moving, merging);
        for &v in moving {
            self.x1[v as usize] = self.c.position(v);
        }
        if !safe {
            self.stats.unsafe_cancelled += 1;
        }
        safe
    }

    /// Tests each primitive pair with a moving vertex once: moving vertices against every
    /// nearby triangle, nearby still vertices against the moving triangles, and moving edges
    /// against every nearby edge (a pair of triangles holds up to 15 such pairs, and a fan
    /// around one moving vertex would test that vertex once per fan triangle).
    fn check_motion(&self, moving: &[u32], merging: Option<[u32; 2]>) -> bool {
        let alias = |v: u32| match merging {
            Some([a, b]) if v == b => a,
            _ => v,
        };
        let moves = |v: u32| moving.contains(&v);
        let x0 = &self.c.mesh.vertices;
        let x1 = &self.x1;
        let swept = |v: u32| {
            let (p, q) = (x0[v as usize], x1[v as usize]);
            (p.min(q), p.max(q))
        };
        let union = |a: (DVec3, DVec3), b: (DVec3, DVec3)| (a.0.min(b.0), a.1.max(b.1));
        let swept_of = |vs: &[u32]| {
            vs.iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |b, &v| {
                    union(b, swept(v))
                })
        };
        let mut tris: Vec<u32> = moving
            .iter()
            .flat_map(|&v| self.c.vertex_triangles(v).iter().copied())
            .filter(|&t| self.c.is_live(t))
            .collect();
        tris.sort_unstable();
        tris.dedup();
        // Candidates: everything near the union of the swept boxes, moving triangles included
        // (their start boxes lie inside it), so moving–moving pairs are tested too.
        let (lo, hi) = tris
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |b, &t| {
                union(b, swept_of(&self.c.triangle(t)))
            });
        let mut near = Vec::new();
        self.grid.query(lo, hi, &mut near);
        near.retain(|&s| self.c.is_live(s));
        let overlap = |a: (DVec3, DVec3), b: (DVec3, DVec3)| boxes_overlap(a.0, a.1, b.0, b.1);
        let vertex_hits = |v: u32, tri: [u32; 3]| {
            let ids = [v, tri[0], tri[1], tri[2]];
            vertex_triangle(&ids.map(|i| x0[i as usize]), &ids.map(|i| x1[i as usize]))
        };
        // Each nearby triangle's corners and swept box (two disjoint boxes never meet).
        let candidates: Vec<([u32; 3], (DVec3, DVec3))> = near
            .iter()
            .map(|&s| {
                let sv = self.c.triangle(s);
                (sv, swept_of(&sv))
            })
            .collect();
        // Moving vertices against every nearby triangle.
        for &v in moving {
            let (va, vb) = (alias(v), swept(v));
            for &(sv, sb) in &candidates {
                if !sv.map(alias).contains(&va) && overlap(vb, sb) && vertex_hits(v, sv) {
                    return false;
                }
            }
        }
        // Still vertices near the moving triangles against them.
        let mut still: Vec<u32> = candidates
            .iter()
            .flat_map(|(sv, _)| sv.iter().copied())
            .filter(|&u| !moves(u))
            .collect();
        still.sort_unstable();
        still.dedup();
        for &t in &tris {
            let tv = self.c.triangle(t);
            let (tb, ta) = (swept_of(&tv), tv.map(alias));
            for &u in &still {
                if !ta.contains(&alias(u)) && overlap(swept(u), tb) && vertex_hits(u, tv) {
                    return false;
                }
            }
        }
        // Moving edges against every nearby edge.
        let edges_of = |tv: [u32; 3]| (0..3).map(move |i| sorted([tv[i], tv[(i + 1) % 3]]));
        let mut moving_edges: Vec<[u32; 2]> = tris
            .iter()
            .flat_map(|&t| edges_of(self.c.triangle(t)))
            .filter(|e| e.iter().any(|&u| moves(u)))
            .collect();
        moving_edges.sort_unstable();
        moving_edges.dedup();
        let mut near_edges: Vec<[u32; 2]> = candidates
            .iter()
            .flat_map(|&(sv, _)| edges_of(sv))
            .collect();
        near_edges.sort_unstable();
        near_edges.dedup();
        for &e in &moving_edges {
            let (eb, ea) = (swept_of(&e), e.map(alias));
            for &f in &near_edges {
                let fa = f.map(alias);
                if ea.iter().any(|v| fa.contains(v)) || !overlap(eb, swept_of(&f)) {
                    continue;
                }
                let ids = [e[0], e[1], f[0], f[1]];
                if edge_edge(&ids.map(|i| x0[i as usize]), &ids.map(|i| x1[i as usize])) {
                    return false;
                }
            }
        }
        true
    }
}

/// The edge `[a, b]` with its ends in ascending order.
fn sorted([a, b]: [u32; 2]) -> [u32; 2] {
    [a.min(b), a.max(b)]
}
