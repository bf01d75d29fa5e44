//! Collision check of a remeshing pseudo-motion (Brochu & Bridson 2009, cited in paper 000
//! §4.2 and Appendix A): the vertices `moving` go linearly from their positions to `x1`, and
//! every vertex–triangle and edge–edge pair with at least one moving primitive is tested by
//! exact CCD against the live triangles the broad phase finds near the swept boxes. Pairs
//! sharing a vertex are skipped (they touch by construction), and so are pairs joining the
//! two ends of an edge being collapsed, which meet on purpose.

use glam::DVec3;

use super::Remesher;
use crate::front::ccd::{edge_edge, vertex_triangle};

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

    fn check_motion(&self, moving: &[u32], merging: Option<[u32; 2]>) -> bool {
        let alias = |v: u32| match merging {
            Some([a, b]) if v == b => a,
            _ => v,
        };
        let moves = |v: u32| moving.contains(&v);
        let x0 = &self.c.mesh.vertices;
        let x1 = &self.x1;
        let mut tris: Vec<u32> = moving
            .iter()
            .flat_map(|&v| self.c.vertex_triangles(v).iter().copied())
            .filter(|&t| self.c.is_live(t))
            .collect();
        tris.sort_unstable();
        tris.dedup();
        // Candidates: everything near the union of the swept boxes, moving triangles included
        // (their start boxes lie inside it), so moving–moving pairs are tested too.
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &t in &tris {
            for v in self.c.triangle(t) {
                let (p, q) = (x0[v as usize], x1[v as usize]);
                lo = lo.min(p).min(q);
                hi = hi.max(p).max(q);
            }
        }
        let mut near = Vec::new();
        self.grid.query(lo, hi, &mut near);
        // Swept boxes: two triangles whose boxes are disjoint cannot meet during the motion,
        // which settles most candidates of the union box before any CCD test.
        let swept = |tri: [u32; 3]| {
            tri.iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| {
                    let (p, q) = (x0[v as usize], x1[v as usize]);
                    (lo.min(p).min(q), hi.max(p).max(q))
                })
        };
        // Each candidate's corners and swept box, once for all moving triangles.
        let candidates: Vec<(u32, [u32; 3], (DVec3, DVec3))> = near
            .iter()
            .filter(|&&s| self.c.is_live(s))
            .map(|&s| {
                let sv = self.c.triangle(s);
                (s, sv, swept(sv))
            })
            .collect();
        for &t in &tris {
            let tv = self.c.triangle(t);
            let (tlo, thi) = swept(tv);
            for &(s, sv, (slo, shi)) in &candidates {
                if s == t {
                    continue;
                }
                if tlo.cmpgt(shi).any() || slo.cmpgt(thi).any() {
                    continue;
                }
                let ta = tv.map(alias);
                let sa = sv.map(alias);
                // Vertex of one against the other triangle.
                for (verts, va, tri) in [(sv, sa, tv), (tv, ta, sv)] {
                    let tri_a = tri.map(alias);
                    for (&v, &v_alias) in verts.iter().zip(&va) {
                        if tri_a.contains(&v_alias) || !(moves(v) || tri.iter().any(|&u| moves(u)))
                        {
                            continue;
                        }
                        let ids = [v, tri[0], tri[1], tri[2]];
                        let p0 = ids.map(|i| x0[i as usize]);
                        let p1 = ids.map(|i| x1[i as usize]);
                        if vertex_triangle(&p0, &p1) {
                            return false;
                        }
                    }
                }
                // Edge against edge.
                for i in 0..3 {
                    let e = [tv[i], tv[(i + 1) % 3]];
                    for j in 0..3 {
                        let f = [sv[j], sv[(j + 1) % 3]];
                        let ea = e.map(alias);
                        let fa = f.map(alias);
                        if ea.iter().any(|v| fa.contains(v))
                            || !(e.iter().chain(&f).any(|&u| moves(u)))
                        {
                            continue;
                        }
                        let ids = [e[0], e[1], f[0], f[1]];
                        let p0 = ids.map(|i| x0[i as usize]);
                        let p1 = ids.map(|i| x1[i as usize]);
                        if edge_edge(&p0, &p1) {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }
}
