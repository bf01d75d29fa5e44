//! The topology parts of a front-tracker step (paper 000 Algorithm 1): merging after
//! collision resolution (§6.2), and after mesh improvement the T1 processes — collapses that
//! bring two non-manifold curves together where the flow shortens the edge between them
//! (§5.1.7), then vertex separation of every irregular vertex (§5.1.4–5.1.6, Algorithm 2) —
//! and the T2 processes (coincident pairs and regions too small to keep, §5.2).

use std::time::Instant;

use glam::DVec3;
use polyphase_grid::{PhaseId, VelocityField};

use super::FrontTracker;
use crate::front::flow::MeshFlow;
use crate::front::topology::degenerate::remove_degenerate_pairs;
use crate::front::topology::merge::merge_pass;
use crate::front::topology::needle::collapse_needles;
use crate::front::topology::separate::{
    collapse_junction_edges, separate_vertices, SeparationStrength,
};
use crate::front::topology::vanish::remove_small_regions;

/// How a step scores T1 processes.
pub(super) enum T1Rule<'a> {
    /// A mesh-driven flow: for mean-curvature flow, separations that lower the area and
    /// collapses where the flow's own vertex velocities shorten the edge; none for the
    /// others.
    Area(&'a MeshFlow),
    /// A prescribed velocity field at the end of the step.
    Field(&'a dyn VelocityField, f64),
}

/// Counts of one step's topology changes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TopologyCounts {
    /// Vertex pairs snapped together by merging.
    pub snaps: usize,
    /// Needle edges collapsed ([`collapse_needles`]).
    pub needles: usize,
    /// Collapses that joined two non-manifold curves (the start of a T1).
    pub junction_collapses: usize,
    /// Vertex separations (the end of a T1).
    pub separations: usize,
    /// Coincident triangle pairs removed or relabeled (§5.2, Fig. 14), merging's included.
    pub degenerate: usize,
    /// Regions removed for being too small (T2), the pieces a flat one pinched into counted
    /// one by one.
    pub vanished: usize,
}

impl TopologyCounts {
    /// The counts of two steps together.
    pub fn plus(&self, o: &TopologyCounts) -> TopologyCounts {
        TopologyCounts {
            snaps: self.snaps + o.snaps,
            needles: self.needles + o.needles,
            junction_collapses: self.junction_collapses + o.junction_collapses,
            separations: self.separations + o.separations,
            degenerate: self.degenerate + o.degenerate,
            vanished: self.vanished + o.vanished,
        }
    }
}

impl FrontTracker {
    /// Snaps together surfaces within the merge distance (§6.2); the first topology stage,
    /// right after the motion. `default` is the distance (in L) when the scene sets none;
    /// `across` the only phase a closing gap may hold ([`merge_pass`]).
    pub(super) fn merge(&mut self, default: f64, across: Option<PhaseId>) -> TopologyCounts {
        let fraction = self.params.merge_distance.unwrap_or(default);
        if fraction <= 0.0 {
            return TopologyCounts::default();
        }
        let start = Instant::now();
        let distance = fraction * self.target;
        let stats = merge_pass(&mut self.c, &self.params, self.target, distance, across);
        self.seconds[2] += start.elapsed().as_secs_f64();
        TopologyCounts {
            snaps: stats.snaps,
            degenerate: stats.degenerate,
            ..TopologyCounts::default()
        }
    }

    /// Needle edges collapsed, the T1 processes of `rule`, then the T2 processes, on the
    /// improved mesh.
    pub(super) fn separate(&mut self, rule: T1Rule) -> TopologyCounts {
        let start = Instant::now();
        let needles = collapse_needles(&mut self.c, &self.params, self.target);
        let mut counts = self.t1(rule);
        counts.needles = needles;
        counts.degenerate += remove_degenerate_pairs(&mut self.c);
        let min_volume = self.params.min_region_volume * self.target.powi(3);
        if min_volume > 0.0 {
            counts.vanished =
                remove_small_regions(&mut self.c, &self.params, self.target, min_volume).removed;
        }
        self.c.compact();
        self.seconds[3] += start.elapsed().as_secs_f64();
        counts
    }

    /// Runs the T1 processes of `rule` on the current mesh.
    fn t1(&mut self, rule: T1Rule) -> TopologyCounts {
        let velocities: Vec<DVec3> = match rule {
            T1Rule::Area(flow) => match flow.area_gradient_velocities(&self.c) {
                Some(v) => v,
                None => return TopologyCounts::default(),
            },
            T1Rule::Field(field, t) => self
                .c
                .mesh
                .vertices
                .iter()
                .map(|&x| field.velocity(x, t))
                .collect(),
        };
        let x = self.c.mesh.vertices.clone();
        let shrinking = |a: u32, b: u32| {
            let (a, b) = (a as usize, b as usize);
            (velocities[b] - velocities[a]).dot(x[b] - x[a]) < 0.0
        };
        let junction_collapses =
            collapse_junction_edges(&mut self.c, &self.params, self.target, &shrinking);
        let strength = match rule {
            T1Rule::Field(field, t) => SeparationStrength::Velocity(field, t),
            _ => SeparationStrength::AreaDecrease,
        };
        let separations = separate_vertices(&mut self.c, &self.params, self.target, &strength);
        TopologyCounts {
            junction_collapses,
            separations,
            ..TopologyCounts::default()
        }
    }
}
