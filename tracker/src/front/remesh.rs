//! Collision-safe remeshing of a labeled non-manifold mesh (paper 000 §7 and Appendix A):
//! passes of edge splitting, edge collapsing, edge flipping and null-space smoothing, then the
//! poor-triangle fail-safe of A.4. Every operation is atomic: it is evaluated against the user
//! bounds (angles, areas, edge lengths, volume change) and checked as a pseudo-motion by
//! continuous collision detection, and either completes in full or leaves the mesh untouched,
//! so the mesh stays closed, label-consistent and intersection-free throughout.

mod collapse;
mod features;
mod flip;
mod safety;
mod smooth;
mod split;
mod volume;

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use super::broadphase::TriangleGrid;

use super::connectivity::Connectivity;
#[cfg(test)]
use super::connectivity::DEAD;
use super::params::{Bounds, FrontParams};
use volume::volume_change;

/// What one remeshing call did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RemeshStats {
    /// Edges split.
    pub splits: usize,
    /// Edges collapsed.
    pub collapses: usize,
    /// Edges flipped.
    pub flips: usize,
    /// Vertices moved by smoothing.
    pub smoothed: usize,
    /// Operations cancelled because their pseudo-motion would collide.
    pub unsafe_cancelled: usize,
    /// Operations cancelled by a quality, length or volume bound.
    pub bound_cancelled: usize,
    /// Operations of the A.4 fail-safe pass that completed.
    pub failsafe: usize,
}

impl RemeshStats {
    /// The counts of two calls together.
    pub fn plus(&self, o: &RemeshStats) -> RemeshStats {
        RemeshStats {
            splits: self.splits + o.splits,
            collapses: self.collapses + o.collapses,
            flips: self.flips + o.flips,
            smoothed: self.smoothed + o.smoothed,
            unsafe_cancelled: self.unsafe_cancelled + o.unsafe_cancelled,
            bound_cancelled: self.bound_cancelled + o.bound_cancelled,
            failsafe: self.failsafe + o.failsafe,
        }
    }
}

/// What one remeshing call keeps beyond its bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Keep {
    /// Collapses and ridge moves are placed so that no phase's volume changes (see
    /// `remesh/volume.rs`).
    pub volumes: bool,
    /// Dihedral features at vertices on non-manifold curves ([`Remesher::junction_creases`]).
    pub junction_creases: bool,
}

/// Remeshes `c` in place toward edge length `target` and compacts it (indices change).
pub fn improve(c: &mut Connectivity, params: &FrontParams, target: f64, keep: Keep) -> RemeshStats {
    let mut r = Remesher::new(c, Bounds::new(params, target));
    r.butterfly = params.butterfly;
    r.keep_volumes = keep.volumes;
    r.junction_creases = keep.junction_creases;
    r.split_pass();
    r.collapse_pass();
    r.flip_pass();
    for _ in 0..params.smoothing_passes {
        r.smooth_pass();
    }
    r.failsafe_pass();
    let stats = r.stats;
    c.compact();
    stats
}

/// Triangle geometry gathered for evaluating an operation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri {
    pub(crate) p: [DVec3; 3],
    pub(crate) labels: [PhaseId; 2],
}

impl Tri {
    pub(crate) fn area_normal(&self) -> DVec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    pub(crate) fn area(&self) -> f64 {
        0.5 * self.area_normal().length()
    }

    /// Cosines of the smallest and of the largest angle (0 and 1 for a degenerate triangle).
    fn angle_cosines(&self) -> (f64, f64) {
        let mut small = -1.0f64;
        let mut large = 1.0f64;
        for k in 0..3 {
            let u = (self.p[(k + 1) % 3] - self.p[k]).normalize_or_zero();
            let v = (self.p[(k + 2) % 3] - self.p[k]).normalize_or_zero();
            if u == DVec3::ZERO || v == DVec3::ZERO {
                return (1.0, -1.0);
            }
            let cos = u.dot(v);
            small = small.max(cos);
            large = large.min(cos);
        }
        (small, large)
    }
}

/// The state of one remeshing call: the mesh, the bounds, the broad phase over the live
/// triangles and a scratch copy of the positions that holds each pseudo-motion's end state.
pub(crate) struct Remesher<'a> {
    pub(crate) c: &'a mut Connectivity,
    pub(crate) b: Bounds,
    pub(crate) grid: TriangleGrid,
    /// Pseudo-motion end positions; equal to the mesh's positions between operations.
    pub(crate) x1: Vec<DVec3>,
    /// In the fail-safe pass only collision safety, inversion and non-degeneracy are checked.
    pub(crate) failsafe: bool,
    /// Collapses may join vertices on different features or non-manifold curves (paper 000
    /// §5.1.7: the collapse that starts a T1 process, allowed only where the flow shortens the
    /// edge; set by [`crate::front::topology::separate::collapse_junction_edges`]).
    pub(crate) junction: bool,
    /// Collapses may leave coincident triangles and may break the link condition: a region
    /// shrinking to nothing ends as such pairs, and a flat one pinches into pieces on the way
    /// (paper 000 §5.2; set by [`crate::front::topology::vanish`], which resolves the pairs at
    /// once and follows the pieces). Either keeps every edge's half-face balance, so the mesh
    /// stays closed and label-consistent.
    pub(crate) coincident: bool,
    /// Collapses skip the pseudo-motion's CCD check and the caller checks their end state
    /// with the exact intersection test instead: for needle edges, below the CCD's near-miss
    /// distance, where every motion reads as a contact
    /// ([`crate::front::topology::needle`]).
    pub(crate) end_state_checked: bool,
    /// Splits move the new vertex to its butterfly point ([`FrontParams::butterfly`]).
    butterfly: bool,
    /// Collapses and ridge moves keep every phase's volume ([`improve`]).
    pub(crate) keep_volumes: bool,
    /// A vertex on a non-manifold curve counts its films' dihedral features too; when false it
    /// is classed by that curve alone ([`Keep::junction_creases`]).
    pub(crate) junction_creases: bool,
    pub(crate) stats: RemeshStats,
    /// Runs the invariant checks after every operation (tests).
    #[cfg(test)]
    pub(crate) verify: bool,
    /// Phase volumes after the last verified operation (tests).
    #[cfg(test)]
    volumes: Vec<f64>,
}

impl<'a> Remesher<'a> {
    pub(crate) fn new(c: &'a mut Connectivity, b: Bounds) -> Remesher<'a> {
        let mut grid = TriangleGrid::new(b.max_edge);
        for t in 0..c.mesh.triangles.len() as u32 {
            if c.is_live(t) {
                let (lo, hi) = tri_box(c, t);
                grid.insert(t, lo, hi);
            }
        }
        let x1 = c.mesh.vertices.clone();
        Remesher {
            c,
            b,
            grid,
            x1,
            failsafe: false,
            junction: false,
            coincident: false,
            end_state_checked: false,
            butterfly: false,
            keep_volumes: true,
            junction_creases: true,
            stats: RemeshStats::default(),
            #[cfg(test)]
            verify: false,
            #[cfg(test)]
            volumes: Vec::new(),
        }
    }

    /// Drops the triangles that died outside the remesher's own operations (coincident pairs
    /// removed by [`crate::front::topology::degenerate::remove_degenerate_pairs`]) from the
    /// broad phase.
    pub(crate) fn forget_dead(&mut self) {
        for t in 0..self.c.mesh.triangles.len() as u32 {
            if !self.c.is_live(t) {
                self.grid.remove(t);
            }
        }
    }

    pub(crate) fn tri(&self, t: u32) -> Tri {
        let [a, b, c] = self.c.triangle(t);
        Tri {
            p: [self.c.position(a), self.c.position(b), self.c.position(c)],
            labels: self.c.labels(t),
        }
    }

    pub(crate) fn add_vertex(&mut self, p: DVec3) -> u32 {
        self.x1.push(p);
        self.c.add_vertex(p)
    }

    pub(crate) fn add_triangle(&mut self, tri: [u32; 3], labels: [PhaseId; 2]) -> u32 {
        let t = self.c.add_triangle(tri, labels);
        let (lo, hi) = tri_box(self.c, t);
        self.grid.insert(t, lo, hi);
        t
    }

    pub(crate) fn remove_triangle(&mut self, t: u32) {
        self.grid.remove(t);
        self.c.remove_triangle(t);
    }

    /// Moves vertex `v` to `p` and refreshes the broad-phase boxes of its triangles.
    pub(crate) fn move_vertex(&mut self, v: u32, p: DVec3) {
        self.c.mesh.vertices[v as usize] = p;
        self.x1[v as usize] = p;
        for i in 0..self.c.vertex_triangles(v).len() {
            let t = self.c.vertex_triangles(v)[i];
            self.grid.remove(t);
            let (lo, hi) = tri_box(self.c, t);
            self.grid.insert(t, lo, hi);
        }
    }

    /// The quality bounds of Appendix A for replacing triangles `old` by `new`: no new angle
    /// outside `[min_angle, max_angle]` unless the worst angle improves, no area below the
    /// minimum, no phase volume changing by more than the bound. In the fail-safe pass only
    /// non-degeneracy is required. Counts a cancellation when the bounds fail.
    pub(crate) fn bounds_allow(&mut self, old: &[Tri], new: &[Tri]) -> bool {
        self.bounds_allow_volume(old, new, self.b.max_volume_change)
    }

    /// [`Self::bounds_allow`] with volume bound `max_volume_change`.
    pub(crate) fn bounds_allow_volume(
        &mut self,
        old: &[Tri],
        new: &[Tri],
        max_volume_change: f64,
    ) -> bool {
        let ok = if new.iter().any(|t| t.area().is_nan() || t.area() <= 0.0) {
            false
        } else if moves_the_domain_boundary(old, new) {
            // Not even the fail-safe may: a boundary face turned off its wall (a flip across a
            // box edge, a collapse between two walls) takes volume from the domain for good.
            false
        } else if self.failsafe {
            true
        } else {
            let worst = |ts: &[Tri]| {
                ts.iter().fold((-1.0f64, 1.0f64), |(s, l), t| {
                    let (ts, tl) = t.angle_cosines();
                    (s.max(ts), l.min(tl))
                })
            };
            let (old_small, old_large) = worst(old);
            let (new_small, new_large) = worst(new);
            (new_small <= self.b.cos_min_angle || new_small < old_small)
                && (new_large >= self.b.cos_max_angle || new_large > old_large)
                && smallest_area(new) > self.b.min_area.min(smallest_area(old))
                && volume_change(old, new) <= max_volume_change
        };
        if !ok {
            self.stats.bound_cancelled += 1;
        }
        ok
    }

    /// Is live triangle `t` very poor (an angle outside `[poor, 180° - poor]`)?
    fn is_poor(&self, t: u32) -> bool {
        let (small, large) = self.tri(t).angle_cosines();
        small > self.b.cos_poor || large < -self.b.cos_poor
    }

    /// Appendix A.4: triangles still very poor after the regular passes get a collapse of
    /// their shortest edge, else a flip of their longest, with only collision safety,
    /// inversion and non-degeneracy checked.
    fn failsafe_pass(&mut self) {
        let poor: Vec<u32> = (0..self.c.mesh.triangles.len() as u32)
            .filter(|&t| self.c.is_live(t) && self.is_poor(t))
            .collect();
        self.failsafe = true;
        for t in poor {
            if !self.c.is_live(t) || !self.is_poor(t) {
                continue;
            }
            let [a, b, c] = self.c.triangle(t);
            let mut edges = [[a, b], [b, c], [c, a]];
            edges.sort_by(|x, y| {
                let l = |e: &[u32; 2]| (self.c.position(e[0]) - self.c.position(e[1])).length();
                l(x).total_cmp(&l(y))
            });
            let [s0, s1] = edges[0];
            let [l0, l1] = edges[2];
            if self.try_collapse(s0, s1) || self.try_flip(l0, l1, true) {
                self.stats.failsafe += 1;
                self.verify_now("fail-safe");
            }
        }
        self.failsafe = false;
    }

    /// After an operation in tests: the live mesh passes the shared invariant checks, and no
    /// phase volume moved by more than the bound (outside the fail-safe pass).
    #[cfg(test)]
    pub(crate) fn verify_now(&mut self, what: &str) {
        if !self.verify {
            return;
        }
        let mesh = self.live_mesh();
        if let Err(e) = crate::invariants::check(&mesh, 0.0) {
            panic!("after {what}: {e}");
        }
        let volumes = mesh.phase_volumes(tests::PHASES);
        if !self.failsafe {
            for (v, w) in volumes.iter().zip(&self.volumes) {
                // The bound, plus rounding of the global tetra sums.
                assert!(
                    (v - w).abs() <= self.b.max_volume_change + 1e-12,
                    "{what} changed a volume by {}",
                    v - w
                );
            }
        }
        self.volumes = volumes;
    }

    #[cfg(not(test))]
    pub(crate) fn verify_now(&mut self, _what: &str) {}

    /// The live triangles as a plain mesh (unused vertices kept).
    #[cfg(test)]
    pub(crate) fn live_mesh(&self) -> crate::mesh::LabeledMesh {
        let mut mesh = self.c.mesh.clone();
        let keep: Vec<bool> = mesh.triangles.iter().map(|t| *t != DEAD).collect();
        let mut k = keep.iter();
        mesh.labels.retain(|_| *k.next().unwrap_or(&false));
        mesh.triangles.retain(|t| *t != DEAD);
        mesh
    }
}

/// Bounding box of live triangle `t`.
pub(crate) fn tri_box(c: &Connectivity, t: u32) -> (DVec3, DVec3) {
    let [a, b, d] = c.triangle(t).map(|v| c.position(v));
    (a.min(b).min(d), a.max(b).max(d))
}

/// Does replacing `old` by `new` change the volume the domain boundary faces (`OUTSIDE`
/// labels) enclose by more than rounding? Sliding within a planar wall changes it by nothing.
fn moves_the_domain_boundary(old: &[Tri], new: &[Tri]) -> bool {
    let Some(first) = old.first() else {
        return false;
    };
    let r = first.p[0];
    let (mut change, mut scale) = (0.0, 0.0);
    for (tris, sign) in [(old, -1.0), (new, 1.0)] {
        for t in tris.iter().filter(|t| t.labels.contains(&OUTSIDE)) {
            let [a, b, c] = t.p.map(|p| p - r);
            let v = a.dot(b.cross(c)) / 6.0;
            // The domain is the face's non-`OUTSIDE` side (as in `volume_change`).
            let inside = if t.labels[0] == OUTSIDE { v } else { -v };
            change += sign * inside;
            scale += v.abs();
        }
    }
    // Each tetra volume carries a relative rounding error of a few ulps; a billionth of
    // their sum is far above that and far below any real off-wall move of a remeshing step.
    change.abs() > 1e-9 * scale
}

/// Triangle `tri` rotated so that it starts with the directed edge `(a, b)`, or `None` when it
/// traverses the edge from `b` to `a` (or does not contain it).
pub(crate) fn starting_with(tri: [u32; 3], a: u32, b: u32) -> Option<[u32; 3]> {
    (0..3)
        .map(|k| [tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]])
        .find(|r| r[0] == a && r[1] == b)
}

#[cfg(test)]
mod tests;

/// The smallest area among `ts` (+∞ for none).
fn smallest_area(ts: &[Tri]) -> f64 {
    ts.iter().map(Tri::area).fold(f64::INFINITY, f64::min)
}
