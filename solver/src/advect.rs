//! Semi-Lagrangian self-advection of the MAC velocity with an RK2 (midpoint) backtrace, and the
//! MacCormack correction with Selle et al. (2008) clamping: where the corrected value leaves the
//! range of the departure stencil, the first-order value is kept, so the scheme stays stable.

use crate::config::AdvectionScheme;
use crate::interp;
use crate::layout::unidx;
use crate::mac::MacGrid;
use glam::DVec3;
use rayon::prelude::*;

/// Departure point of `x` after time `dt` in `vel` (midpoint rule).
#[inline]
fn backtrace(vel: &MacGrid, x: DVec3, dt: f64) -> DVec3 {
    let mid = x - 0.5 * dt * vel.sample(x);
    x - dt * vel.sample(mid)
}

/// Semi-Lagrangian transport of the face values `src` through `vel` over `dt`; returns the new
/// values and the departure points.
fn semi_lagrangian(
    vel: &MacGrid,
    src: &MacGrid,
    open: &[Vec<f64>; 3],
    dt: f64,
) -> [Vec<(f64, DVec3)>; 3] {
    [0, 1, 2].map(|a| {
        let dims = vel.layout.face_dims(a);
        (0..vel.comps[a].len())
            .into_par_iter()
            .map(|f| {
                if open[a][f] == 0.0 {
                    return (0.0, DVec3::ZERO);
                }
                let x = vel.face_position(a, unidx(dims, f));
                let xd = backtrace(vel, x, dt);
                (src.sample_component(a, xd), xd)
            })
            .collect()
    })
}

/// Advects the velocity through itself over `dt`.
pub(crate) fn advect(
    vel: &MacGrid,
    open: &[Vec<f64>; 3],
    dt: f64,
    scheme: AdvectionScheme,
) -> MacGrid {
    let mut out = vel.clone();
    if scheme == AdvectionScheme::None {
        return out;
    }
    let forward = semi_lagrangian(vel, vel, open, dt);
    for (comp, fw) in out.comps.iter_mut().zip(&forward) {
        *comp = fw.iter().map(|v| v.0).collect();
    }
    if scheme == AdvectionScheme::SemiLagrangian {
        return out;
    }
    let back = semi_lagrangian(vel, &out, open, -dt);
    for a in 0..3 {
        let corrected: Vec<f64> = (0..out.comps[a].len())
            .into_par_iter()
            .map(|f| {
                let (hat, xd) = forward[a][f];
                if open[a][f] == 0.0 {
                    return 0.0;
                }
                let mc = hat + 0.5 * (vel.comps[a][f] - back[a][f].0);
                let (lo, hi) = interp::stencil_range(&vel.spec, &vel.layout, &vel.comps[a], a, xd);
                if mc < lo || mc > hi {
                    hat
                } else {
                    mc
                }
            })
            .collect();
        out.comps[a] = corrected;
    }
    out
}
