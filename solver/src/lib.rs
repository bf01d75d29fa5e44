//! MAC-grid incompressible multiphase solver (ARCHITECTURE.md "Inside Solver::step"):
//! semi-Lagrangian / MacCormack advection, gravity and body forces, implicit variable viscosity
//! in full stress form, and a variable-density pressure projection with ghost-fluid face
//! densities, on a staggered grid with free-slip / no-slip / periodic boundaries and static
//! solids. Linear systems are solved by CG with MIC(0) or geometric-multigrid preconditioning,
//! in parallel and bit-deterministically.
#![deny(unsafe_code)]
#![warn(missing_docs)]

mod advect;
pub mod bench;
mod config;
mod div_free;
mod error;
mod extension;
mod interp;
mod jump;
mod layout;
mod linalg;
mod mac;
mod phase;
mod point_force;
mod pressure;
mod sample_viscosity;
mod solid;
mod solver;
mod viscosity;

pub use config::{
    AdvectionScheme, AxisBoundary, Interpolation, LinearSolverSettings, PreconditionerKind,
    SolverConfig, Wall,
};
pub use error::SolverError;
pub use jump::{InterfaceFace, PressureJumps};
pub use linalg::pcg::SolveStats;
pub use mac::MacGrid;
pub use phase::PhaseProps;
pub use point_force::PointForces;
pub use solid::{SignedDistance, Solid};
pub use solver::{BodyForce, Solver, SolverState, StepReport, StepTimings};
