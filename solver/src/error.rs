//! Typed errors of the solver: bad input, bad configuration, linear solves that fail.

use polyphase_grid::PhaseId;
use thiserror::Error;

/// Everything that can go wrong in the solver; the caller sees it instead of a bad field.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SolverError {
    /// The configuration is unusable (zero cells, non-positive cell size, bad tolerance, …).
    #[error("invalid solver configuration: {0}")]
    InvalidConfig(String),
    /// The phase field was sampled on a different grid than the solver's.
    #[error("phase field grid {found} does not match the solver grid {expected}")]
    GridMismatch {
        /// The solver's grid, formatted.
        expected: String,
        /// The phase field's grid, formatted.
        found: String,
    },
    /// A NaN or infinite value in an input (or produced by a solve).
    #[error("non-finite value in {what} at index {index}")]
    NonFinite {
        /// Which input held it (velocity, phi, density, …).
        what: &'static str,
        /// Index of the first offending entry.
        index: usize,
    },
    /// A cell names a phase the phase table does not have.
    #[error("cell {cell} has phase {phase}, but the phase table has {count} phases")]
    UnknownPhase {
        /// The offending phase id.
        phase: PhaseId,
        /// Linear index of the cell.
        cell: usize,
        /// Length of the phase table.
        count: usize,
    },
    /// A phase has non-physical properties.
    #[error("phase {phase}: {reason}")]
    InvalidPhase {
        /// Index into the phase table.
        phase: usize,
        /// What is wrong.
        reason: String,
    },
    /// The time step is not a positive finite number.
    #[error("invalid time step {0}")]
    InvalidTimeStep(f64),
    /// A linear solve did not reach its tolerance within its iteration limit.
    #[error("{system} solve did not converge: relative residual {residual:e} after {iterations} iterations (tolerance {tolerance:e})")]
    NotConverged {
        /// "pressure" or "viscosity".
        system: &'static str,
        /// Iterations performed.
        iterations: usize,
        /// Final relative residual.
        residual: f64,
        /// Requested relative residual.
        tolerance: f64,
    },
}
