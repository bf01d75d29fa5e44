//! Pressure jumps at interface faces (the ghost-fluid jump condition that carries surface
//! tension): a drop at rest whose every interface face carries the Laplace jump σκ stays at
//! rest, with exactly that pressure difference.

mod common;

use common::*;
use glam::DVec3;
use polyphase_solver::{PointForces, PressureJumps, Solver};

/// A water ball of radius `r` (phase 1) in air, every interface face jumping by the exact
/// Laplace pressure 2σ/r: (largest speed after `steps` steps, mean pressure inside − outside).
fn static_drop(steps: usize) -> (f64, f64, f64) {
    let (sigma, r) = (0.0728, 0.3);
    let g = grid([24, 24, 24], 1.0 / 24.0);
    let f = ball(g, DVec3::splat(0.5), r);
    let mut s = Solver::new(config(g)).unwrap();
    let laplace = sigma * 2.0 / r;
    let faces = s.interface_faces(&f).unwrap();
    assert!(!faces.is_empty());
    // J = p_above − p_below: +σκ where the cell above is the drop, −σκ where it is below.
    let jumps = PressureJumps::new(
        faces
            .iter()
            .map(|face| (*face, if face.above == 1 { laplace } else { -laplace })),
    );
    for _ in 0..steps {
        s.step_with_tension(&f, &WATER_AIR, 1e-3, &jumps, &PointForces::default())
            .unwrap();
    }
    let mut speed: f64 = 0.0;
    for a in 0..3 {
        for u in s.velocity().component(a) {
            speed = speed.max(u.abs());
        }
    }
    let (mut inside, mut outside, mut ni, mut no) = (0.0, 0.0, 0, 0);
    for (p, &c) in s.pressure().iter().zip(&f.chi) {
        if c == 1 {
            inside += p;
            ni += 1;
        } else {
            outside += p;
            no += 1;
        }
    }
    (speed, inside / ni as f64 - outside / no as f64, laplace)
}

#[test]
fn a_drop_with_a_uniform_laplace_jump_stays_at_rest_with_that_pressure() {
    let (speed, difference, laplace) = static_drop(5);
    // A uniform jump is balanced exactly by a pressure that is constant on each side: the
    // solve (relative residual 1e-12) leaves velocities at round-off.
    assert!(speed < 1e-10, "spurious speed {speed}");
    // Each side's pressure is constant, so the means differ by exactly the jump.
    assert!(
        (difference / laplace - 1.0).abs() < 1e-8,
        "{difference} against σκ = {laplace}"
    );
}
