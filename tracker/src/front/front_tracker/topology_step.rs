//! The topology part of a front-tracker step (paper 000 Algorithm 1 after collision
//! resolution and mesh improvement): T1 processes — collapses that bring two non-manifold
//! curves together where the flow shortens the edge between them (§5.1.7), then vertex
//! separation of every irregular vertex (§5.1.4–5.1.6, Algorithm 2).

use glam::DVec3;
use polyphase_grid::VelocityField;

use super::FrontTracker;
use crate::front::flow::{FlowStep, MeshFlow};
use crate::front::topology::separate::{
    collapse_junction_edges, separate_vertices, SeparationStrength,
};

/// How a step scores T1 processes.
pub(super) enum T1Rule<'a> {
    /// No T1 processes: the paper gives normal flows no separation rule (§5.1.6).
    Off,
    /// Mean-curvature flow: separations that lower the area, collapses where the flow's own
    /// vertex velocities shorten the edge.
    Area(&'a MeshFlow),
    /// A prescribed velocity field at the end of the step.
    Field(&'a dyn VelocityField, f64),
}

/// Counts of one step's topology changes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TopologyCounts {
    /// Collapses that joined two non-manifold curves (the start of a T1).
    pub junction_collapses: usize,
    /// Vertex separations (the end of a T1).
    pub separations: usize,
}

impl TopologyCounts {
    /// The counts of two steps together.
    pub fn plus(&self, o: &TopologyCounts) -> TopologyCounts {
        TopologyCounts {
            junction_collapses: self.junction_collapses + o.junction_collapses,
            separations: self.separations + o.separations,
        }
    }
}

impl FrontTracker {
    /// Runs the T1 processes of `rule` on the current mesh.
    pub(super) fn topology(&mut self, rule: T1Rule) -> TopologyCounts {
        let velocities: Vec<DVec3> = match rule {
            T1Rule::Off => return TopologyCounts::default(),
            T1Rule::Area(flow) => match flow.step(&self.c, 1) {
                FlowStep::Vertices(v) => v,
                FlowStep::Field(_) => return TopologyCounts::default(),
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
        }
    }
}
