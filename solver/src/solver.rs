//! The public solver: owns the MAC velocity and the static solid fractions, and advances them
//! one step at a time (ARCHITECTURE.md "Inside Solver::step"): advect, body forces, implicit
//! viscosity, variable-density projection. A failed step leaves the state untouched.

use crate::advect::advect_by_phase;
use crate::config::{AxisBoundary, Interpolation, SolverConfig};
use crate::error::SolverError;
use crate::extension::{
    all_face_owners, all_seed_phases, carries, extend, owning_phases, UNREACHED,
};
use crate::jump::{InterfaceFace, PressureJumps};
use crate::layout::{idx, unidx, Layout};
use crate::linalg::pcg::SolveStats;
use crate::linalg::vecops::first_non_finite;
use crate::mac::MacGrid;
use crate::phase::{cell_material, face_densities, PhaseProps};
use crate::point_force::PointForces;
use crate::sample_viscosity::SampleViscosity;
use crate::solid::open_fractions;
use crate::{pressure, viscosity};
use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseField, PhaseId};
use rayon::prelude::*;
use std::time::Instant;

/// Extra body acceleration (m/s²) beyond gravity: the hook for surface-tension, buoyancy
/// models, stirring, or anything else a scene adds.
pub trait BodyForce: Sync {
    /// Acceleration at `x` and time `t`.
    fn acceleration(&self, x: DVec3, t: f64) -> DVec3;
}

/// Wall-clock seconds spent per stage of a step (for stats; never affects results).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepTimings {
    /// Velocity advection.
    pub advection: f64,
    /// Gravity and body forces.
    pub forces: f64,
    /// Implicit viscosity (assembly and solve).
    pub viscosity: f64,
    /// Pressure projection (assembly and solve).
    pub pressure: f64,
}

/// What a step did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepReport {
    /// The pressure solve.
    pub pressure: SolveStats,
    /// The viscosity solve; None when every phase is inviscid.
    pub viscosity: Option<SolveStats>,
    /// Time per stage.
    pub timings: StepTimings,
}

/// Everything a step reads or writes besides the configuration (which also fixes the solid
/// fractions): what a checkpoint must hold to continue bit for bit.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverState {
    /// Simulated time (s).
    pub time: f64,
    /// Face velocities per component, as [`MacGrid::component`] lays them out.
    pub velocity: [Vec<f64>; 3],
    /// Cell-centre pressure of the last projection.
    pub pressure: Vec<f64>,
    /// The phases each face's velocity belongs to in the last step, per component, as pairs
    /// (see `extension::seed_phases`; `PhaseId::MAX` for none); `None` before the first step.
    pub seed_phases: Option<[Vec<PhaseId>; 3]>,
    /// The phase owning each face in the last step (see `extension::face_owners`); `None`
    /// before the first step.
    pub owners: Option<[Vec<PhaseId>; 3]>,
}

/// The MAC-grid multiphase solver.
#[derive(Clone, Debug)]
pub struct Solver {
    config: SolverConfig,
    velocity: MacGrid,
    open: [Vec<f64>; 3],
    pressure: Vec<f64>,
    seed_phases: Option<[Vec<PhaseId>; 3]>,
    owners: Option<[Vec<PhaseId>; 3]>,
    time: f64,
}

impl Solver {
    /// A solver at rest at time 0; checks the configuration and rasterises the solids.
    pub fn new(config: SolverConfig) -> Result<Self, SolverError> {
        config.validate()?;
        let layout = Layout {
            n: config.grid.dims,
            periodic: config.boundaries.map(|b| b == AxisBoundary::Periodic),
        };
        let open = [0, 1, 2].map(|a| open_fractions(&config.grid, &layout, &config.solids, a));
        let velocity = MacGrid::zeros(config.grid, layout, config.interpolation);
        let pressure = vec![0.0; layout.cells()];
        Ok(Self {
            config,
            velocity,
            open,
            pressure,
            seed_phases: None,
            owners: None,
            time: 0.0,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SolverConfig {
        &self.config
    }

    /// The cells (a [`PhaseField`] passed to [`Solver::step`] must be sampled on them).
    pub fn grid(&self) -> &GridSpec {
        &self.config.grid
    }

    /// Gravity (m/s²).
    pub fn gravity(&self) -> DVec3 {
        self.config.gravity
    }

    /// The velocity; implements [`polyphase_grid::VelocityField`] for trackers.
    pub fn velocity(&self) -> &MacGrid {
        &self.velocity
    }

    /// Mutable velocity, for initial conditions.
    pub fn velocity_mut(&mut self) -> &mut MacGrid {
        &mut self.velocity
    }

    /// Pressure (Pa) at the cell centres from the last projection, zero mean per fluid region.
    pub fn pressure(&self) -> &[f64] {
        &self.pressure
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// A copy of the evolving state (for checkpoints).
    pub fn state(&self) -> SolverState {
        SolverState {
            time: self.time,
            velocity: self.velocity.comps.clone(),
            pressure: self.pressure.clone(),
            seed_phases: self.seed_phases.clone(),
            owners: self.owners.clone(),
        }
    }

    /// Puts back a state taken by [`Solver::state`] from a solver of the same configuration;
    /// arrays of the wrong size are refused and leave the solver untouched.
    pub fn restore(&mut self, state: SolverState) -> Result<(), SolverError> {
        let sizes = |v: &[Vec<f64>; 3], p: &[f64]| [v[0].len(), v[1].len(), v[2].len(), p.len()];
        let expected = sizes(&self.velocity.comps, &self.pressure);
        let found = sizes(&state.velocity, &state.pressure);
        let fits = |faces: &Option<[Vec<PhaseId>; 3]>, per_face: usize| {
            faces.as_ref().is_none_or(|o| {
                (0..3).all(|a| o[a].len() == per_face * self.velocity.comps[a].len())
            })
        };
        let owners_fit = fits(&state.seed_phases, 2) && fits(&state.owners, 1);
        if expected != found || !owners_fit {
            return Err(SolverError::GridMismatch {
                expected: format!("u, v, w, p sizes {expected:?}"),
                found: format!("{found:?}"),
            });
        }
        self.time = state.time;
        self.velocity.comps = state.velocity;
        self.pressure = state.pressure;
        self.seed_phases = state.seed_phases;
        self.owners = state.owners;
        Ok(())
    }

    /// Open (non-solid) fraction of each face of component `a`; 0 on domain walls.
    pub fn open_fraction(&self, a: usize) -> &[f64] {
        &self.open[a]
    }

    /// Discrete divergence (1/s) per cell of the current velocity.
    pub fn divergence(&self) -> Vec<f64> {
        pressure::divergence(&self.velocity, &self.open)
    }

    /// Largest stable-for-advection time step: cfl·h / (max|u| + √(h|g|)), the gravity term
    /// anticipating the speed a step of free fall adds (Bridson's estimate). Viscosity is
    /// implicit and adds no limit. Infinite for a fluid at rest without gravity.
    pub fn cfl_dt(&self, cfl: f64) -> f64 {
        let h = self.config.grid.h;
        let speed = self.velocity.max_abs() + (h * self.config.gravity.length()).sqrt();
        if speed > 0.0 {
            cfl.max(0.0) * h / speed
        } else {
            f64::INFINITY
        }
    }

    /// The velocity the interfaces move with: on each face, the velocity of the densest phase
    /// within `band` faces of it (continued across its interfaces, see `extension.rs`),
    /// unless the face belongs to a phase at least as dense. A liquid's surface then moves
    /// with the liquid alone: the normal velocity is continuous across an interface anyway,
    /// and the light phase's tangential slip, which interpolation would otherwise blend into
    /// the surface's motion, is left out. The continuation starts from every face the phase
    /// owns, those the interface crosses included: they carry the normal velocity at the
    /// interface, where a continuation from a cell further in would lag a growing wave
    /// (Rayleigh–Taylor grew 20 % too slowly that way at 32 cells per wavelength). Each
    /// face's owner is the one its velocity was computed for (the last step's); `field`
    /// gives them before the first step.
    pub fn interface_velocity(
        &self,
        field: &PhaseField,
        phases: &[PhaseProps],
        band: u8,
    ) -> Result<MacGrid, SolverError> {
        Ok(self.continued_velocity(field, phases, band)?.velocity)
    }

    /// [`Solver::interface_velocity`] made discretely divergence-free again, for a tracker
    /// that moves its surfaces by the velocity alone (the front tracker). The continuation
    /// overwrites light faces without regard to flux: under a ball landing on the floor, the
    /// air cell between them gets the water's downward velocity on its top face and 0 on the
    /// floor, and the ball's bottom is squeezed out of existence (`balls` at 64 lost 31 % of
    /// its water that way). A weighted projection, min Σ w (Δu)² subject to zero divergence,
    /// restores the flux balance: the faces a heavy phase owns and all the continuation wrote
    /// are held (w = 10⁶: every surface keeps its liquid's motion, so a surge front keeps its
    /// speed), the light phase's own faces beyond the continuation take up the correction.
    /// Held faces must reach past the interpolation stencil of every surface point: with
    /// only the continuation's first ring held, the correction's jump at the next ring
    /// sheared the surfaces (`balls` at 64: every liquid +0.3 to +0.9 % by t = 0.2 s and the
    /// mesh 10 K → 65 K triangles by 0.8 s, against within +0.3 % and 7.6 K held whole).
    /// The result samples with [`Interpolation::DivergenceFree`]: trilinear sampling of the
    /// projected field still has sources between the faces.
    pub fn solenoidal_interface_velocity(
        &self,
        field: &PhaseField,
        phases: &[PhaseProps],
        band: u8,
    ) -> Result<MacGrid, SolverError> {
        /// Weights of held and free faces: a held face takes 10⁻⁶ of the correction a free
        /// one next to it would.
        const HELD: f64 = 1e6;
        const FREE: f64 = 1.0;
        /// A phase this many times denser than the lightest keeps its own faces.
        const HEAVY: f64 = 10.0;
        let Continued {
            velocity: mut out,
            layers,
            owners,
        } = self.continued_velocity(field, phases, band)?;
        let lightest = phases
            .iter()
            .map(|p| p.density)
            .fold(f64::INFINITY, f64::min);
        let weights = [0, 1, 2].map(|a| {
            layers[a]
                .par_iter()
                .zip(&owners[a])
                .map(|(&layer, &own)| {
                    let heavy = phases[usize::from(own)].density >= HEAVY * lightest;
                    let held = layer != 0 || heavy;
                    if held {
                        HELD
                    } else {
                        FREE
                    }
                })
                .collect()
        });
        pressure::project(
            &mut out,
            &self.open,
            &weights,
            1.0,
            &self.config.pressure,
            None,
        )?;
        out.interpolation = Interpolation::DivergenceFree;
        Ok(out)
    }

    /// The continuation of [`Solver::interface_velocity`], with where each face's value came
    /// from.
    fn continued_velocity(
        &self,
        field: &PhaseField,
        phases: &[PhaseProps],
        band: u8,
    ) -> Result<Continued, SolverError> {
        let seeds = self.face_phases(field, phases, false)?;
        let density = |p: PhaseId| phases[usize::from(p)].density;
        let mut order = owning_phases(&seeds, &self.open);
        order.sort_by(|&a, &b| density(a).total_cmp(&density(b)).then(a.cmp(&b)));
        let mut out = self.velocity.clone();
        let mut from = [0, 1, 2].map(|a| vec![0u8; out.comps[a].len()]);
        for &phase in &order {
            let ext = extend(
                &self.velocity,
                &self.open,
                &|a, f| seeds[a][f] == phase,
                band,
            );
            let parts = ext.field.comps.iter().zip(&ext.layer).zip(&seeds);
            for ((comp, from), ((values, layers), own)) in
                out.comps.iter_mut().zip(from.iter_mut()).zip(parts)
            {
                comp.par_iter_mut()
                    .zip(from.par_iter_mut())
                    .zip(values)
                    .zip(layers)
                    .zip(own)
                    .for_each(|((((o, f), &v), &layer), &own)| {
                        let lighter = density(own) < density(phase);
                        if layer != 0 && layer != UNREACHED && lighter {
                            *o = v;
                            *f = layer;
                        }
                    });
            }
        }
        Ok(Continued {
            velocity: out,
            layers: from,
            owners: seeds,
        })
    }

    /// The phases each face's current velocity belongs to: [`SolverState::seed_phases`]
    /// when `pure`, else [`SolverState::owners`]; from `field` before the first step.
    fn face_phases(
        &self,
        field: &PhaseField,
        phases: &[PhaseProps],
        pure: bool,
    ) -> Result<[Vec<PhaseId>; 3], SolverError> {
        let material = cell_material(field, phases)?;
        let layout = &self.velocity.layout;
        Ok(match (pure, &self.seed_phases, &self.owners) {
            (true, Some(p), _) => p.clone(),
            (false, _, Some(o)) => o.clone(),
            (true, None, _) => all_seed_phases(&material, layout),
            (false, _, None) => all_face_owners(&material, layout),
        })
    }

    /// Velocity at each cell centre (cell order, x fastest) in the field of the cell's own
    /// phase χ from `field`: the mean of the cell's two faces per axis, each phase's velocity
    /// continued two faces across its interfaces. A cell the interface has just swept over
    /// still has faces holding the other phase's velocity; this reads its own phase's instead
    /// (for output grids).
    pub fn cell_velocities(
        &self,
        field: &PhaseField,
        phases: &[PhaseProps],
    ) -> Result<Vec<DVec3>, SolverError> {
        let layout = self.velocity.layout;
        let owners = self.face_phases(field, phases, true)?;
        let group = cell_material(field, phases)?.group;
        let mut present: Vec<PhaseId> = group.clone();
        present.sort_unstable();
        present.dedup();
        let mut out = vec![DVec3::ZERO; layout.cells()];
        for phase in present {
            let ext = extend(
                &self.velocity,
                &self.open,
                &|a, f| carries(&owners[a], f, phase),
                2,
            );
            out.par_iter_mut().enumerate().for_each(|(c, v)| {
                if group[c] != phase {
                    return;
                }
                let p = unidx(layout.n, c);
                for a in 0..3 {
                    let dims = layout.face_dims(a);
                    let mut q = p;
                    q[a] = layout.node_above(a, p[a]);
                    let comp = &ext.field.comps[a];
                    v[a] = 0.5 * (comp[idx(dims, p)] + comp[idx(dims, q)]);
                }
            });
        }
        Ok(out)
    }

    /// Advances by `dt` with gravity only.
    pub fn step(
        &mut self,
        field: &PhaseField,
        phases: &[PhaseProps],
        dt: f64,
    ) -> Result<StepReport, SolverError> {
        self.step_inner(field, phases, dt, None, None)
    }

    /// Advances by `dt` with gravity, the pressure jumping by `jumps` across interface faces
    /// (surface tension's Laplace jump; see [`PressureJumps`]) and the impulses of `points`
    /// (its pull along triple curves; see [`PointForces`]).
    pub fn step_with_tension(
        &mut self,
        field: &PhaseField,
        phases: &[PhaseProps],
        dt: f64,
        jumps: &PressureJumps,
        points: &PointForces,
    ) -> Result<StepReport, SolverError> {
        self.step_inner(field, phases, dt, None, Some((jumps, points)))
    }

    /// The faces between cells of different phases in `field`, with where the interface
    /// crosses each (from φ): where [`PressureJumps`] act.
    pub fn interface_faces(&self, field: &PhaseField) -> Result<Vec<InterfaceFace>, SolverError> {
        let n = self.config.grid.cell_count();
        if field.grid != self.config.grid || field.phi.len() != n || field.chi.len() != n {
            return Err(SolverError::GridMismatch {
                expected: format!("{:?}, {n} samples", self.config.grid),
                found: format!("{:?}, {} samples", field.grid, field.phi.len()),
            });
        }
        Ok(crate::jump::interface_faces(field, &self.velocity.layout))
    }

    /// Advances by `dt` with gravity plus `force`.
    pub fn step_with_force(
        &mut self,
        field: &PhaseField,
        phases: &[PhaseProps],
        dt: f64,
        force: &dyn BodyForce,
    ) -> Result<StepReport, SolverError> {
        self.step_inner(field, phases, dt, Some(force), None)
    }

    /// Projects the current velocity only (initial conditions, tests); `dt` scales the
    /// reported pressure.
    pub fn project(
        &mut self,
        field: &PhaseField,
        phases: &[PhaseProps],
        dt: f64,
    ) -> Result<SolveStats, SolverError> {
        self.check_inputs(field, dt)?;
        let material = cell_material(field, phases)?;
        let mut vel = self.velocity.clone();
        let rho = [0, 1, 2].map(|a| face_densities(&material, &vel.layout, a));
        let out = pressure::project(&mut vel, &self.open, &rho, dt, &self.config.pressure, None)?;
        self.velocity = vel;
        self.pressure = out.pressure;
        Ok(out.stats)
    }

    fn check_inputs(&self, field: &PhaseField, dt: f64) -> Result<(), SolverError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(SolverError::InvalidTimeStep(dt));
        }
        if field.grid != self.config.grid {
            return Err(SolverError::GridMismatch {
                expected: format!("{:?}", self.config.grid),
                found: format!("{:?}", field.grid),
            });
        }
        for a in 0..3 {
            if let Some(index) = first_non_finite(&self.velocity.comps[a]) {
                return Err(SolverError::NonFinite {
                    what: "velocity",
                    index,
                });
            }
        }
        Ok(())
    }

    fn step_inner(
        &mut self,
        field: &PhaseField,
        phases: &[PhaseProps],
        dt: f64,
        force: Option<&dyn BodyForce>,
        tension: Option<(&PressureJumps, &PointForces)>,
    ) -> Result<StepReport, SolverError> {
        self.check_inputs(field, dt)?;
        let material = cell_material(field, phases)?;
        let mut timings = StepTimings::default();
        let open = &self.open;

        let t0 = Instant::now();
        let mut start = self.velocity.clone();
        for (comp, op) in start.comps.iter_mut().zip(open) {
            comp.par_iter_mut().zip(op).for_each(|(u, s)| {
                if *s == 0.0 {
                    *u = 0.0
                }
            });
        }
        let owners = all_face_owners(&material, &start.layout);
        let pure = all_seed_phases(&material, &start.layout);
        let before = self.seed_phases.as_ref().unwrap_or(&pure);
        let mut vel = advect_by_phase(&start, open, before, &owners, dt, self.config.advection);
        timings.advection = t0.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let g = self.config.gravity;
        let time = self.time;
        for a in 0..3 {
            let dims = vel.layout.face_dims(a);
            let positions = &start;
            vel.comps[a].par_iter_mut().enumerate().for_each(|(f, u)| {
                if open[a][f] == 0.0 {
                    return;
                }
                let mut acc = g[a];
                if let Some(fo) = force {
                    acc += fo.acceleration(positions.face_position(a, unidx(dims, f)), time)[a];
                }
                *u += dt * acc;
            });
        }
        timings.forces = t1.elapsed().as_secs_f64();

        let rho = [0, 1, 2].map(|a| face_densities(&material, &vel.layout, a));
        if let Some((_, points)) = tension {
            points.apply(&mut vel, open, &rho, dt);
        }
        let t2 = Instant::now();
        let viscous = material.mu.iter().any(|&m| m > 0.0);
        let viscosity = if viscous {
            let system = viscosity::ViscousSystem::new(
                vel.layout,
                self.config.grid.h,
                dt,
                &self.config.boundaries,
                open,
                &rho,
                &SampleViscosity::new(&material, phases, &vel.layout, self.config.grid.h),
            );
            Some(viscosity::solve(&system, &mut vel, &self.config.viscosity)?.0)
        } else {
            None
        };
        timings.viscosity = t2.elapsed().as_secs_f64();

        let t3 = Instant::now();
        let dense = tension.map(|(j, _)| j.dense(&vel.layout));
        let projected = pressure::project(
            &mut vel,
            open,
            &rho,
            dt,
            &self.config.pressure,
            dense.as_ref(),
        )?;
        timings.pressure = t3.elapsed().as_secs_f64();

        for a in 0..3 {
            if let Some(index) = first_non_finite(&vel.comps[a]) {
                return Err(SolverError::NonFinite {
                    what: "velocity after step",
                    index,
                });
            }
        }
        self.velocity = vel;
        self.pressure = projected.pressure;
        self.seed_phases = Some(pure);
        self.owners = Some(owners);
        self.time += dt;
        Ok(StepReport {
            pressure: projected.stats,
            viscosity,
            timings,
        })
    }
}

/// A velocity continued across interfaces ([`Solver::interface_velocity`]) and its sources.
struct Continued {
    velocity: MacGrid,
    /// Per face, the ring its value came from: 0 for the face's own phase, k for the k-th ring
    /// of a denser phase's continuation.
    layers: [Vec<u8>; 3],
    /// Per face, the phase that owns it.
    owners: [Vec<PhaseId>; 3],
}
