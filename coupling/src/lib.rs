//! The coupled simulation (ARCHITECTURE.md "One coupled step", paper 004 §7.5): the solver's
//! velocity advects the tracker, and the tracker's φ and χ, sampled at the solver's cells, give
//! the per-phase density and viscosity of the next solver step. The tracker may run finer.
#![deny(unsafe_code)]

pub mod contact_angle;
pub mod diagnostics;
pub mod error;
pub mod junction;
pub mod line_tension;
pub mod pending;
pub mod rt_theory;
pub mod setup;
pub mod sim;
pub mod tension;

pub use diagnostics::{
    cross_section, interface_extent, measure, pieces, CrossSection, Measured, Piece,
};
pub use error::CouplingError;
pub use rt_theory::RtLinear;
pub use setup::{build_tracker, from_scene, with_tracker, AnyTracker};
pub use sim::{interface_lag, CapillaryReport, CoupledSim, FrameReport, TimeControl};
pub use tension::SurfaceTension;
