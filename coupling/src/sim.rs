//! One coupled step and one frame of steps, with adaptive dt and per-stage timings.

use std::time::Instant;

use glam::DVec3;
use polyphase_solver::{MacGrid, PhaseProps, Solver, SolverState};
use polyphase_tracker::{departure_point, InterfaceTracker, PhaseField, PhaseId, StepStats};

use crate::error::CouplingError;
use crate::pending::PendingSteps;
use crate::tension::SurfaceTension;

/// Time-step control. Solver: dt = min(cfl·h/(max|u| + √(h|g|)), max_dt), shortened so a
/// frame ends exactly on its time. Tracker (loose coupling, paper 004 §7.5): it advances once
/// the fluid has moved up to `tracker_travel` metres since its last advance (and at every
/// frame end), through each of those steps' velocities in turn; each tracker step
/// resamples the mesh and costs volume, so fewer, larger tracker steps are cheaper and
/// conserve better.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeControl {
    /// Solver CFL number (see [`Solver::cfl_dt`]).
    pub cfl: f64,
    /// Largest solver step in seconds.
    pub max_dt: f64,
    /// Largest distance (m) the fluid may move during one tracker step.
    pub tracker_travel: f64,
}

/// What one frame of coupled steps did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameReport {
    /// Solver steps taken.
    pub steps: usize,
    /// Tracker steps taken.
    pub tracker_steps: usize,
    /// Smallest and largest dt used.
    pub dt_range: (f64, f64),
    /// (stage, seconds) summed over the steps, in execution order: sampling, solver stages,
    /// tracker stages.
    pub stages: Vec<(&'static str, f64)>,
    /// Pressure CG iterations summed over the steps.
    pub pressure_iterations: usize,
    /// Viscosity CG iterations summed over the steps.
    pub viscosity_iterations: usize,
    /// Tracker cells and interface cells after the last step.
    pub cells: usize,
    /// Finest tracker cells the interface crosses after the last step.
    pub interface_cells: usize,
    /// Largest [`interface_lag`] of the frame's tracker steps, in solver cells.
    pub interface_lag: f64,
    /// Per phase, the volume (m³) the tracker's volume correction added over the frame
    /// ([`StepStats::volume_correction`], summed).
    pub volume_correction: Vec<f64>,
    /// The tracker's events ([`StepStats::events`]: merge snaps, T1, T2), summed over the
    /// frame's tracker steps.
    pub events: Vec<(&'static str, usize)>,
    /// With surface tension: the capillary time-step limit (s) and, summed over the steps,
    /// the interface faces that carried a tension and those where no interface of their pair
    /// was found near the crossing (no jump there).
    pub capillary: Option<CapillaryReport>,
}

/// Surface tension's part of a [`FrameReport`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CapillaryReport {
    /// The capillary time-step limit (s), [`SurfaceTension::capillary_dt`].
    pub dt_limit: f64,
    /// Interface faces that carried a tension, summed over the frame's steps.
    pub faces: usize,
    /// Of those, faces without an interface of their pair near the crossing (no jump).
    pub missed: usize,
}

impl FrameReport {
    fn add(&mut self, name: &'static str, secs: f64) {
        match self.stages.iter_mut().find(|(n, _)| *n == name) {
            Some(e) => e.1 += secs,
            None => self.stages.push((name, secs)),
        }
    }
}

/// How far the interface the solver saw for the last step before a tracker step (`seen`, the
/// previous mesh read at departure points) lies from the one the tracker step contoured
/// (`now`), in solver cells: the largest difference of the distance to the two interfaces
/// over the cells whose centres lie within h/8 of the contoured one. `seen`'s φ is the old
/// mesh's distance read at the departure point, which a flow that compresses or stretches
/// the interface's neighbourhood by a factor J scales by J; that close to the interface it
/// adds at most (J − 1)·h/8, not a lag. The solver's interface lags by this much; resampling
/// and the volume correction alone give a few hundredths of a cell.
pub fn interface_lag(seen: &PhaseField, now: &PhaseField) -> f64 {
    let h = now.grid.h;
    let mut worst: f64 = 0.0;
    for c in 0..now.phi.len() {
        let (a, b) = (seen.phi[c], now.phi[c]);
        if b >= 0.125 * h {
            continue;
        }
        let gap = if seen.chi[c] == now.chi[c] {
            (a - b).abs()
        } else {
            a + b
        };
        worst = worst.max(gap / h);
    }
    worst
}

/// A solver and a tracker advancing together.
pub struct CoupledSim<T: InterfaceTracker> {
    solver: Solver,
    tracker: T,
    phases: Vec<PhaseProps>,
    control: TimeControl,
    time: f64,
    steps: usize,
    pending: Option<PendingSteps>,
    tension: Option<SurfaceTension>,
    /// The interface velocity of the solver's current state (the last step's end velocity):
    /// the next step's start velocity, which reads the same faces and owners, so it is kept
    /// rather than computed again. `None` before the first step and after a restore.
    end_velocity: Option<MacGrid>,
    /// φ, χ at the solver's cells as the last tracker step left them: the next step, with no
    /// solver steps pending, reads exactly this, so it is kept rather than sampled again.
    /// `None` once read, while steps are pending, and after a restore.
    sampled: Option<PhaseField>,
}

impl<T: InterfaceTracker> CoupledSim<T> {
    /// Couples a solver at rest and a tracker at time 0.
    pub fn new(
        solver: Solver,
        tracker: T,
        phases: Vec<PhaseProps>,
        control: TimeControl,
    ) -> Result<Self, CouplingError> {
        if !(control.cfl.is_finite() && control.cfl > 0.0) {
            return Err(CouplingError::Invalid(format!(
                "cfl {} must be positive",
                control.cfl
            )));
        }
        if !(control.tracker_travel.is_finite() && control.tracker_travel > 0.0) {
            return Err(CouplingError::Invalid(format!(
                "tracker_travel {} must be positive",
                control.tracker_travel
            )));
        }
        if control.max_dt.is_nan() || control.max_dt <= 0.0 {
            return Err(CouplingError::Invalid(format!(
                "max_dt {} must be positive",
                control.max_dt
            )));
        }
        Ok(Self {
            solver,
            tracker,
            phases,
            control,
            time: 0.0,
            steps: 0,
            pending: None,
            tension: None,
            end_velocity: None,
            sampled: None,
        })
    }

    /// Adds surface tension (measured on the tracker's current mesh from now on).
    pub fn set_tension(&mut self, mut tension: SurfaceTension) {
        tension.refresh(self.tracker.mesh());
        self.tension = Some(tension);
    }

    /// The capillary time-step limit (∞ without surface tension).
    pub fn capillary_dt(&self) -> f64 {
        self.tension.as_ref().map_or(f64::INFINITY, |t| {
            t.capillary_dt(&self.phases, self.solver.grid().h)
        })
    }

    /// The fluid solver.
    pub fn solver(&self) -> &Solver {
        &self.solver
    }

    /// The phases' densities and viscosities.
    pub fn phases(&self) -> &[PhaseProps] {
        &self.phases
    }

    /// The mean velocity against gravity of the solver cells whose phase is `phase` (each in
    /// its own phase's field, [`Solver::cell_velocities`]); `None` when no cell holds it or
    /// there is no gravity. A bubble's rise velocity in the sense of Hysing et al. (2009).
    pub fn rise_velocity(&self, phase: PhaseId) -> Result<Option<f64>, CouplingError> {
        let up = -self.solver.gravity().normalize_or_zero();
        if up == DVec3::ZERO {
            return Ok(None);
        }
        let field = self.tracker.sample(self.solver.grid());
        let velocities = self.solver.cell_velocities(&field, &self.phases)?;
        let (mut sum, mut n) = (0.0, 0usize);
        for (v, &chi) in velocities.iter().zip(&field.chi) {
            if chi == phase {
                sum += v.dot(up);
                n += 1;
            }
        }
        Ok((n > 0).then(|| sum / n as f64))
    }

    /// The mean pressure (Pa) of the solver cells of `inside` minus that of the cells of
    /// `outside`; `None` when either has no cell. A static drop's Laplace jump σκ.
    pub fn pressure_jump(&self, inside: PhaseId, outside: PhaseId) -> Option<f64> {
        let field = self.tracker.sample(self.solver.grid());
        let mean = |phase: PhaseId| {
            let (mut sum, mut n) = (0.0, 0usize);
            for (p, &chi) in self.solver.pressure().iter().zip(&field.chi) {
                if chi == phase {
                    sum += p;
                    n += 1;
                }
            }
            (n > 0).then(|| sum / n as f64)
        };
        Some(mean(inside)? - mean(outside)?)
    }

    /// (centre coordinate, mean velocity `component`) of each layer of solver cells across
    /// `axis`, lowest first, each cell's velocity in its own phase's field
    /// ([`Solver::cell_velocities`]): the profile of a shear flow along the layers.
    pub fn velocity_profile(
        &self,
        component: usize,
        axis: usize,
    ) -> Result<Vec<(f64, f64)>, CouplingError> {
        let grid = *self.solver.grid();
        let field = self.tracker.sample(&grid);
        let velocities = self.solver.cell_velocities(&field, &self.phases)?;
        let n = grid.dims;
        let mut sums = vec![0.0; n[axis]];
        for (c, v) in velocities.iter().enumerate() {
            let layer = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])][axis];
            sums[layer] += v[component];
        }
        let per_layer = (grid.cell_count() / n[axis]) as f64;
        Ok(sums
            .iter()
            .enumerate()
            .map(|(j, s)| {
                let centre = grid.origin[axis] + (j as f64 + 0.5) * grid.h;
                (centre, s / per_layer)
            })
            .collect())
    }

    /// The interface tracker.
    pub fn tracker(&self) -> &T {
        &self.tracker
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Coupled steps taken so far.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Puts back the state of a frame end (from a checkpoint): the solver's state, the
    /// simulated time and the step count. At a frame end the tracker is in step with the
    /// solver, so no pending solver steps are kept.
    pub fn restore(
        &mut self,
        solver: SolverState,
        time: f64,
        steps: usize,
    ) -> Result<(), CouplingError> {
        self.solver.restore(solver)?;
        self.time = time;
        self.steps = steps;
        self.pending = None;
        self.end_velocity = None;
        self.sampled = None;
        Ok(())
    }

    /// One coupled step of `dt`: φ, χ at the solver's cells → solver step; the tracker then
    /// advances over all pending steps if they moved the fluid `tracker_travel` or `sync`
    /// is set. Stage timings are added to `report`.
    pub fn step(
        &mut self,
        dt: f64,
        sync: bool,
        report: &mut FrameReport,
    ) -> Result<(), CouplingError> {
        let t0 = Instant::now();
        let grid = *self.solver.grid();
        let field = match &self.pending {
            Some(p) => self
                .tracker
                .sample_advected(&grid, p, p.start(), p.duration()),
            None => match self.sampled.take() {
                Some(field) => field,
                None => self.tracker.sample(&grid),
            },
        };
        report.add("sample", t0.elapsed().as_secs_f64());
        // The tracker's velocity reaches as far past each interface as the fluid may travel
        // before the tracker catches up, plus the interpolation stencil.
        let band = (self.control.tracker_travel / grid.h).ceil().min(250.0) as u8 + 2;
        let t1 = Instant::now();
        let before = match self.end_velocity.take() {
            Some(v) => v,
            None => self.interface_velocity(&field, band)?,
        };
        let mut interface_secs = t1.elapsed().as_secs_f64();
        let solved = match &self.tension {
            Some(tension) => {
                let t = Instant::now();
                let faces = self.solver.interface_faces(&field)?;
                let locate = |x| match &self.pending {
                    Some(p) => departure_point(p, x, p.start(), p.duration()),
                    None => x,
                };
                let (jumps, stats) = tension.jumps(&faces, locate, 2.0 * grid.h);
                let c = report.capillary.get_or_insert_with(Default::default);
                c.faces += stats.faces;
                c.missed += stats.missed;
                report.add("tension", t.elapsed().as_secs_f64());
                let lines = tension.line_forces();
                self.solver
                    .step_with_tension(&field, &self.phases, dt, &jumps, lines)?
            }
            None => self.solver.step(&field, &self.phases, dt)?,
        };
        report.add("advect_velocity", solved.timings.advection);
        report.add("forces", solved.timings.forces);
        report.add("viscosity", solved.timings.viscosity);
        report.add("pressure", solved.timings.pressure);
        report.pressure_iterations += solved.pressure.iterations;
        report.viscosity_iterations += solved.viscosity.map_or(0, |v| v.iterations);
        let t2 = Instant::now();
        let after = self.interface_velocity(&field, band)?;
        self.end_velocity = Some(after.clone());
        // The interfaces move over the step with the mean of its start and end velocities
        // (trapezoidal rule): the end velocity alone runs a falling drop ahead by g·t·dt/2.
        let mut velocity = after;
        for a in 0..3 {
            for (u, b) in velocity
                .component_mut(a)
                .iter_mut()
                .zip(before.component(a))
            {
                *u = 0.5 * (*u + b);
            }
        }
        interface_secs += t2.elapsed().as_secs_f64();
        report.add("interface_velocity", interface_secs);
        let time = self.time;
        let pending = self.pending.get_or_insert_with(|| PendingSteps::new(time));
        pending.push(dt, velocity);
        let travel = pending.travel();
        self.time += dt;
        self.steps += 1;
        // Surface tension reads κ off the mesh, so the mesh must follow every step: a κ that
        // lags the shape by the tracker's usual several steps drives capillary waves unstable
        // (measured: a static drop blew up within five frames).
        if sync || travel >= self.control.tracker_travel || self.tension.is_some() {
            self.flush(report)?;
        }
        Ok(())
    }

    /// The velocity the tracker moves in (see [`Solver::interface_velocity`]), made
    /// divergence-free again for a tracker that asks for it.
    fn interface_velocity(&self, field: &PhaseField, band: u8) -> Result<MacGrid, CouplingError> {
        Ok(if self.tracker.needs_solenoidal_velocity() {
            self.solver
                .solenoidal_interface_velocity(field, &self.phases, band)?
        } else {
            self.solver.interface_velocity(field, &self.phases, band)?
        })
    }

    /// Advances the tracker over the pending solver steps, each in its own velocity
    /// (divergence-free, as every step's velocity is).
    fn flush(&mut self, report: &mut FrameReport) -> Result<(), CouplingError> {
        let Some(pending) = self.pending.take() else {
            return Ok(());
        };
        let (start, duration) = (pending.start(), pending.duration());
        let grid = *self.solver.grid();
        // The advected φ, χ before the tracker step and the tracker's after it: their gap is
        // the step's interface lag; both count as sampling.
        let t = Instant::now();
        let seen = self
            .tracker
            .sample_advected(&grid, &pending, start, duration);
        let mut sampling = t.elapsed().as_secs_f64();
        let tracked: StepStats = self.tracker.advance(&pending, start, duration)?;
        if let Some(tension) = &mut self.tension {
            let t = Instant::now();
            tension.refresh(self.tracker.mesh());
            report.add("curvature", t.elapsed().as_secs_f64());
        }
        let t = Instant::now();
        let now = self.tracker.sample(&grid);
        sampling += t.elapsed().as_secs_f64();
        report.add("sample", sampling);
        let lag = interface_lag(&seen, &now);
        report.interface_lag = report.interface_lag.max(lag);
        self.sampled = Some(now);
        for &(name, secs) in &tracked.stages {
            report.add(name, secs);
        }
        report.cells = tracked.cells;
        report.interface_cells = tracked.interface_cells;
        tracked.add_volume_correction_to(&mut report.volume_correction);
        tracked.add_events_to(&mut report.events);
        report.tracker_steps += 1;
        Ok(())
    }

    /// Steps until `t_end` with adaptive dt; the last step lands exactly on `t_end`, and a step
    /// that would leave a sliver under half a step splits the remainder in two instead.
    pub fn advance_to(&mut self, t_end: f64) -> Result<FrameReport, CouplingError> {
        let mut report = FrameReport {
            dt_range: (f64::INFINITY, 0.0),
            ..FrameReport::default()
        };
        while self.time < t_end {
            let remaining = t_end - self.time;
            let capillary = self.capillary_dt();
            let limit = self
                .solver
                .cfl_dt(self.control.cfl)
                .min(self.control.max_dt)
                .min(capillary);
            if capillary.is_finite() {
                report
                    .capillary
                    .get_or_insert_with(Default::default)
                    .dt_limit = capillary;
            }
            let dt = if remaining <= limit * (1.0 + 1e-9) {
                remaining
            } else if remaining < 2.0 * limit {
                0.5 * remaining
            } else {
                limit
            };
            let last = remaining <= limit * (1.0 + 1e-9);
            self.step(dt, last, &mut report)?;
            if last {
                self.time = t_end;
            }
            report.steps += 1;
            report.dt_range = (report.dt_range.0.min(dt), report.dt_range.1.max(dt));
        }
        Ok(report)
    }
}
