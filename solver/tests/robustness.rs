//! High contrasts converge; bad input is a typed error and leaves the state untouched;
//! results are bit-identical with 1 and 2 threads.

mod common;

use common::*;
use glam::DVec3;
use polyphase_solver::{
    LinearSolverSettings, PhaseProps, PreconditionerKind, Solver, SolverConfig, SolverError,
};

/// Honey ball (ρ 1000, μ 10) in air (ρ 1, μ 1e-3): density ratio 1000, viscosity ratio 10⁴.
const HONEY_AIR: [PhaseProps; 2] = [
    PhaseProps {
        density: 1.0,
        viscosity: 1e-3,
    },
    PhaseProps {
        density: 1000.0,
        viscosity: 10.0,
    },
];

fn swirl(s: &mut Solver) {
    struct Swirl;
    impl polyphase_grid::VelocityField for Swirl {
        fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
            let r = x - DVec3::splat(0.5);
            DVec3::new(-r.y, r.x, 0.3 * r.x * r.y)
        }
    }
    s.velocity_mut().set_from(&Swirl, 0.0);
}

fn contrast_config(kind: PreconditionerKind) -> SolverConfig {
    let g = grid([16, 16, 16], 1.0 / 16.0);
    let mut c = SolverConfig::closed_box(g);
    let settings = LinearSolverSettings {
        preconditioner: kind,
        tolerance: 1e-8,
        max_iterations: 2000,
    };
    c.pressure = settings;
    c.viscosity = settings;
    c
}

fn run_contrast(kind: PreconditionerKind, steps: usize) -> Solver {
    let mut s = Solver::new(contrast_config(kind)).unwrap();
    swirl(&mut s);
    let f = ball(*s.grid(), DVec3::new(0.5, 0.6, 0.5), 0.25);
    for _ in 0..steps {
        let dt = s.cfl_dt(1.0).min(0.02);
        let r = s.step(&f, &HONEY_AIR, dt).unwrap();
        assert!(r.viscosity.is_some());
    }
    s
}

#[test]
fn density_1000_and_viscosity_1e4_ratios_converge() {
    for kind in [PreconditionerKind::Mic0, PreconditionerKind::Multigrid] {
        let s = run_contrast(kind, 5);
        let speed = s.velocity().max_abs();
        assert!(speed.is_finite() && speed < 10.0, "speed {speed}");
        // Each pressure solve reached 1e-8 relative residual (else step() errs); the
        // divergence left is of that order relative to the face speeds.
        assert!(relative_divergence(&s, speed) < 1e-6);
    }
}

#[test]
fn results_are_bit_identical_with_one_and_two_threads() {
    let run = |threads: usize, kind| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let s = run_contrast(kind, 3);
                (0..3)
                    .flat_map(|a| s.velocity().component(a).to_vec())
                    .map(f64::to_bits)
                    .collect::<Vec<u64>>()
            })
    };
    for kind in [PreconditionerKind::Mic0, PreconditionerKind::Multigrid] {
        // Fixed-order reductions: the same bits, not merely close values.
        assert_eq!(run(1, kind), run(2, kind));
    }
}

#[test]
fn non_finite_and_invalid_input_are_errors() {
    let c = contrast_config(PreconditionerKind::Mic0);
    let g = c.grid;
    let good = ball(g, DVec3::splat(0.5), 0.25);
    let mut s = Solver::new(c.clone()).unwrap();
    swirl(&mut s);
    let before = s.velocity().component(0).to_vec();

    let mut f = good.clone();
    f.phi[10] = f64::NAN;
    assert!(matches!(
        s.step(&f, &HONEY_AIR, 0.01),
        Err(SolverError::NonFinite {
            what: "phi",
            index: 10
        })
    ));

    let mut f = good.clone();
    f.chi[3] = 7;
    assert!(matches!(
        s.step(&f, &HONEY_AIR, 0.01),
        Err(SolverError::UnknownPhase {
            phase: 7,
            cell: 3,
            ..
        })
    ));

    let bad = [
        HONEY_AIR[0],
        PhaseProps {
            density: f64::INFINITY,
            viscosity: 1.0,
        },
    ];
    assert!(matches!(
        s.step(&good, &bad, 0.01),
        Err(SolverError::InvalidPhase { phase: 1, .. })
    ));
    let bad = [
        HONEY_AIR[0],
        PhaseProps {
            density: 1.0,
            viscosity: f64::NAN,
        },
    ];
    assert!(matches!(
        s.step(&good, &bad, 0.01),
        Err(SolverError::InvalidPhase { phase: 1, .. })
    ));

    for dt in [f64::NAN, f64::INFINITY, 0.0, -1.0] {
        assert!(matches!(
            s.step(&good, &HONEY_AIR, dt),
            Err(SolverError::InvalidTimeStep(_))
        ));
    }

    let other = ball(grid([8, 8, 8], 1.0 / 8.0), DVec3::splat(0.5), 0.25);
    assert!(matches!(
        s.step(&other, &HONEY_AIR, 0.01),
        Err(SolverError::GridMismatch { .. })
    ));

    assert_eq!(
        s.velocity().component(0),
        &before[..],
        "failed steps must not change the state"
    );

    s.velocity_mut().component_mut(1)[5] = f64::INFINITY;
    assert!(matches!(
        s.step(&good, &HONEY_AIR, 0.01),
        Err(SolverError::NonFinite {
            what: "velocity",
            index: 5
        })
    ));

    let mut c2 = c.clone();
    c2.grid.h = f64::NAN;
    assert!(matches!(
        Solver::new(c2),
        Err(SolverError::InvalidConfig(_))
    ));
    let mut c3 = c;
    c3.gravity = DVec3::new(0.0, f64::NAN, 0.0);
    assert!(matches!(
        Solver::new(c3),
        Err(SolverError::InvalidConfig(_))
    ));
}

#[test]
fn a_solve_that_cannot_converge_is_an_error() {
    let mut c = contrast_config(PreconditionerKind::Mic0);
    c.pressure.max_iterations = 2;
    let mut s = Solver::new(c).unwrap();
    swirl(&mut s);
    let before = s.velocity().component(2).to_vec();
    let f = ball(*s.grid(), DVec3::splat(0.5), 0.25);
    let r = s.step(&f, &HONEY_AIR, 0.01);
    assert!(
        matches!(
            r,
            Err(SolverError::NotConverged {
                system: "pressure",
                iterations: 2,
                ..
            })
        ),
        "{r:?}"
    );
    assert_eq!(s.velocity().component(2), &before[..]);
}
