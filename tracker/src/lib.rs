//! Multiphase interface tracking (ARCHITECTURE.md "The parts", `tracker/`).
#![deny(unsafe_code)]

pub mod contour;
pub mod contour_tracker;
pub mod curvature;
pub mod front;
pub mod invariants;
pub mod mesh;
pub mod metrics;
pub mod ply;
pub mod query;
pub mod sampling;
pub mod snapshot;
pub mod specks;
pub mod tracker;
pub mod volume_correction;

pub use contour::{MdTree, PhaseSampler};
pub use contour_tracker::ContourTracker;
pub use curvature::CurvatureSampler;
pub use invariants::InvariantError;
pub use mesh::LabeledMesh;
pub use ply::{read_ply, write_ply, PlyError};
pub use polyphase_grid::{GridSpec, PhaseField, PhaseId, VelocityField, OUTSIDE};
pub use query::{MeshQuery, Nearest};
pub use snapshot::TrackerSnapshot;
pub use tracker::{departure_point, InterfaceTracker, StepStats, TrackerError};
