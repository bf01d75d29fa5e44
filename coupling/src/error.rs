//! Why a coupled step or set-up failed.

use polyphase_solver::SolverError;
use polyphase_tracker::TrackerError;
use thiserror::Error;

/// A failure of the coupled simulation, naming the stage.
#[derive(Debug, Error)]
pub enum CouplingError {
    /// The fluid solver rejected its input or did not converge.
    #[error("solver: {0}")]
    Solver(#[from] SolverError),
    /// The tracker could not advance.
    #[error("tracker: {0}")]
    Tracker(#[from] TrackerError),
    /// The scene or time control cannot be simulated (passive scene, bad step limits).
    #[error("{0}")]
    Invalid(String),
}
