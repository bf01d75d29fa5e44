//! Variable-density pressure projection with ghost-fluid face densities (see [`crate::phase`])
//! and solid face open fractions s (Batty et al. 2007): with q = p·dt/h the update of a face is
//! u = u* − (q_hi − q_lo)/ρ_face, and zero net flux Σ ±s·u per cell gives the SPD system
//! Σ_faces (s/ρ_face)(q_c − q_nb) = −Σ ±s·u*. Closed regions make it singular (constant
//! pressure per connected region); the right-hand side is made consistent by removing its mean
//! per region, which CG handles.

use crate::config::{LinearSolverSettings, PreconditionerKind};
use crate::error::SolverError;
use crate::layout::{idx, unidx, Layout};
use crate::linalg::mic0::Mic0;
use crate::linalg::multigrid::Multigrid;
use crate::linalg::pcg::{pcg, Preconditioner, SolveStats};
use crate::linalg::stencil::Stencil7;
use crate::mac::MacGrid;
use rayon::prelude::*;

/// Index of the face of component `d` on the upper side of cell `p` along `d`.
#[inline]
fn upper_face(layout: &Layout, p: [usize; 3], d: usize) -> usize {
    let mut q = p;
    q[d] = layout.node_above(d, p[d]);
    idx(layout.face_dims(d), q)
}

/// Index of the face of component `d` on the lower side of cell `p` along `d`.
#[inline]
fn lower_face(layout: &Layout, p: [usize; 3], d: usize) -> usize {
    idx(layout.face_dims(d), p)
}

/// Face indices (lower, upper) of cell `p` along each axis.
#[inline]
fn cell_faces(layout: &Layout, p: [usize; 3]) -> [(usize, usize); 3] {
    [0, 1, 2].map(|d| (lower_face(layout, p, d), upper_face(layout, p, d)))
}

/// β = s/ρ of face `f` of component `d`, 0 when closed.
#[inline]
fn beta(open: &[Vec<f64>; 3], rho_face: &[Vec<f64>; 3], d: usize, f: usize) -> f64 {
    let s = open[d][f];
    if s > 0.0 {
        s / rho_face[d][f]
    } else {
        0.0
    }
}

/// The projection matrix Σ (s/ρ)(q_c − q_nb). One pass over x-rows; a face couples two
/// distinct cells unless it is a wall (β = 0 there) or a periodic axis has a single cell.
pub(crate) fn build_matrix(
    layout: &Layout,
    open: &[Vec<f64>; 3],
    rho_face: &[Vec<f64>; 3],
) -> Stencil7 {
    let mut a = Stencil7::zeros(layout.n, layout.periodic);
    let [nx, ny, _] = layout.n;
    let single = [0, 1, 2].map(|d| layout.n[d] == 1);
    let [o0, o1, o2] = &mut a.off;
    a.diag
        .par_chunks_mut(nx)
        .zip(o0.par_chunks_mut(nx))
        .zip(o1.par_chunks_mut(nx))
        .zip(o2.par_chunks_mut(nx))
        .enumerate()
        .for_each(|(row, (((dg, x0), x1), x2))| {
            let (j, k) = (row % ny, row / ny);
            let offs = [x0, x1, x2];
            for i in 0..nx {
                let p = [i, j, k];
                let faces = cell_faces(layout, p);
                let mut sum = 0.0;
                for d in 0..3 {
                    if single[d] {
                        offs[d][i] = 0.0;
                        continue;
                    }
                    let (lo, up) = faces[d];
                    let bu = beta(open, rho_face, d, up);
                    let bl = beta(open, rho_face, d, lo);
                    offs[d][i] = -bu;
                    sum += bu + bl;
                }
                dg[i] = sum;
            }
        });
    a
}

/// Net outward face flux per cell divided by h: the discrete divergence (1/s).
pub(crate) fn divergence(vel: &MacGrid, open: &[Vec<f64>; 3]) -> Vec<f64> {
    let layout = vel.layout;
    let h = vel.spec.h;
    let [nx, ny, _] = layout.n;
    let mut out = vec![0.0; layout.cells()];
    out.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let (j, k) = (row % ny, row / ny);
        for (i, oi) in o.iter_mut().enumerate() {
            let faces = cell_faces(&layout, [i, j, k]);
            let mut s = 0.0;
            for (d, (lo, up)) in faces.into_iter().enumerate() {
                s += open[d][up] * vel.comps[d][up] - open[d][lo] * vel.comps[d][lo];
            }
            *oi = s / h;
        }
    });
    out
}

/// Removes the mean of `b` over each connected region of the coupling graph of `a`
/// (sequential flood fill in index order, sums in that order: deterministic).
fn make_consistent(a: &Stencil7, b: &mut [f64]) {
    let n = a.len();
    let connected = (0..n).into_par_iter().all(|c| {
        let p = unidx(a.dims, c);
        (0..3).all(|d| a.up(p, d).is_none() || a.off[d][c] != 0.0)
    });
    if connected {
        // Every neighbour pair is coupled: one region, one mean (fixed-order sum).
        let mean = crate::linalg::vecops::sum(b) / n as f64;
        b.par_iter_mut().for_each(|v| *v -= mean);
        return;
    }
    let mut label = vec![usize::MAX; n];
    let mut stack = Vec::new();
    let mut members = Vec::new();
    for seed in 0..n {
        if label[seed] != usize::MAX {
            continue;
        }
        label[seed] = seed;
        stack.push(seed);
        members.clear();
        while let Some(c) = stack.pop() {
            members.push(c);
            let p = unidx(a.dims, c);
            for d in 0..3 {
                if let Some(u) = a.up(p, d) {
                    if a.off[d][c] != 0.0 && label[u] == usize::MAX {
                        label[u] = seed;
                        stack.push(u);
                    }
                }
                if let Some(l) = a.down(p, d) {
                    if a.off[d][l] != 0.0 && label[l] == usize::MAX {
                        label[l] = seed;
                        stack.push(l);
                    }
                }
            }
        }
        members.sort_unstable();
        let mean = members.iter().map(|&c| b[c]).sum::<f64>() / members.len() as f64;
        for &c in &members {
            b[c] -= mean;
        }
    }
}

/// Builds the preconditioner `kind` for `a` and runs PCG.
pub(crate) fn solve_stencil(
    a: &Stencil7,
    b: Vec<f64>,
    x: &mut [f64],
    settings: &LinearSolverSettings,
    system: &'static str,
) -> Result<(SolveStats, usize), SolverError> {
    let (m, mem): (Box<dyn Preconditioner + '_>, usize) = match settings.preconditioner {
        PreconditionerKind::Mic0 => {
            let m = Mic0::new(a);
            let mem = m.memory_bytes();
            (Box::new(m), mem)
        }
        PreconditionerKind::Multigrid => {
            let m = Multigrid::new(a);
            let mem = m.memory_bytes();
            (Box::new(m), mem)
        }
    };
    let stats = pcg(a, m.as_ref(), b, x, settings, system)?;
    Ok((stats, mem))
}

/// Result of a projection.
pub(crate) struct Projected {
    pub stats: SolveStats,
    /// Pressure (Pa) at the cell centres, zero mean per region.
    pub pressure: Vec<f64>,
    /// Bytes of matrix, preconditioner and CG vectors.
    pub memory_bytes: usize,
}

/// Makes `vel` discretely divergence-free (in place), with the pressure jumping by `jumps`
/// (Pa, p_above − p_below, per face; see `jump.rs`) across interface faces.
pub(crate) fn project(
    vel: &mut MacGrid,
    open: &[Vec<f64>; 3],
    rho_face: &[Vec<f64>; 3],
    dt: f64,
    settings: &LinearSolverSettings,
    jumps: Option<&[Vec<f64>; 3]>,
) -> Result<Projected, SolverError> {
    let layout = vel.layout;
    let h = vel.spec.h;
    let a = build_matrix(&layout, open, rho_face);
    let mut b: Vec<f64> = divergence(vel, open)
        .into_par_iter()
        .map(|d| -d * h)
        .collect();
    // In q = p·dt/h a jump J is ĵ = J·dt/h, and a face's flux (q_above − q_below − ĵ)·β: each
    // cell's zero-net-outflow row gains −β·ĵ for its upper faces and +β·ĵ for its lower ones.
    let scale = dt / h;
    if let Some(j) = jumps {
        let [nx, ny, _] = layout.n;
        b.par_chunks_mut(nx).enumerate().for_each(|(row, bs)| {
            let (jy, k) = (row % ny, row / ny);
            for (i, bi) in bs.iter_mut().enumerate() {
                for (d, (lo, up)) in cell_faces(&layout, [i, jy, k]).into_iter().enumerate() {
                    *bi += scale
                        * (beta(open, rho_face, d, lo) * j[d][lo]
                            - beta(open, rho_face, d, up) * j[d][up]);
                }
            }
        });
    }
    make_consistent(&a, &mut b);
    let mut q = vec![0.0; layout.cells()];
    let (stats, pre_mem) = solve_stencil(&a, b, &mut q, settings, "pressure")?;
    for d in 0..3 {
        let fd = layout.face_dims(d);
        let comp = &mut vel.comps[d];
        comp.par_iter_mut().enumerate().for_each(|(f, u)| {
            let s = open[d][f];
            if s == 0.0 {
                *u = 0.0;
                return;
            }
            let p = unidx(fd, f);
            if let (Some(lo), Some(hi)) =
                (layout.cell_below(d, p[d]), layout.cell_above_node(d, p[d]))
            {
                let mut pl = p;
                pl[d] = lo;
                let mut ph = p;
                ph[d] = hi;
                let jump = jumps.map_or(0.0, |j| scale * j[d][f]);
                *u -= (q[idx(layout.n, ph)] - q[idx(layout.n, pl)] - jump) / rho_face[d][f];
            }
        });
    }
    let pressure = q.par_iter().map(|v| v * h / dt).collect();
    let n = layout.cells();
    // CG's four vectors (x, r, p, q; see `pcg`).
    let memory_bytes = a.memory_bytes() + pre_mem + 4 * n * std::mem::size_of::<f64>();
    Ok(Projected {
        stats,
        pressure,
        memory_bytes,
    })
}
