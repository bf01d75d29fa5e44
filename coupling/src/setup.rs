//! Builds trackers and coupled simulations from validated scenes.

use std::time::Instant;

use glam::DVec3;
use polyphase_scenes::{BoundaryKind, BoundarySpec, PreconditionerSpec, Scene, TrackerKind, WALLS};
use polyphase_solver::{
    AxisBoundary, LinearSolverSettings, PhaseProps, PreconditionerKind, Solver, SolverConfig, Wall,
};
use polyphase_tracker::front::front_tracker::FrontTracker;
use polyphase_tracker::{ContourTracker, InterfaceTracker, StepStats, TrackerSnapshot};

use crate::error::CouplingError;
use crate::sim::{CoupledSim, TimeControl};
use crate::tension::SurfaceTension;

/// Whichever tracker a scene asked for.
pub type AnyTracker = Box<dyn InterfaceTracker>;

/// The tracker of `scene`, built from its exact initial shapes with the stats of that build, or
/// restored from `snapshot` (a checkpoint: then the stats are empty). The only place that
/// turns the scene's tracker kind into a tracker; everything after it sees only
/// [`InterfaceTracker`]. A snapshot of another kind than the scene's is an error.
pub fn build_tracker(
    scene: &Scene,
    snapshot: Option<TrackerSnapshot>,
) -> Result<(AnyTracker, StepStats), CouplingError> {
    let initial = |x| scene.initial.sample(x);
    let n_phases = scene.file.phases.len();
    let background = scene.initial.background;
    match (scene.file.tracker.kind, snapshot) {
        (TrackerKind::Contour, None) => {
            let (mut tracker, first) =
                ContourTracker::new(scene.grid, &initial, n_phases, background);
            tracker.set_volume_targets(scene.volume_targets());
            tracker.set_max_travel(scene.file.time.cfl * scene.grid.h);
            tracker.set_junction_weights(scene.file.domain.slab);
            Ok((Box::new(tracker), first))
        }
        (
            TrackerKind::Contour,
            Some(TrackerSnapshot::Contour {
                mesh,
                tree,
                volume_targets,
                component_targets,
                carried_loss,
            }),
        ) => {
            let mut tracker = ContourTracker::from_parts(
                scene.grid,
                mesh,
                tree,
                n_phases,
                background,
                volume_targets,
                component_targets,
                carried_loss,
            );
            tracker.set_max_travel(scene.file.time.cfl * scene.grid.h);
            tracker.set_junction_weights(scene.file.domain.slab);
            Ok((Box::new(tracker), StepStats::default()))
        }
        (TrackerKind::Front, snapshot) => {
            let started = Instant::now();
            let params = scene.file.tracker.front.clone().unwrap_or_default();
            let restoring = snapshot.is_some();
            let built = match snapshot {
                None => FrontTracker::from_sampler_with(
                    scene.grid,
                    &initial,
                    n_phases,
                    background,
                    params,
                    scene.mesh_flow.clone(),
                ),
                // A restored tracker takes its flow after the fact: its mesh is not coarsened
                // again.
                Some(TrackerSnapshot::Front(state)) => {
                    FrontTracker::from_state(state, n_phases, background, params).map(|mut t| {
                        if let Some(flow) = &scene.mesh_flow {
                            t.set_flow(flow.clone());
                        }
                        t
                    })
                }
                Some(TrackerSnapshot::Contour { .. }) => {
                    return Err(other_kind(scene, "a contouring", "the front"))
                }
            };
            let mut tracker = built.map_err(|e| {
                CouplingError::Invalid(format!(
                    "{}: starting the front tracker: {e}",
                    scene.file.name
                ))
            })?;
            tracker.set_volume_correction(scene.file.volume_correction);
            let first = match restoring {
                true => StepStats::default(),
                false => StepStats {
                    stages: vec![("build", started.elapsed().as_secs_f64())],
                    ..StepStats::default()
                },
            };
            Ok((Box::new(tracker), first))
        }
        (TrackerKind::Contour, Some(TrackerSnapshot::Front(_))) => {
            Err(other_kind(scene, "a front", "the contouring"))
        }
    }
}

/// The error of a checkpoint that holds `held` tracker for a scene that asks for `asked`.
fn other_kind(scene: &Scene, held: &str, asked: &str) -> CouplingError {
    CouplingError::Invalid(format!(
        "{}: the checkpoint holds {held} tracker, but the scene asks for {asked} tracker",
        scene.file.name
    ))
}

/// Solver (the scene's boundaries, a free-slip closed box by default, at the scene's solver
/// resolution, at rest) and the scene's tracker (built by [`build_tracker`]) for a coupled
/// scene, plus the tracker's first-build stats.
pub fn from_scene(scene: &Scene) -> Result<(CoupledSim<AnyTracker>, StepStats), CouplingError> {
    let (tracker, first) = build_tracker(scene, None)?;
    Ok((with_tracker(scene, tracker)?, first))
}

/// The coupled simulation of a coupled scene around a given tracker (one restored from a
/// checkpoint, or one a test built), with the solver at rest at time 0 until it is restored
/// too.
pub fn with_tracker<T: InterfaceTracker>(
    scene: &Scene,
    tracker: T,
) -> Result<CoupledSim<T>, CouplingError> {
    let (solver, phases, control) = solver_parts(scene, tracker.max_travel())?;
    let mut sim = CoupledSim::new(solver, tracker, phases, control)?;
    if scene.tension.any() {
        // Curvature is fitted over 4 tracker cells of mesh: at 2.5 the fit's noise drove a
        // static drop's spurious currents up 8e-5 m/s in 200 steps, at 4 they stay near 2e-5
        // (`validation/laplace2`), for a bias of about +0.17·(4h/R)² in κ (`curvature.rs`).
        // A slab's κ is its section's: 6e-6 m/s there.
        sim.set_tension(SurfaceTension::new(
            scene.tension.clone(),
            4.0 * scene.grid.h,
            scene.file.domain.slab.then_some(2),
        ));
    }
    Ok(sim)
}

/// The solver's boundary conditions of a scene's validated `[solver.boundary]`.
fn boundaries(spec: &BoundarySpec) -> [AxisBoundary; 3] {
    let velocity = |wall: usize| {
        spec.wall_velocity
            .get(WALLS[wall])
            .map_or(DVec3::ZERO, |v| DVec3::from_array(*v))
    };
    let kinds = spec.axes();
    [0, 1, 2].map(|a| match kinds[a] {
        BoundaryKind::FreeSlip => AxisBoundary::FREE_SLIP,
        BoundaryKind::Periodic => AxisBoundary::Periodic,
        BoundaryKind::NoSlip => AxisBoundary::Walls {
            low: Wall::NoSlip {
                velocity: velocity(2 * a),
            },
            high: Wall::NoSlip {
                velocity: velocity(2 * a + 1),
            },
        },
    })
}

/// The solver, phase properties and time control a coupled scene asks for, the tracker
/// advancing after the fluid moved `tracker_travel`.
fn solver_parts(
    scene: &Scene,
    tracker_travel: f64,
) -> Result<(Solver, Vec<PhaseProps>, TimeControl), CouplingError> {
    let (Some(grid), Some(spec)) = (scene.solver_grid, scene.file.solver.as_ref()) else {
        return Err(CouplingError::Invalid(format!(
            "scene '{}' is passive (velocity.field is not \"fluid\")",
            scene.file.name
        )));
    };
    let mut config = SolverConfig::closed_box(grid);
    config.gravity = DVec3::from_array(spec.gravity);
    config.boundaries = boundaries(&spec.boundary);
    let kind = |p: PreconditionerSpec| match p {
        PreconditionerSpec::Mic0 => PreconditionerKind::Mic0,
        PreconditionerSpec::Multigrid => PreconditionerKind::Multigrid,
    };
    // The scene's choice for both solves, else the faster one of each (see `SolverSpec`).
    let (pressure, viscosity) = spec.preconditioner.map_or(
        (PreconditionerKind::Multigrid, PreconditionerKind::Mic0),
        |p| (kind(p), kind(p)),
    );
    let linear = |preconditioner| LinearSolverSettings {
        preconditioner,
        tolerance: spec.tolerance,
        max_iterations: LinearSolverSettings::default().max_iterations,
    };
    config.pressure = linear(pressure);
    config.viscosity = linear(viscosity);
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
        tracker_travel,
    };
    Ok((solver, phases, control))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A built-in scene with `cfl = N` added to its `[time]` table.
    fn with_time_cfl(name: &str, cfl: f64) -> Scene {
        let (_, text) = polyphase_scenes::BUILTIN
            .iter()
            .find(|(n, _)| *n == name)
            .expect("built-in");
        let text = text.replacen("[time]\n", &format!("[time]\ncfl = {cfl}\n"), 1);
        Scene::parse(&text, name).expect("valid")
    }

    #[test]
    fn fresh_and_restored_trackers_travel_the_scenes_time_cfl() {
        for name in ["rayleigh_taylor", "circle3_rotate"] {
            let scene = with_time_cfl(name, 2.5);
            let h = scene.grid.h;
            let (fresh, _) = build_tracker(&scene, None).expect("built");
            assert_eq!(fresh.max_travel(), 2.5 * h, "{name}, fresh");
            let restored = build_tracker(&scene, fresh.snapshot()).expect("restored").0;
            assert_eq!(restored.max_travel(), 2.5 * h, "{name}, from a checkpoint");
        }
    }

    #[test]
    fn pressure_defaults_to_multigrid_and_a_scene_choice_sets_both_solves() {
        let kinds = |scene: &Scene| {
            let (sim, _) = from_scene(scene).expect("coupled");
            let config = sim.solver().config();
            (
                config.pressure.preconditioner,
                config.viscosity.preconditioner,
            )
        };
        let (_, text) = polyphase_scenes::BUILTIN
            .iter()
            .find(|(n, _)| *n == "rayleigh_taylor")
            .expect("built-in");
        let default = Scene::parse(text, "rayleigh_taylor").expect("valid");
        assert_eq!(
            kinds(&default),
            (PreconditionerKind::Multigrid, PreconditionerKind::Mic0)
        );
        for (name, kind) in [
            ("mic0", PreconditionerKind::Mic0),
            ("multigrid", PreconditionerKind::Multigrid),
        ] {
            let chosen = text.replacen(
                "[solver]\n",
                &format!("[solver]\npreconditioner = \"{name}\"\n"),
                1,
            );
            let scene = Scene::parse(&chosen, "rayleigh_taylor").expect("valid");
            assert_eq!(kinds(&scene), (kind, kind), "{name}");
        }
    }

    /// `enright` at 8³ with the given tracker.
    fn small_enright(tracker: &str) -> Scene {
        let (_, text) = polyphase_scenes::BUILTIN
            .iter()
            .find(|(n, _)| *n == "enright")
            .expect("built-in");
        let text = text.replacen(
            "resolution = 64\n",
            &format!("resolution = 8\ntracker = \"{tracker}\"\n"),
            1,
        );
        Scene::parse(&text, "enright").expect("valid")
    }

    #[test]
    fn a_front_tracker_restores_and_a_snapshot_of_the_other_kind_is_refused() {
        let (contour, front) = (small_enright("contour"), small_enright("front"));
        let (fresh, _) = build_tracker(&front, None).expect("built");
        let (restored, first) = build_tracker(&front, fresh.snapshot()).expect("restored");
        assert_eq!(restored.mesh(), fresh.mesh());
        assert_eq!(restored.max_travel(), fresh.max_travel());
        assert!(first.stages.is_empty(), "a restore builds nothing");

        let refused = |scene: &Scene, snapshot, held: &str| {
            let err = build_tracker(scene, snapshot).err().expect("refused");
            assert!(err.to_string().contains(held), "{err}");
        };
        refused(&contour, fresh.snapshot(), "holds a front tracker");
        let contour_snapshot = build_tracker(&contour, None).expect("built").0.snapshot();
        refused(&front, contour_snapshot, "holds a contouring tracker");
    }
}
