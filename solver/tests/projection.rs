//! Variable-density projection: divergence-free output, hydrostatic rest, second-order
//! convergence, agreement of the two preconditioners.

mod common;

use common::*;
use glam::DVec3;
use polyphase_solver::{PhaseProps, PreconditionerKind, Solver};
use std::f64::consts::PI;

fn random_velocity(s: &mut Solver, seed: u64) -> f64 {
    let mut rng = Lcg(seed);
    let mut max = 0.0f64;
    for a in 0..3 {
        for u in s.velocity_mut().component_mut(a) {
            *u = rng.next();
            max = max.max(u.abs());
        }
    }
    max
}

fn divergence_after_projection(kind: PreconditionerKind) -> f64 {
    let g = grid([16, 16, 16], 1.0 / 16.0);
    let mut c = config(g);
    c.pressure = tight(kind);
    let mut s = Solver::new(c).unwrap();
    let speed = random_velocity(&mut s, 7);
    let f = ball(g, DVec3::new(0.45, 0.5, 0.55), 0.3);
    let stats = s.project(&f, &WATER_AIR, 0.01).unwrap();
    assert!(stats.iterations > 0);
    relative_divergence(&s, speed)
}

#[test]
fn projection_is_divergence_free_at_density_ratio_1000_mic0() {
    // The solve runs to 1e-12 relative residual; the divergence is that residual scaled by
    // the face coefficients (≤ 1000 across the density jump), so 1e-8 has margin.
    assert!(divergence_after_projection(PreconditionerKind::Mic0) < 1e-8);
}

#[test]
fn projection_is_divergence_free_at_density_ratio_1000_multigrid() {
    // Same bound and reason as the MIC(0) case.
    assert!(divergence_after_projection(PreconditionerKind::Multigrid) < 1e-8);
}

#[test]
fn mic0_and_multigrid_give_the_same_projection() {
    let g = grid([16, 16, 16], 1.0 / 16.0);
    let f = ball(g, DVec3::new(0.5, 0.4, 0.5), 0.25);
    let mut out = Vec::new();
    for kind in [PreconditionerKind::Mic0, PreconditionerKind::Multigrid] {
        let mut c = config(g);
        c.pressure = tight(kind);
        let mut s = Solver::new(c).unwrap();
        random_velocity(&mut s, 3);
        s.project(&f, &WATER_AIR, 0.01).unwrap();
        out.push(s.velocity().component(1).to_vec());
    }
    let diff = out[0]
        .iter()
        .zip(&out[1])
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    // The projection is unique; both solves stop at 1e-12 relative residual, and the velocity
    // differs by at most that residual amplified by the condition of the 1000:1 system.
    assert!(diff < 1e-7, "diff {diff}");
}

#[test]
fn three_hydrostatic_layers_stay_at_rest() {
    let g = grid([6, 24, 6], 1.0 / 24.0);
    let mut c = config(g);
    c.gravity = DVec3::new(0.0, -9.81, 0.0);
    let mut s = Solver::new(c).unwrap();
    // Interfaces at heights that are not cell-aligned; heavy at the bottom.
    let f = layers(g, &[0.31, 0.67]);
    let phases = [
        PhaseProps {
            density: 1000.0,
            viscosity: 1e-3,
        },
        PhaseProps {
            density: 800.0,
            viscosity: 5e-2,
        },
        PhaseProps {
            density: 1.0,
            viscosity: 1.8e-5,
        },
    ];
    for _ in 0..100 {
        s.step(&f, &phases, 0.01).unwrap();
    }
    let umax = s.velocity().max_abs();
    // The ghost-fluid face density is exact for layers, so the discrete hydrostatic pressure
    // balances gravity to solver tolerance (1e-12 relative); the bound is 1e-6 m/s.
    assert!(umax < 1e-6, "max |u| = {umax}");
    // The pressure difference across the column is the weight of the layers, ∫ρg dy
    // (0.31·1000 + 0.36·800 + 0.33·1)·9.81 between the centres of the extreme cells, up to the
    // half cells at either end.
    let p = s.pressure();
    let bottom = p[g.cell_index(0, 0, 0)];
    let top = p[g.cell_index(0, 23, 0)];
    let h = g.h;
    let expected = ((0.31 - 0.5 * h) * 1000.0 + 0.36 * 800.0 + (0.33 - 0.5 * h) * 1.0) * 9.81;
    // Exact for the ghost-fluid discretisation of piecewise-constant density.
    assert!(
        ((bottom - top) - expected).abs() < 1e-6 * expected,
        "{} vs {expected}",
        bottom - top
    );
}

/// Max-norm pressure error of projecting u* = ∇p for p = cos πx cos πy cos πz (zero normal
/// derivative on the walls of the unit box), ρ = 1000, dt = ρ.
fn manufactured_error(n: usize) -> f64 {
    let g = grid([n, n, n], 1.0 / n as f64);
    let mut s = Solver::new(config(g)).unwrap();
    let exact = |x: DVec3| (PI * x.x).cos() * (PI * x.y).cos() * (PI * x.z).cos();
    let grad = |x: DVec3| {
        -PI * DVec3::new(
            (PI * x.x).sin() * (PI * x.y).cos() * (PI * x.z).cos(),
            (PI * x.x).cos() * (PI * x.y).sin() * (PI * x.z).cos(),
            (PI * x.x).cos() * (PI * x.y).cos() * (PI * x.z).sin(),
        )
    };
    let field: &dyn polyphase_grid::VelocityField = &Grad(grad);
    s.velocity_mut().set_from(field, 0.0);
    let rho = 1000.0;
    let phases = [PhaseProps {
        density: rho,
        viscosity: 0.0,
    }];
    // u = u* − (dt/ρ)∇p with dt = ρ: the discrete pressure approximates p itself.
    s.project(&uniform(g), &phases, rho).unwrap();
    let p = s.pressure();
    let mut err_sum = 0.0;
    let mut diffs = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d = p[g.cell_index(i, j, k)] - exact(g.cell_center(i, j, k));
                diffs.push(d);
                err_sum += d;
            }
        }
    }
    let mean = err_sum / diffs.len() as f64;
    diffs.iter().fold(0.0f64, |m, d| m.max((d - mean).abs()))
}

struct Grad<F>(F);
impl<F: Fn(DVec3) -> DVec3 + Sync> polyphase_grid::VelocityField for Grad<F> {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        (self.0)(x)
    }
}

#[test]
fn projection_converges_at_second_order() {
    let e8 = manufactured_error(8);
    let e16 = manufactured_error(16);
    let e32 = manufactured_error(32);
    let (r1, r2) = (e8 / e16, e16 / e32);
    // Second order: halving h divides the error by 4 (the MAC stencil's truncation error is
    // O(h²)); [3.5, 4.5] allows the pre-asymptotic drift of the coarse levels.
    assert!(
        (3.5..4.5).contains(&r1),
        "ratios {r1} {r2} errors {e8} {e16} {e32}"
    );
    assert!(
        (3.5..4.5).contains(&r2),
        "ratios {r1} {r2} errors {e8} {e16} {e32}"
    );
}
