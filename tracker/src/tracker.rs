//! The interface every tracker implements (DESIGN.md "InterfaceTracker"), so each scene can
//! choose its tracker and every tracker test can run on all of them.

use polyphase_grid::{GridSpec, PhaseField, VelocityField};
use thiserror::Error;

use crate::mesh::LabeledMesh;

/// Wall time of each stage of one step, and the sizes that explain it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepStats {
    /// (stage name, seconds), in execution order.
    pub stages: Vec<(&'static str, f64)>,
    /// Cells of the adaptive structure (paper 004 Table 1 "Cells").
    pub cells: usize,
    /// Finest cells the interface crosses (Table 1 "Intersect Cells").
    pub interface_cells: usize,
}

/// Why a step could not be taken.
#[derive(Debug, Error, PartialEq)]
pub enum TrackerError {
    /// The velocity field returned NaN or infinity somewhere along a backtrace.
    #[error("velocity field is not finite near ({x:.6}, {y:.6}, {z:.6}) at t = {t}")]
    NonFiniteVelocity { x: f64, y: f64, z: f64, t: f64 },
}

/// A multiphase interface tracker: advances in a velocity field and answers φ, χ.
pub trait InterfaceTracker: Send {
    /// Moves the interfaces from time `t` to `t + dt`.
    fn advance(
        &mut self,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> Result<StepStats, TrackerError>;
    /// φ (unsigned distance) and χ (phase) at the cell centres of `grid`.
    fn sample(&self, grid: &GridSpec) -> PhaseField;
    /// The current interface mesh, closed at the domain boundary.
    fn mesh(&self) -> &LabeledMesh;
    /// Volume of each phase enclosed by the current mesh.
    fn phase_volumes(&self) -> Vec<f64>;
}
