//! Snap-based merging (paper 000 §6.2, Figs. 15, 17, 18, 19): where two parts of the surface
//! come within the merge distance, the nearby primitives are subdivided so that each side has a
//! vertex at the closest points (compatible remeshing), and the two vertices are snapped into
//! one at their average position. Repeated over a contact region this zips the surfaces
//! together face to face; the coincident triangle pairs it leaves are the degenerate zero-volume
//! regions of §5.2, removed after each pass (deleted where the same phase met itself, replaced
//! by one separating triangle where two phases met).
//!
//! A pair's splits and snap form one atomic operation: checked against the remeshing bounds
//! and by continuous collision detection, and either completed or cancelled as a whole, so the
//! mesh stays closed, label-consistent and intersection-free (coincident triangle pairs aside,
//! until the removal at the end of the pass).

mod proximity;
mod snap;
mod subdivide;
#[cfg(test)]
mod tests;

use glam::DVec3;
use polyphase_grid::PhaseId;

use self::proximity::{Pair, Prim};
use super::degenerate::remove_degenerate_pairs;
use crate::front::connectivity::Connectivity;
use crate::front::params::{Bounds, FrontParams};
use crate::front::remesh::Remesher;

/// What one [`merge_pass`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MergeStats {
    /// Vertex pairs snapped into one.
    pub snaps: usize,
    /// Edge and triangle splits that gave a snapped pair its vertices.
    pub splits: usize,
    /// Proximity pairs given up because a split or the snap failed a quality bound or would
    /// have caused a collision (the pair's splits undone).
    pub cancelled: usize,
    /// Coincident triangle pairs the snaps made, resolved by
    /// [`remove_degenerate_pairs`] (§5.2).
    pub degenerate: usize,
}

/// Passes over the proximity pairs at most; each pass snaps what the previous one's edits made
/// snappable (a pair whose primitives an earlier snap of the same pass changed waits for the
/// next), and a pass without a snap ends the merge.
const MAX_PASSES: usize = 8;

/// Merges the parts of `c` closer than `distance` (paper 000 §6.2), resolves the coincident
/// triangle pairs that leaves (§5.2), and compacts the mesh (indices change). `target` is the
/// remeshing target edge length that scales the quality bounds of [`FrontParams`]. Each snap
/// moves its two vertices by at most `distance / 2`, which changes a phase's volume by at most
/// a third of the area of their triangles times that (the gap being closed); splits and the
/// removal of coincident pairs move nothing.
///
/// `across`: the only phase a closing gap may hold (`None`: any). In a fluid the films that
/// close are the air's, when two liquids or a liquid and a wall meet; the two faces of a
/// liquid sheet thinner than the merge distance are not a gap, and snapping them deletes the
/// sheet (measured with merging on: `balls` at 64 lost 4.8 % of its water by t = 0.37 s, and
/// 0.10 % with this rule).
pub fn merge_pass(
    c: &mut Connectivity,
    params: &FrontParams,
    target: f64,
    distance: f64,
    across: Option<PhaseId>,
) -> MergeStats {
    let mut m = Merger::new(c, params, target, distance);
    m.across = across;
    m.run();
    let stats = m.stats;
    c.compact();
    stats
}

/// The state of one merge: the remesher whose operations, bounds and collision checks it
/// shares, the merge distance and the subdivision threshold.
pub(crate) struct Merger<'a> {
    /// The mesh with its broad phase, bounds and operation counters.
    pub(crate) r: Remesher<'a>,
    /// Primitives closer than this are merged.
    distance: f64,
    /// A split point closer than this to an existing vertex (or, on a triangle, to one of its
    /// edges) uses that vertex (edge) instead (§6.2: avoids poor triangles and needless
    /// refinement). Half the collapse length: a closer split would make an edge that the next
    /// collapse pass removes again.
    near: f64,
    /// The only phase a closing gap may hold ([`merge_pass`]); `None`: any.
    pub(crate) across: Option<PhaseId>,
    /// What the merge did so far.
    pub(crate) stats: MergeStats,
    /// Runs the invariant and intersection checks after every operation (tests).
    #[cfg(test)]
    pub(crate) verify: bool,
}

impl<'a> Merger<'a> {
    /// A merger over `c` with the remeshing bounds for target edge length `target`.
    pub(crate) fn new(
        c: &'a mut Connectivity,
        params: &FrontParams,
        target: f64,
        distance: f64,
    ) -> Merger<'a> {
        Merger {
            r: Remesher::new(c, Bounds::new(params, target)),
            distance,
            near: 0.5 * params.min_edge * target,
            across: None,
            stats: MergeStats::default(),
            #[cfg(test)]
            verify: false,
        }
    }

    /// Passes over the proximity pairs, closest first, each followed by the removal of the
    /// coincident triangle pairs it made, until one snaps nothing.
    pub(crate) fn run(&mut self) {
        for _ in 0..MAX_PASSES {
            let mut snapped = 0;
            for pair in self.proximity_pairs() {
                if self.try_merge(pair) {
                    snapped += 1;
                }
            }
            self.remove_degenerate();
            if snapped == 0 {
                break;
            }
        }
    }

    /// Merges one proximity pair found at the start of the pass, if its primitives still
    /// exist and are still within the distance: picks the vertex (existing or to be split
    /// off) of each side, splits, snaps. `true` when the snap happened.
    fn try_merge(&mut self, pair: Pair) -> bool {
        if !self.exists(&pair.a) || !self.exists(&pair.b) {
            return false;
        }
        let (pa, pb) = self.closest_points(&pair.a, &pair.b);
        if pa.distance(pb) > self.distance
            || !self.fold_allows(&pair.a, &pair.b)
            || !self.facing(&pair.a, &pair.b, pa, pb)
            || !self.gap_allowed(&pair.a, &pair.b, pa, pb)
        {
            return false;
        }
        let (a, pa) = self.reduce(pair.a, pa, pb);
        let pb = self.closest_to(&pair.b, pa);
        let (b, pb) = self.reduce(pair.b, pb, pa);
        if !self.snappable(&a, &b) {
            return false;
        }
        // The splits and the snap form one atomic operation: a cancelled snap undoes the
        // splits made for it, which would only have refined the mesh for nothing.
        let Some((u, split_a)) = self.vertex_at(a, pa) else {
            self.stats.cancelled += 1;
            return false;
        };
        let Some((w, split_b)) = self.vertex_at(b, pb) else {
            split_a.into_iter().for_each(|s| self.undo(s));
            self.stats.cancelled += 1;
            self.verify_now("undone split");
            return false;
        };
        if self.try_snap(u, w) {
            self.stats.splits += usize::from(split_a.is_some()) + usize::from(split_b.is_some());
            self.stats.snaps += 1;
            self.verify_now("split and snap");
            true
        } else {
            split_b.into_iter().for_each(|s| self.undo(s));
            split_a.into_iter().for_each(|s| self.undo(s));
            self.stats.cancelled += 1;
            self.verify_now("cancelled snap");
            false
        }
    }

    /// Resolves the coincident triangle pairs the pass's snaps made (§5.2: where two surfaces
    /// met face to face), and drops the removed triangles from the broad phase.
    fn remove_degenerate(&mut self) {
        self.stats.degenerate += remove_degenerate_pairs(self.r.c);
        self.r.forget_dead();
        self.verify_now("degenerate removal");
    }

    /// May the reduced primitives `a`, `b` be given vertices and snapped? They share no
    /// vertex, satisfy the fold rule, two vertices share no edge (collapse's job, §6.2), and a
    /// vertex is no apex of a triangle on the edge it faces (the split vertex would be its
    /// neighbour).
    fn snappable(&self, a: &Prim, b: &Prim) -> bool {
        let apex_of = |v: u32, e: &[u32; 2]| {
            let mut tris = Vec::new();
            self.r.c.edge_triangles(e[0], e[1], &mut tris);
            tris.iter().any(|&t| self.r.c.triangle(t).contains(&v))
        };
        let adjacent = match (a, b) {
            (Prim::Vertex(u), Prim::Vertex(w)) => self.r.c.neighbours(*u).binary_search(w).is_ok(),
            (Prim::Vertex(v), Prim::Edge(e)) | (Prim::Edge(e), Prim::Vertex(v)) => apex_of(*v, e),
            _ => false,
        };
        !adjacent && !a.shares_vertex(b) && self.fold_allows(a, b)
    }

    /// After an operation in tests: the live mesh is closed and label-consistent, and no two
    /// triangles intersect except coincident pairs (same three vertices), the degenerate
    /// regions that §5.2 removes.
    #[cfg(test)]
    fn verify_now(&mut self, what: &str) {
        if !self.verify {
            return;
        }
        let mesh = self.r.live_mesh();
        if let Err(e) = crate::invariants::check(&mesh, 0.0) {
            panic!("after {what}: {e}");
        }
        let key = |t: u32| {
            let mut k = mesh.triangles[t as usize];
            k.sort_unstable();
            k
        };
        let bad: Vec<(u32, u32)> = crate::front::intersection::self_intersections(&mesh)
            .into_iter()
            .filter(|&(s, t)| key(s) != key(t))
            .collect();
        assert!(bad.is_empty(), "after {what}: intersecting {bad:?}");
    }

    #[cfg(not(test))]
    fn verify_now(&mut self, _what: &str) {}

    /// Position of vertex `v`.
    fn position(&self, v: u32) -> DVec3 {
        self.r.c.position(v)
    }
}
