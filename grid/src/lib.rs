//! The shared vocabulary between the interface tracker and the fluid solver (ARCHITECTURE.md
//! "Data between the parts"): phase ids, regular grids, the phase field the tracker hands to
//! the solver, and the velocity field the solver (or an analytic flow) hands to the tracker.
//! Kept tiny on purpose so that `tracker` and `solver` never depend on each other.
#![deny(unsafe_code)]

pub mod vdb;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Index of a phase in the scene's phase list.
pub type PhaseId = u16;

/// Pseudo-phase on the far side of the domain boundary; closes the interface mesh there.
pub const OUTSIDE: PhaseId = PhaseId::MAX;

/// A regular grid of cubic cells: `dims` cells along each axis starting at `origin`.
/// Nodes (cell corners) number `dims + 1` per axis; samples of a [`PhaseField`] sit at cell centres.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridSpec {
    pub origin: DVec3,
    pub h: f64,
    pub dims: [usize; 3],
}

impl GridSpec {
    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }

    /// Linear index of cell (i, j, k), x fastest.
    pub fn cell_index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Centre of cell (i, j, k).
    pub fn cell_center(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * self.h
    }

    /// Position of node (i, j, k), the lower corner of cell (i, j, k).
    pub fn node(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.h
    }

    /// Length of the box's diagonal: no two points inside it are farther apart.
    pub fn diagonal(&self) -> f64 {
        (self.upper() - self.origin).length()
    }

    /// Upper corner of the domain the grid covers.
    pub fn upper(&self) -> DVec3 {
        self.origin
            + DVec3::new(
                self.dims[0] as f64,
                self.dims[1] as f64,
                self.dims[2] as f64,
            ) * self.h
    }
}

/// Unsigned distance φ to the nearest interface and phase id χ at the cell centres of `grid`:
/// everything the solver knows of the interfaces (ARCHITECTURE.md "PhaseField").
///
/// φ is never infinite: where there is no interface at all (one phase fills the domain, a
/// tracker answers φ = ∞), [`PhaseField::from_cell_centres`] stores [`GridSpec::diagonal`],
/// farther than any interface inside the box could be; so φ ≤ the diagonal everywhere.
#[derive(Clone, Debug)]
pub struct PhaseField {
    pub grid: GridSpec,
    pub phi: Vec<f64>,
    pub chi: Vec<PhaseId>,
}

impl PhaseField {
    /// φ, χ at every cell centre of `grid` from `f`, computed in parallel, stored in cell order
    /// (x fastest); each value depends only on its own cell, so any thread count gives the same.
    /// Distances beyond the grid's diagonal (φ = ∞: no interface) are stored as the diagonal;
    /// NaN is kept, for the solver's input check to name.
    pub fn from_cell_centres(
        grid: &GridSpec,
        f: impl Fn(DVec3) -> (f64, PhaseId) + Sync,
    ) -> PhaseField {
        let [nx, ny, _] = grid.dims;
        let far = grid.diagonal();
        let (phi, chi) = (0..grid.cell_count())
            .into_par_iter()
            .map(|c| {
                let (d, p) = f(grid.cell_center(c % nx, (c / nx) % ny, c / (nx * ny)));
                (if d > far { far } else { d }, p)
            })
            .unzip();
        PhaseField {
            grid: *grid,
            phi,
            chi,
        }
    }
}

/// Anything that gives a velocity (m/s) at a point and time: analytic test flows, or the
/// solver's MAC grid when coupled. Trackers see only this.
pub trait VelocityField: Sync {
    fn velocity(&self, x: DVec3, t: f64) -> DVec3;

    /// Departure point of the trajectory that reaches `x` at `t + dt`: classical RK4 backwards
    /// in time (the analytic test flows are smooth, so the fourth-order error is far below h).
    /// A field that is piecewise in time overrides this to trace each piece on its own.
    fn departure(&self, x: DVec3, t: f64, dt: f64) -> DVec3 {
        rk4_departure(self, x, t, dt)
    }
}

/// The departure point of [`VelocityField::departure`]'s default: classical RK4 backwards in
/// time; for fields that override it and still trace with RK4.
pub fn rk4_departure<V: VelocityField + ?Sized>(v: &V, x: DVec3, t: f64, dt: f64) -> DVec3 {
    let t1 = t + dt;
    let k1 = v.velocity(x, t1);
    let k2 = v.velocity(x - 0.5 * dt * k1, t1 - 0.5 * dt);
    let k3 = v.velocity(x - 0.5 * dt * k2, t1 - 0.5 * dt);
    let k4 = v.velocity(x - dt * k3, t);
    x - dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_interface_reads_as_the_diagonal() {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 0.5,
            dims: [2, 4, 2],
        };
        // The box is 1 × 2 × 1: its diagonal is √6.
        assert!((grid.diagonal() - 6f64.sqrt()).abs() < 1e-15);
        let none = PhaseField::from_cell_centres(&grid, |_| (f64::INFINITY, 3));
        assert!(none.phi.iter().all(|&d| d == grid.diagonal()));
        assert!(none.chi.iter().all(|&c| c == 3));
        let near = PhaseField::from_cell_centres(&grid, |x| (x.y, 0));
        assert_eq!(near.phi[0], 0.25);
        let bad = PhaseField::from_cell_centres(&grid, |_| (f64::NAN, 0));
        assert!(bad.phi.iter().all(|d| d.is_nan()));
    }
}
