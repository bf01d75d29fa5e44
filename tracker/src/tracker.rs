//! The interface every tracker implements (ARCHITECTURE.md "The tracker contract"), so each
//! scene can choose its tracker and every tracker test can run on all of them.

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseField, PhaseId, VelocityField};
use thiserror::Error;

use crate::mesh::LabeledMesh;
use crate::snapshot::TrackerSnapshot;

/// Wall time of each stage of one step, and the sizes that explain it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepStats {
    /// (stage name, seconds), in execution order.
    pub stages: Vec<(&'static str, f64)>,
    /// Cells of the adaptive structure (paper 004 Table 1 "Cells").
    pub cells: usize,
    /// Finest cells the interface crosses (Table 1 "Intersect Cells").
    pub interface_cells: usize,
    /// Per phase, the volume (m³) the step's volume correction added to it, to first order in
    /// its offset (negative: removed); empty when the tracker corrects nothing.
    pub volume_correction: Vec<f64>,
    /// (event name, count) of the step's discrete events, such as the front tracker's
    /// topology changes; empty for a tracker that has none.
    pub events: Vec<(&'static str, usize)>,
}

impl StepStats {
    /// Adds this step's event counts into `total` (a frame's sum over its steps).
    pub fn add_events_to(&self, total: &mut Vec<(&'static str, usize)>) {
        for &(name, n) in &self.events {
            match total.iter_mut().find(|(m, _)| *m == name) {
                Some(entry) => entry.1 += n,
                None => total.push((name, n)),
            }
        }
    }

    /// Adds this step's per-phase volume correction into `total`, grown as needed: a frame's
    /// sum over its steps.
    pub fn add_volume_correction_to(&self, total: &mut Vec<f64>) {
        if total.len() < self.volume_correction.len() {
            total.resize(self.volume_correction.len(), 0.0);
        }
        for (t, v) in total.iter_mut().zip(&self.volume_correction) {
            *t += v;
        }
    }
}

/// Why a step could not be taken.
#[derive(Debug, Error, PartialEq)]
pub enum TrackerError {
    /// The velocity field returned NaN or infinity somewhere along a backtrace.
    #[error("velocity field is not finite near ({x:.6}, {y:.6}, {z:.6}) at t = {t}")]
    NonFiniteVelocity { x: f64, y: f64, z: f64, t: f64 },
}

/// A multiphase interface tracker: advances in a velocity field and answers φ, χ.
pub trait InterfaceTracker: Send + Sync {
    /// Moves the interfaces from time `t` to `t + dt`.
    fn advance(
        &mut self,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> Result<StepStats, TrackerError>;
    /// How far (m) the interfaces may move in one step of this tracker: a run takes enough
    /// steps (passive) or advances the tracker often enough (coupled) to stay within it.
    fn max_travel(&self) -> f64;
    /// Exact φ (unsigned distance) and χ (phase) of the current interface at `x`.
    fn phi_chi(&self, x: DVec3) -> (f64, PhaseId);
    /// φ and χ at the cell centres of `grid`.
    fn sample(&self, grid: &GridSpec) -> PhaseField {
        PhaseField::from_cell_centres(grid, |x| self.phi_chi(x))
    }
    /// φ and χ at the cell centres of `grid` of the interface as `velocity` would carry it
    /// from `t` to `t + dt`, without advancing: each centre is traced back to its departure
    /// point ([`departure_point`]) and the current interface is read there (the
    /// semi-Lagrangian step of paper 004 §3, less the resampling). A coupled run hands this
    /// to the solver between tracker steps, so the solver always sees today's interface.
    fn sample_advected(
        &self,
        grid: &GridSpec,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> PhaseField {
        PhaseField::from_cell_centres(grid, |x| self.phi_chi(departure_point(velocity, x, t, dt)))
    }
    /// The current interface mesh, closed at the domain boundary.
    fn mesh(&self) -> &LabeledMesh;
    /// The whole state for a checkpoint; `None` for a tracker whose runs cannot be resumed
    /// (the default).
    fn snapshot(&self) -> Option<TrackerSnapshot> {
        None
    }
    /// Volume of each phase enclosed by the current mesh.
    fn phase_volumes(&self) -> Vec<f64>;
    /// Number of connected regions (a tracker that tracks them: the front tracker, whose
    /// topology changes create and remove them); `None` by default.
    fn region_count(&self) -> Option<usize> {
        None
    }
    /// Whether the velocity this tracker moves in must be discretely divergence-free near
    /// the interfaces: true for a tracker that carries its surfaces by the velocity alone
    /// (the front tracker), so that any divergence shows up as lost or gained volume; false
    /// (the default) for one that rebuilds and corrects its phases every step.
    fn needs_solenoidal_velocity(&self) -> bool {
        false
    }
}

/// A boxed tracker is a tracker: the run loops hold whichever kind the scene asked for.
impl<T: InterfaceTracker + ?Sized> InterfaceTracker for Box<T> {
    fn advance(
        &mut self,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> Result<StepStats, TrackerError> {
        (**self).advance(velocity, t, dt)
    }
    fn max_travel(&self) -> f64 {
        (**self).max_travel()
    }
    fn phi_chi(&self, x: DVec3) -> (f64, PhaseId) {
        (**self).phi_chi(x)
    }
    fn sample(&self, grid: &GridSpec) -> PhaseField {
        (**self).sample(grid)
    }
    fn sample_advected(
        &self,
        grid: &GridSpec,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> PhaseField {
        (**self).sample_advected(grid, velocity, t, dt)
    }
    fn mesh(&self) -> &LabeledMesh {
        (**self).mesh()
    }
    fn snapshot(&self) -> Option<TrackerSnapshot> {
        (**self).snapshot()
    }
    fn phase_volumes(&self) -> Vec<f64> {
        (**self).phase_volumes()
    }
    fn region_count(&self) -> Option<usize> {
        (**self).region_count()
    }
    fn needs_solenoidal_velocity(&self) -> bool {
        (**self).needs_solenoidal_velocity()
    }
}

/// Departure point of the trajectory that reaches `x` at `t + dt`
/// ([`VelocityField::departure`]: RK4 backwards, or piece by piece for a field that is
/// piecewise in time).
pub fn departure_point(v: &dyn VelocityField, x: DVec3, t: f64, dt: f64) -> DVec3 {
    v.departure(x, t, dt)
}
