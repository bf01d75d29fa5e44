//! A water ball free-falling in air stays a ball (no momentum leaks across the 1000:1
//! interface), moves with g·t, and the solver's interface never lags the tracker's.

use glam::DVec3;
use polyphase_coupling::{from_scene, AnyTracker, CoupledSim};
use polyphase_scenes::Scene;
use polyphase_tracker::{InterfaceTracker, LabeledMesh, PhaseId};

const WATER: PhaseId = 1;

/// Volume and centroid of a phase's region (divergence theorem over its triangles).
fn volume_centroid(mesh: &LabeledMesh, phase: PhaseId) -> (f64, DVec3) {
    let (mut vol, mut moment) = (0.0, DVec3::ZERO);
    for (tri, labels) in mesh.triangles.iter().zip(&mesh.labels) {
        // labels = [front, back]: the normal points out of `phase` when it is behind.
        let sign = if labels[1] == phase {
            1.0
        } else if labels[0] == phase {
            -1.0
        } else {
            continue;
        };
        let [a, b, c] = tri.map(|v| mesh.vertices[v as usize]);
        let v6 = sign * a.dot(b.cross(c));
        vol += v6 / 6.0;
        moment += v6 / 24.0 * (a + b + c);
    }
    (vol, moment / vol)
}

/// Largest |distance from the centroid / equivalent radius − 1| over the ball's vertices.
fn roundness_error(mesh: &LabeledMesh) -> f64 {
    let (vol, centre) = volume_centroid(mesh, WATER);
    let radius = (3.0 * vol / (4.0 * std::f64::consts::PI)).cbrt();
    let mut worst: f64 = 0.0;
    for (tri, labels) in mesh.triangles.iter().zip(&mesh.labels) {
        if labels.contains(&WATER) {
            for &v in tri {
                let d = (mesh.vertices[v as usize] - centre).length();
                worst = worst.max((d / radius - 1.0).abs());
            }
        }
    }
    worst
}

/// Largest |v − g·t| / |g·t| over the solver cells the water fills.
fn velocity_error(sim: &CoupledSim<AnyTracker>) -> f64 {
    let grid = *sim.solver().grid();
    let field = sim.tracker().sample(&grid);
    let v = sim.solver().cell_velocities(&field, sim.phases()).unwrap();
    let fall = DVec3::new(0.0, -9.81 * sim.time(), 0.0);
    let mut worst: f64 = 0.0;
    for (c, &chi) in field.chi.iter().enumerate() {
        if chi == WATER {
            worst = worst.max((v[c] - fall).length() / fall.length());
        }
    }
    worst
}

/// The built-in `fall` at 6 solver cells across the ball (solver 32, tracker 64 along y), at
/// the default `time.cfl`, to t = 0.2 s in four frames.
#[test]
fn falling_ball_stays_a_ball_at_six_cells_across() {
    let text = polyphase_scenes::BUILTIN
        .iter()
        .find(|(n, _)| *n == "fall")
        .map(|(_, t)| *t)
        .unwrap()
        .replace("resolution = 128", "resolution = 64")
        .replace("resolution = 64\ncfl", "resolution = 32\ncfl");
    let scene = Scene::parse(&text, "fall-6").unwrap();
    assert_eq!(scene.solver_grid.unwrap().dims, [16, 32, 16]);
    let (mut sim, _) = from_scene(&scene).unwrap();
    let (_, start) = volume_centroid(sim.tracker().mesh(), WATER);
    let mut steps = (0, 0);
    for frame in 1..=4 {
        let t = 0.05 * frame as f64;
        let report = sim.advance_to(t).unwrap();
        // Physically the ball deforms well under 1 % by t = 0.2 s (aerodynamic pressure
        // ~2 Pa against ~700 Pa hydrostatic), so the shape and the velocity are numerical
        // errors; the bound at 6 cells across is the one the issue sets (6 %).
        let round = roundness_error(sim.tracker().mesh());
        assert!(round < 0.06, "t = {t}: vertices {round:.4} off the radius");
        let speed = velocity_error(&sim);
        assert!(speed < 0.06, "t = {t}: water velocity {speed:.4} off g·t");
        // The solver's interface is the tracker's advected to each step: before a tracker
        // step it may differ from the contoured one by resampling only (issue: 0.25 cells;
        // without advecting it, it lagged by up to the whole travel, 4 solver cells here).
        assert!(
            report.interface_lag < 0.25,
            "t = {t}: solver interface lags {:.3} cells",
            report.interface_lag
        );
        steps = (steps.0 + report.steps, steps.1 + report.tracker_steps);
        // Free fall: the centroid drops g·t²/2 (trapezoidal interface motion, second order).
        let (_, centre) = volume_centroid(sim.tracker().mesh(), WATER);
        let drop = start.y - centre.y;
        let exact = 0.5 * 9.81 * t * t;
        assert!(
            (drop - exact).abs() < 0.05 * exact + 0.25 * scene.grid.h,
            "t = {t}: fell {drop:.4} m, free fall {exact:.4} m"
        );
    }
    // Solver steps between tracker steps did happen, so the lag bound above tested them.
    assert!(steps.1 < steps.0, "solver/tracker steps {steps:?}");
}
