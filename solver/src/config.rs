//! Solver configuration: grid, boundaries, gravity, schemes, linear-solver settings, solids.

use crate::error::SolverError;
use crate::solid::Solid;
use glam::DVec3;
use polyphase_grid::GridSpec;

/// One wall of the domain box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Wall {
    /// Zero normal velocity, zero tangential stress.
    FreeSlip,
    /// Zero normal velocity, tangential velocity equal to the wall's (moving lids, Couette).
    NoSlip {
        /// Velocity of the wall; its normal component is ignored (walls do not move normally).
        velocity: DVec3,
    },
}

/// Boundary condition along one axis of the domain box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AxisBoundary {
    /// The domain repeats along this axis.
    Periodic,
    /// Solid walls at both ends.
    Walls {
        /// Wall at the lower end of the axis.
        low: Wall,
        /// Wall at the upper end of the axis.
        high: Wall,
    },
}

impl AxisBoundary {
    /// Free-slip walls at both ends: the default closed box.
    pub const FREE_SLIP: AxisBoundary = AxisBoundary::Walls {
        low: Wall::FreeSlip,
        high: Wall::FreeSlip,
    };
}

/// Velocity interpolation used for advection and for the [`polyphase_grid::VelocityField`] view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Trilinear: cheap, diffusive.
    Trilinear,
    /// Tensor-product monotone cubic Hermite (Fritsch–Carlson limited): sharper, no new extrema.
    MonotoneCubic,
    /// Catmull–Rom along each component's axis and its running sum's derivative across: no
    /// divergence anywhere when the field has none per cell (interfaces moved in it keep
    /// their volumes; see `div_free.rs`).
    DivergenceFree,
}

/// Velocity self-advection scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AdvectionScheme {
    /// No advection (Stokes flow, tests of the other stages).
    None,
    /// First-order semi-Lagrangian with an RK2 backtrace.
    SemiLagrangian,
    /// MacCormack correction on top of semi-Lagrangian, clamped to the departure stencil's range
    /// (Selle et al. 2008); falls back to the semi-Lagrangian value where the clamp triggers.
    MacCormack,
}

/// Preconditioner of a conjugate-gradient solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PreconditionerKind {
    /// Modified incomplete Cholesky, level 0 (Bridson's τ = 0.97, safety σ = 0.25).
    Mic0,
    /// One symmetric V-cycle of geometric multigrid (aggregation, red–black Gauss–Seidel).
    Multigrid,
}

/// Settings of one preconditioned CG solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearSolverSettings {
    /// Which preconditioner.
    pub preconditioner: PreconditionerKind,
    /// Stop when ‖r‖₂ ≤ tolerance·‖b‖₂.
    pub tolerance: f64,
    /// Give up (with [`SolverError::NotConverged`]) after this many iterations.
    pub max_iterations: usize,
}

impl Default for LinearSolverSettings {
    fn default() -> Self {
        Self {
            preconditioner: PreconditionerKind::Mic0,
            tolerance: 1e-8,
            max_iterations: 2000,
        }
    }
}

/// Everything fixed for the life of a [`crate::Solver`].
#[derive(Clone, Debug)]
pub struct SolverConfig {
    /// The MAC grid's cells (pressure at their centres).
    pub grid: GridSpec,
    /// Boundary condition per axis (x, y, z).
    pub boundaries: [AxisBoundary; 3],
    /// Gravity (m/s²); −y by convention (ARCHITECTURE.md "Conventions").
    pub gravity: DVec3,
    /// Velocity advection scheme.
    pub advection: AdvectionScheme,
    /// Velocity interpolation.
    pub interpolation: Interpolation,
    /// Pressure projection solve.
    pub pressure: LinearSolverSettings,
    /// Implicit viscosity solve.
    pub viscosity: LinearSolverSettings,
    /// Static solid obstacles.
    pub solids: Vec<Solid>,
}

impl SolverConfig {
    /// A closed free-slip box with gravity −9.81 ŷ, MacCormack advection, trilinear
    /// interpolation and MIC(0)-PCG solves to 1e-8.
    pub fn closed_box(grid: GridSpec) -> Self {
        Self {
            grid,
            boundaries: [AxisBoundary::FREE_SLIP; 3],
            gravity: DVec3::new(0.0, -9.81, 0.0),
            advection: AdvectionScheme::MacCormack,
            interpolation: Interpolation::Trilinear,
            pressure: LinearSolverSettings::default(),
            viscosity: LinearSolverSettings::default(),
            solids: Vec::new(),
        }
    }

    /// Checks the values a solver cannot work with.
    pub fn validate(&self) -> Result<(), SolverError> {
        let g = &self.grid;
        if g.dims.contains(&0) {
            return Err(SolverError::InvalidConfig(format!(
                "grid dims {:?} has a zero",
                g.dims
            )));
        }
        if !(g.h.is_finite() && g.h > 0.0) {
            return Err(SolverError::InvalidConfig(format!(
                "cell size {} must be positive",
                g.h
            )));
        }
        if !g.origin.is_finite() {
            return Err(SolverError::InvalidConfig(
                "grid origin is not finite".into(),
            ));
        }
        if !self.gravity.is_finite() {
            return Err(SolverError::InvalidConfig("gravity is not finite".into()));
        }
        for b in &self.boundaries {
            if let AxisBoundary::Walls { low, high } = b {
                for w in [low, high] {
                    if let Wall::NoSlip { velocity } = w {
                        if !velocity.is_finite() {
                            return Err(SolverError::InvalidConfig(
                                "wall velocity is not finite".into(),
                            ));
                        }
                    }
                }
            }
        }
        for (name, s) in [("pressure", &self.pressure), ("viscosity", &self.viscosity)] {
            if !(s.tolerance.is_finite() && s.tolerance > 0.0) {
                return Err(SolverError::InvalidConfig(format!(
                    "{name} tolerance {} must be positive",
                    s.tolerance
                )));
            }
            if s.max_iterations == 0 {
                return Err(SolverError::InvalidConfig(format!(
                    "{name} max_iterations is 0"
                )));
            }
        }
        Ok(())
    }
}
