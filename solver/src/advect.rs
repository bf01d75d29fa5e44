//! Semi-Lagrangian self-advection of the MAC velocity with an RK2 (midpoint) backtrace, and the
//! MacCormack correction with Selle et al. (2008) clamping: where the corrected value leaves the
//! range of the departure stencil, the first-order value is kept, so the scheme stays stable.
//! With several phases each face is advected in its own phase's velocity field (see
//! [`crate::extension`]), so no stencil mixes two phases' momentum.

use crate::config::AdvectionScheme;
use crate::extension::{carries, extend, owning_phases};
use crate::interp;
use crate::layout::unidx;
use crate::mac::MacGrid;
use glam::DVec3;
use polyphase_grid::PhaseId;
use rayon::prelude::*;

/// Which faces a pass computes: (component, face index) → yes or no.
type Active<'a> = dyn Fn(usize, usize) -> bool + Sync + 'a;

/// Departure point of `x` after time `dt` in `vel` (midpoint rule).
#[inline]
fn backtrace(vel: &MacGrid, x: DVec3, dt: f64) -> DVec3 {
    let mid = x - 0.5 * dt * vel.sample(x);
    x - dt * vel.sample(mid)
}

/// Semi-Lagrangian transport of the face values `src` through `vel` over `dt` on the `active`
/// open faces; returns the new values and the departure points (zero elsewhere).
fn semi_lagrangian(
    vel: &MacGrid,
    src: &MacGrid,
    open: &[Vec<f64>; 3],
    dt: f64,
    active: &Active,
) -> [Vec<(f64, DVec3)>; 3] {
    [0, 1, 2].map(|a| {
        let dims = vel.layout.face_dims(a);
        (0..vel.comps[a].len())
            .into_par_iter()
            .map(|f| {
                if open[a][f] == 0.0 || !active(a, f) {
                    return (0.0, DVec3::ZERO);
                }
                let x = vel.face_position(a, unidx(dims, f));
                let xd = backtrace(vel, x, dt);
                (src.sample_component(a, xd), xd)
            })
            .collect()
    })
}

/// Advects `vel` through itself over `dt`, computing the first-order values on the `forward`
/// faces and the result on the `keep` faces (a subset whose MacCormack back-trace reads only
/// `forward` faces); other faces come back as zero.
fn advect_where(
    vel: &MacGrid,
    open: &[Vec<f64>; 3],
    dt: f64,
    scheme: AdvectionScheme,
    forward_faces: &Active,
    keep: &Active,
) -> MacGrid {
    let mut out = vel.clone();
    let forward = semi_lagrangian(vel, vel, open, dt, forward_faces);
    for (comp, fw) in out.comps.iter_mut().zip(&forward) {
        *comp = fw.iter().map(|v| v.0).collect();
    }
    if scheme == AdvectionScheme::SemiLagrangian {
        return out;
    }
    let back = semi_lagrangian(vel, &out, open, -dt, keep);
    for a in 0..3 {
        let corrected: Vec<f64> = (0..out.comps[a].len())
            .into_par_iter()
            .map(|f| {
                let (hat, xd) = forward[a][f];
                if open[a][f] == 0.0 || !keep(a, f) {
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

/// Advects the velocity through itself over `dt`.
pub(crate) fn advect(
    vel: &MacGrid,
    open: &[Vec<f64>; 3],
    dt: f64,
    scheme: AdvectionScheme,
) -> MacGrid {
    if scheme == AdvectionScheme::None {
        return vel.clone();
    }
    advect_where(vel, open, dt, scheme, &|_, _| true, &|_, _| true)
}

/// Advects the velocity over `dt` with every face in its owner's field: each phase's velocity
/// is continued across its interfaces far enough that no departure stencil of its own faces
/// (nor of the MacCormack back-trace) leaves it, advected, and kept on its own faces.
/// `before` says which phases each face's current value belongs to (the seed pairs of the
/// step that computed it, see `extension::seed_phases`): a face the interface has just swept
/// over still holds the other phase's velocity, so each phase's field grows from the faces
/// that carried it before, and `owners` (now) says which phase's result each face keeps.
pub(crate) fn advect_by_phase(
    vel: &MacGrid,
    open: &[Vec<f64>; 3],
    before: &[Vec<PhaseId>; 3],
    owners: &[Vec<PhaseId>; 3],
    dt: f64,
    scheme: AdvectionScheme,
) -> MacGrid {
    let phases = owning_phases(owners, open);
    if scheme == AdvectionScheme::None || phases.len() < 2 {
        return advect(vel, open, dt, scheme);
    }
    // Departures lie within the largest displacement; the interpolation stencil reaches two
    // faces further (monotone cubic), so `reach` rings hold every value a kept face's forward
    // or back trace reads, and 2·reach + 1 rings every value those forward values read.
    let displacement = (vel.max_abs() * dt / vel.spec.h).ceil();
    let reach = (displacement.min(100.0) as u8).saturating_add(2);
    let rings = reach.saturating_mul(2).saturating_add(1);
    let mut out = vel.clone();
    for c in &mut out.comps {
        c.fill(0.0);
    }
    for phase in phases {
        let ext = extend(vel, open, &|a, f| carries(&before[a], f, phase), rings);
        let advected = advect_where(
            &ext.field,
            open,
            dt,
            scheme,
            &|a, f| ext.layer[a][f] <= reach,
            &|a, f| owners[a][f] == phase,
        );
        for ((comp, new), own) in out.comps.iter_mut().zip(&advected.comps).zip(owners) {
            comp.par_iter_mut()
                .zip(new)
                .zip(own)
                .for_each(|((o, v), &own)| {
                    if own == phase {
                        *o = *v;
                    }
                });
        }
    }
    out
}
