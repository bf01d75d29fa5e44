//! Shared scene builders for the solver tests.
#![allow(dead_code)]

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseField, PhaseId};
use polyphase_solver::{
    AdvectionScheme, AxisBoundary, Interpolation, LinearSolverSettings, PhaseProps,
    PreconditionerKind, SolverConfig,
};

/// Grid of `dims` cells of size `h` at the origin.
pub fn grid(dims: [usize; 3], h: f64) -> GridSpec {
    GridSpec {
        origin: DVec3::ZERO,
        h,
        dims,
    }
}

/// Phase field from a function giving (unsigned distance, phase) at a cell centre.
pub fn field(grid: GridSpec, f: impl Fn(DVec3) -> (f64, PhaseId)) -> PhaseField {
    let mut phi = Vec::new();
    let mut chi = Vec::new();
    for k in 0..grid.dims[2] {
        for j in 0..grid.dims[1] {
            for i in 0..grid.dims[0] {
                let (d, c) = f(grid.cell_center(i, j, k));
                phi.push(d);
                chi.push(c);
            }
        }
    }
    PhaseField { grid, phi, chi }
}

/// One phase everywhere.
pub fn uniform(grid: GridSpec) -> PhaseField {
    field(grid, |_| (1e3, 0))
}

/// Horizontal layers: phase k between heights[k-1] and heights[k] (y).
pub fn layers(grid: GridSpec, heights: &[f64]) -> PhaseField {
    field(grid, |x| {
        let phase = heights.iter().filter(|&&y| x.y > y).count() as PhaseId;
        let d = heights
            .iter()
            .map(|y| (x.y - y).abs())
            .fold(f64::INFINITY, f64::min);
        (d, phase)
    })
}

/// Phase 1 inside the ball, phase 0 outside.
pub fn ball(grid: GridSpec, centre: DVec3, radius: f64) -> PhaseField {
    field(grid, |x| {
        let d = (x - centre).length() - radius;
        (d.abs(), PhaseId::from(d < 0.0))
    })
}

/// Tight solver settings for tests that check exactness.
pub fn tight(preconditioner: PreconditionerKind) -> LinearSolverSettings {
    LinearSolverSettings {
        preconditioner,
        tolerance: 1e-12,
        max_iterations: 5000,
    }
}

/// Closed free-slip box without gravity, tight solves.
pub fn config(grid: GridSpec) -> SolverConfig {
    let mut c = SolverConfig::closed_box(grid);
    c.gravity = DVec3::ZERO;
    c.pressure = tight(PreconditionerKind::Mic0);
    c.viscosity = tight(PreconditionerKind::Mic0);
    c.interpolation = Interpolation::Trilinear;
    c.advection = AdvectionScheme::MacCormack;
    c
}

/// All axes periodic.
pub fn periodic(mut c: SolverConfig) -> SolverConfig {
    c.boundaries = [AxisBoundary::Periodic; 3];
    c
}

/// Water / air.
pub const WATER_AIR: [PhaseProps; 2] = [
    PhaseProps {
        density: 1.0,
        viscosity: 0.0,
    },
    PhaseProps {
        density: 1000.0,
        viscosity: 0.0,
    },
];

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, Knuth's constants).
pub struct Lcg(pub u64);

impl Lcg {
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// Largest |divergence|·h relative to the largest face speed.
pub fn relative_divergence(s: &polyphase_solver::Solver, speed: f64) -> f64 {
    let h = s.grid().h;
    s.divergence().iter().fold(0.0f64, |m, d| m.max(d.abs())) * h / speed
}
