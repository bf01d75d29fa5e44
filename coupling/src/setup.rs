//! Builds a coupled simulation from a validated coupled scene.

use glam::DVec3;
use polyphase_scenes::{PreconditionerSpec, Scene};
use polyphase_solver::{
    LinearSolverSettings, PhaseProps, PreconditionerKind, Solver, SolverConfig,
};
use polyphase_tracker::{ContourTracker, InterfaceTracker, StepStats};

use crate::error::CouplingError;
use crate::sim::{CoupledSim, TimeControl};

/// Solver (free-slip closed box at the scene's solver resolution, at rest) and contour
/// tracker (the scene's resolution, exact initial shapes) for a coupled scene, plus the
/// tracker's first-build stats.
pub fn from_scene(scene: &Scene) -> Result<(CoupledSim<ContourTracker>, StepStats), CouplingError> {
    let (solver, phases, control) = solver_parts(scene)?;
    let initial = |x| scene.initial.sample(x);
    let (mut tracker, first) = ContourTracker::new(
        scene.grid,
        &initial,
        scene.file.phases.len(),
        scene.initial.background,
    );
    tracker.set_volume_targets(scene.volume_targets());
    Ok((CoupledSim::new(solver, tracker, phases, control)?, first))
}

/// The coupled simulation of a coupled scene around a given tracker (a front tracker, or a
/// contouring tracker restored from a checkpoint), with the solver at rest at time 0 until it
/// is restored too.
pub fn with_tracker<T: InterfaceTracker>(
    scene: &Scene,
    tracker: T,
) -> Result<CoupledSim<T>, CouplingError> {
    let (solver, phases, control) = solver_parts(scene)?;
    CoupledSim::new(solver, tracker, phases, control)
}

/// The solver, phase properties and time control a coupled scene asks for.
fn solver_parts(scene: &Scene) -> Result<(Solver, Vec<PhaseProps>, TimeControl), CouplingError> {
    let (Some(grid), Some(spec)) = (scene.solver_grid, scene.file.solver.as_ref()) else {
        return Err(CouplingError::Invalid(format!(
            "scene '{}' is passive (velocity.field is not \"fluid\")",
            scene.file.name
        )));
    };
    let mut config = SolverConfig::closed_box(grid);
    config.gravity = DVec3::from_array(spec.gravity);
    let linear = LinearSolverSettings {
        preconditioner: match spec.preconditioner {
            PreconditionerSpec::Mic0 => PreconditionerKind::Mic0,
            PreconditionerSpec::Multigrid => PreconditionerKind::Multigrid,
        },
        tolerance: spec.tolerance,
        max_iterations: LinearSolverSettings::default().max_iterations,
    };
    config.pressure = linear;
    config.viscosity = linear;
    let solver = Solver::new(config)?;
    let phases = scene
        .file
        .phases
        .iter()
        .map(|p| PhaseProps {
            density: p.density,
            viscosity: p.viscosity,
        })
        .collect();
    let control = TimeControl {
        cfl: spec.cfl,
        max_dt: spec.max_dt.unwrap_or(scene.frame_dt()),
        tracker_travel: scene.tracker_travel(),
    };
    Ok((solver, phases, control))
}
