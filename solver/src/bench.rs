//! Benchmark of the linear solves (`polyphase bench solver`): a liquid sphere in air (density
//! ratio 1000:1, honey-like 50 Pa·s liquid against 1.8e-5 Pa·s air, a viscosity ratio of
//! 2.8·10⁶) in a closed free-slip unit box with a swirling velocity plus one step of gravity;
//! the pressure solve and the viscosity solve, each with MIC(0)-PCG and multigrid-PCG, to 1e-6
//! relative residual. The viscosity solves run a second time with the air 5e-3 Pa·s (a
//! viscosity ratio of 10⁴).

use crate::config::{LinearSolverSettings, PreconditionerKind, SolverConfig};
use crate::error::SolverError;
use crate::layout::{unidx, Layout};
use crate::mac::MacGrid;
use crate::phase::{cell_material, face_densities, PhaseProps};
use crate::sample_viscosity::SampleViscosity;
use crate::solid::open_fractions;
use crate::{pressure, viscosity};
use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseField};
use std::f64::consts::PI;
use std::time::Instant;

/// Relative residual every benchmarked solve runs to.
pub const TOLERANCE: f64 = 1e-6;

/// Viscosity of the liquid sphere, Pa·s.
const LIQUID_VISCOSITY: f64 = 50.0;

/// Air viscosities of the benchmarked cases, Pa·s: real air, then a 10⁴ viscosity ratio.
const AIR_VISCOSITIES: [f64; 2] = [1.8e-5, LIQUID_VISCOSITY * 1e-4];

/// One measured solve.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchRow {
    /// Cells per axis.
    pub res: usize,
    /// "pressure" or "viscosity".
    pub solve: &'static str,
    /// "mic0" or "multigrid".
    pub preconditioner: &'static str,
    /// Liquid over air viscosity.
    pub viscosity_ratio: f64,
    /// CG iterations.
    pub iterations: usize,
    /// Wall-clock seconds of assembly, preconditioner set-up and solve.
    pub seconds: f64,
    /// Final relative residual.
    pub residual: f64,
    /// Bytes of matrix, preconditioner and CG vectors.
    pub memory_bytes: usize,
}

/// The benchmark scene at `res`³ with air of viscosity `air_viscosity`: phase field, phases,
/// velocity.
fn scene(
    res: usize,
    air_viscosity: f64,
) -> (GridSpec, Layout, PhaseField, [PhaseProps; 2], MacGrid) {
    let h = 1.0 / res as f64;
    let grid = GridSpec {
        origin: DVec3::ZERO,
        h,
        dims: [res; 3],
    };
    let layout = Layout {
        n: grid.dims,
        periodic: [false; 3],
    };
    let centre = DVec3::new(0.5, 0.4, 0.5);
    let radius = 0.25;
    let n = grid.cell_count();
    let mut phi = Vec::with_capacity(n);
    let mut chi = Vec::with_capacity(n);
    for c in 0..n {
        let p = unidx(grid.dims, c);
        let d = (grid.cell_center(p[0], p[1], p[2]) - centre).length() - radius;
        phi.push(d.abs());
        chi.push(u16::from(d < 0.0));
    }
    let field = PhaseField { grid, phi, chi };
    let phases = [
        PhaseProps {
            density: 1.0,
            viscosity: air_viscosity,
        },
        PhaseProps {
            density: 1000.0,
            viscosity: LIQUID_VISCOSITY,
        },
    ];
    let mut vel = MacGrid::zeros(grid, layout, crate::config::Interpolation::Trilinear);
    for a in 0..3 {
        let dims = layout.face_dims(a);
        let dt = 0.01;
        for f in 0..vel.comps[a].len() {
            let p = unidx(dims, f);
            if layout.on_wall(a, p[a]) {
                continue;
            }
            let x = vel.face_position(a, p);
            let swirl = DVec3::new(
                (PI * x.y).sin() * (2.0 * PI * x.z).cos(),
                (PI * x.z).sin() * (2.0 * PI * x.x).cos(),
                (PI * x.x).sin() * (2.0 * PI * x.y).cos(),
            );
            vel.comps[a][f] = swirl[a] + if a == 1 { -9.81 * dt } else { 0.0 };
        }
    }
    (grid, layout, field, phases, vel)
}

/// Runs the whole benchmark at each resolution (cells per axis).
pub fn run(resolutions: &[usize]) -> Result<Vec<BenchRow>, SolverError> {
    run_selected(resolutions, true, true, None)
}

/// Runs the pressure and/or the viscosity part of the benchmark at each resolution, with one
/// preconditioner or (`None`) both.
pub fn run_selected(
    resolutions: &[usize],
    pressure_solves: bool,
    viscosity_solves: bool,
    only: Option<PreconditionerKind>,
) -> Result<Vec<BenchRow>, SolverError> {
    let mut rows = Vec::new();
    let dt = 0.01;
    for &res in resolutions {
        for (case, &air) in AIR_VISCOSITIES.iter().enumerate() {
            let (grid, layout, field, phases, vel) = scene(res, air);
            let ratio = phases[1].viscosity / phases[0].viscosity;
            let config = SolverConfig::closed_box(grid);
            config.validate()?;
            let open = [0, 1, 2].map(|a| open_fractions(&grid, &layout, &[], a));
            let material = cell_material(&field, &phases)?;
            let rho = [0, 1, 2].map(|a| face_densities(&material, &layout, a));
            for (kind, name) in [
                (PreconditionerKind::Mic0, "mic0"),
                (PreconditionerKind::Multigrid, "multigrid"),
            ] {
                if only.is_some_and(|o| o != kind) {
                    continue;
                }
                let settings = LinearSolverSettings {
                    preconditioner: kind,
                    tolerance: TOLERANCE,
                    max_iterations: 10_000,
                };
                // The pressure solve does not see the viscosity: once per resolution.
                if pressure_solves && case == 0 {
                    let mut v = vel.clone();
                    let t = Instant::now();
                    let out = pressure::project(&mut v, &open, &rho, dt, &settings, None)?;
                    rows.push(BenchRow {
                        res,
                        solve: "pressure",
                        preconditioner: name,
                        viscosity_ratio: ratio,
                        iterations: out.stats.iterations,
                        seconds: t.elapsed().as_secs_f64(),
                        residual: out.stats.residual,
                        memory_bytes: out.memory_bytes,
                    });
                }
                if !viscosity_solves {
                    continue;
                }
                let mut v = vel.clone();
                let t = Instant::now();
                let system = viscosity::ViscousSystem::new(
                    layout,
                    grid.h,
                    dt,
                    &config.boundaries,
                    &open,
                    &rho,
                    &SampleViscosity::new(&material, &phases, &layout, grid.h),
                );
                let (stats, mem) = viscosity::solve(&system, &mut v, &settings)?;
                rows.push(BenchRow {
                    res,
                    solve: "viscosity",
                    preconditioner: name,
                    viscosity_ratio: ratio,
                    iterations: stats.iterations,
                    seconds: t.elapsed().as_secs_f64(),
                    residual: stats.residual,
                    memory_bytes: mem,
                });
            }
        }
    }
    Ok(rows)
}

/// The rows as an aligned text table.
pub fn format_table(rows: &[BenchRow]) -> String {
    let mut s = format!(
        "{:>5} {:<10} {:<10} {:>9} {:>6} {:>9} {:>10} {:>10}\n",
        "res", "solve", "precond", "mu_ratio", "iters", "seconds", "residual", "memory_MB"
    );
    for r in rows {
        s.push_str(&format!(
            "{:>5} {:<10} {:<10} {:>9.1e} {:>6} {:>9.3} {:>10.2e} {:>10.1}\n",
            r.res,
            r.solve,
            r.preconditioner,
            r.viscosity_ratio,
            r.iterations,
            r.seconds,
            r.residual,
            r.memory_bytes as f64 / 1e6
        ));
    }
    s
}
