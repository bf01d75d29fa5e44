//! Null-space (tangential) vertex smoothing (paper 000 Appendix A.3) of vertices next to a
//! poorly shaped triangle: a smooth vertex moves
//! toward the area-weighted centroid of its triangles with the normal component of that
//! displacement removed (the area-weighted normal is the gradient of the volume enclosed by the
//! vertex's fan, so the fan's volume does not change); a ridge vertex (two feature edges,
//! non-manifold curves included) moves along the ridge, toward the midpoint of its two ridge
//! neighbours, and then by the least needed to keep every phase's volume (`volume.rs`); peaks,
//! ends of ridges and other non-manifold vertices stay. Each displacement is checked as a
//! pseudo-motion.

use glam::DVec3;

use super::features::Kind;
use super::volume::volume_preserving;
use super::{Remesher, Tri};

impl Remesher<'_> {
    /// Smooths every vertex once, in index order (Gauss–Seidel, deterministic).
    pub(super) fn smooth_pass(&mut self) {
        for v in 0..self.c.mesh.vertices.len() as u32 {
            if !self.c.vertex_triangles(v).is_empty() && self.try_smooth(v) {
                self.stats.smoothed += 1;
                self.verify_now("smooth");
            }
        }
    }

    /// Does `v` touch a triangle with an angle below 25° or above 120°? Only such vertices
    /// are smoothed: smoothing a fine neighbourhood gains nothing, and on a curved ridge or
    /// triple curve every move costs a little volume.
    fn needs_smoothing(&self, v: u32) -> bool {
        // cos 25°, cos 120°.
        let (cos_small, cos_large) = (0.906_307_787, -0.5);
        self.c.vertex_triangles(v).iter().any(|&t| {
            let (small, large) = self.tri(t).angle_cosines();
            small > cos_small || large < cos_large
        })
    }

    /// The smoothed position of `v`, or `None` when `v` must stay.
    fn smoothed_position(&self, v: u32) -> Option<DVec3> {
        if !self.needs_smoothing(v) {
            return None;
        }
        let x = self.c.position(v);
        let f = self.vertex_features(v);
        match (f.kind, f.non_manifold, &f.feature_neighbours[..]) {
            (Kind::Smooth, false, _) => {
                let tris = self.c.vertex_triangles(v);
                let reference = self.c.labels(tris[0]);
                let (mut weighted, mut area, mut normal) = (DVec3::ZERO, 0.0, DVec3::ZERO);
                for &t in tris {
                    let tri = self.tri(t);
                    let an = tri.area_normal();
                    let a = 0.5 * an.length();
                    weighted += a * (tri.p[0] + tri.p[1] + tri.p[2]) / 3.0;
                    area += a;
                    // Orient every normal toward the reference triangle's front phase.
                    normal += if tri.labels[0] == reference[0] {
                        an
                    } else {
                        -an
                    };
                }
                let n = normal.normalize_or_zero();
                if area <= 0.0 || n == DVec3::ZERO {
                    return None;
                }
                let d = weighted / area - x;
                Some(x + d - d.dot(n) * n)
            }
            (Kind::Ridge, _, &[u1, u2]) => {
                let (p1, p2) = (self.c.position(u1), self.c.position(u2));
                let dir = ((p1 - x).normalize_or_zero() - (p2 - x).normalize_or_zero())
                    .normalize_or_zero();
                let d = 0.5 * (p1 + p2) - x;
                let along = x + d.dot(dir) * dir;
                if !self.keep_volumes {
                    return Some(along);
                }
                // Along a curved ridge every phase around it gains or loses a little; the
                // move is completed in the phases' volume gradients so that none does.
                let old: Vec<Tri> = self.star(v);
                let new_at = |p: DVec3| self.star_moved(v, p);
                Some(volume_preserving(&old, &new_at, along, (p1 - p2).length()))
            }
            _ => None,
        }
    }

    /// Moves `v` to its smoothed position if the bounds allow and the motion is safe.
    pub(super) fn try_smooth(&mut self, v: u32) -> bool {
        let Some(p) = self.smoothed_position(v) else {
            return false;
        };
        let x = self.c.position(v);
        // Gauss–Seidel smoothing converges geometrically, and a vertex boxed in by its
        // neighbours is asked to move a little again every step; moves below 1 % of the
        // collapse length turn no angle by more than about a degree, and skipping them saves
        // their collision check (measured: most of the smoothing time on enright).
        if (p - x).length() < 1e-2 * self.b.min_edge {
            return false;
        }
        // No edge may grow past the split length.
        self.try_move(v, p, self.b.max_edge)
    }

    /// Moves `v` to `p` if no edge grows past `max_len` (or past its length, if longer), no
    /// triangle turns over, the bounds allow and the motion is collision-safe.
    pub(super) fn try_move(&mut self, v: u32, p: DVec3, max_len: f64) -> bool {
        let x = self.c.position(v);
        let too_long = self.c.neighbours(v).iter().any(|&u| {
            let q = self.c.position(u);
            (p - q).length() > max_len.max((x - q).length())
        });
        if too_long {
            self.stats.bound_cancelled += 1;
            return false;
        }
        let old = self.star(v);
        let new = self.star_moved(v, p);
        if old
            .iter()
            .zip(&new)
            .any(|(o, n)| o.area_normal().dot(n.area_normal()) <= 0.0)
        {
            self.stats.bound_cancelled += 1;
            return false;
        }
        if !self.bounds_allow(&old, &new) || !self.pseudo_motion_is_safe(&[v], &[p], None) {
            return false;
        }
        self.move_vertex(v, p);
        true
    }

    /// The triangles around `v`.
    fn star(&self, v: u32) -> Vec<Tri> {
        self.c
            .vertex_triangles(v)
            .iter()
            .map(|&t| self.tri(t))
            .collect()
    }

    /// The triangles around `v` as they would be with `v` at `p`.
    fn star_moved(&self, v: u32, p: DVec3) -> Vec<Tri> {
        self.c
            .vertex_triangles(v)
            .iter()
            .map(|&t| Tri {
                p: self
                    .c
                    .triangle(t)
                    .map(|u| if u == v { p } else { self.c.position(u) }),
                labels: self.c.labels(t),
            })
            .collect()
    }
}
