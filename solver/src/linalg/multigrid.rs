//! Geometric multigrid preconditioner for [`Stencil7`] matrices: 2×2×2 aggregation, coarse
//! matrices by Galerkin summation of the fine couplings across each coarse face, scaled by ½
//! (piecewise-constant prolongation overweights the coarse Laplacian by 2 in 3D), mass-like
//! diagonal parts summed unscaled. One symmetric V-cycle (red–black Gauss–Seidel, red→black
//! before, black→red after) is an SPD preconditioner for CG. Parallel and deterministic: each
//! colour update reads only the previous iterate.

use crate::layout::{idx, par_fill};
use crate::linalg::pcg::Preconditioner;
use crate::linalg::stencil::Stencil7;
use rayon::prelude::*;
use std::sync::{Mutex, PoisonError};

/// Smoothing sweep pairs before and after the coarse correction.
const SMOOTH: usize = 2;
/// Sweep pairs on the coarsest level.
const COARSEST_SWEEPS: usize = 30;
/// Stop coarsening when a level has at most this many unknowns.
const COARSEST_CELLS: usize = 64;
/// Scale of the aggregated couplings (see module doc).
const COARSE_SCALE: f64 = 0.5;
/// Minimum x-rows per rayon task: keeps the small levels from drowning in task overhead.
const ROWS_PER_TASK: usize = 32;

/// The hierarchy: level 0 is the matrix itself.
pub(crate) struct Multigrid<'a> {
    fine: &'a Stencil7,
    coarse: Vec<Stencil7>,
    /// Per-level work vectors (iterate, scratch, restricted residual of the level below),
    /// reused across applications; PCG applies the preconditioner sequentially.
    scratch: Vec<Mutex<[Vec<f64>; 3]>>,
}

fn coarsen(a: &Stencil7) -> Stencil7 {
    let cd = [
        a.dims[0].div_ceil(2),
        a.dims[1].div_ceil(2),
        a.dims[2].div_ceil(2),
    ];
    let n = cd[0] * cd[1] * cd[2];
    let entries: Vec<[f64; 4]> = (0..n)
        .into_par_iter()
        .map(|cc| {
            let pc = crate::layout::unidx(cd, cc);
            let mut out = [0.0; 4];
            for dk in 0..2 {
                for dj in 0..2 {
                    for di in 0..2 {
                        let p = [2 * pc[0] + di, 2 * pc[1] + dj, 2 * pc[2] + dk];
                        if p[0] >= a.dims[0] || p[1] >= a.dims[1] || p[2] >= a.dims[2] {
                            continue;
                        }
                        let c = idx(a.dims, p);
                        let mut extra = a.diag[c];
                        for d in 0..3 {
                            if a.up(p, d).is_some() {
                                extra += a.off[d][c];
                            }
                            if let Some(l) = a.down(p, d) {
                                extra += a.off[d][l];
                            }
                            if let Some(u) = a.up(p, d) {
                                let pu = crate::layout::unidx(a.dims, u);
                                if pu[d] / 2 != pc[d] {
                                    out[1 + d] += COARSE_SCALE * a.off[d][c];
                                }
                            }
                        }
                        out[0] += extra.max(0.0);
                    }
                }
            }
            out
        })
        .collect();
    let mut s = Stencil7::zeros(cd, a.periodic);
    for (c, e) in entries.iter().enumerate() {
        for d in 0..3 {
            s.off[d][c] = e[1 + d];
        }
    }
    let diag: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|c| {
            let p = crate::layout::unidx(cd, c);
            let mut dsum = entries[c][0];
            for d in 0..3 {
                if s.up(p, d).is_some() {
                    dsum -= s.off[d][c];
                }
                if let Some(l) = s.down(p, d) {
                    dsum -= s.off[d][l];
                }
            }
            dsum
        })
        .collect();
    s.diag = diag;
    s
}

/// One red–black half-sweep: unknowns of `color` get their Gauss–Seidel value from `x`.
fn half_sweep(a: &Stencil7, b: &[f64], x: &[f64], out: &mut [f64], color: usize) {
    let nx = a.dims[0];
    let ny = a.dims[1];
    out.par_chunks_mut(nx)
        .with_min_len(ROWS_PER_TASK)
        .enumerate()
        .for_each(|(row, o)| {
            let (j, k) = (row % ny, row / ny);
            let base = row * nx;
            a.offdiag_row(row, x, o);
            let first = (color + j + k) % 2;
            for (i, oi) in o.iter_mut().enumerate() {
                let c = base + i;
                *oi = if i % 2 == first && a.diag[c] > 0.0 {
                    (b[c] - *oi) / a.diag[c]
                } else {
                    x[c]
                };
            }
        });
}

fn sweeps(a: &Stencil7, b: &[f64], x: &mut Vec<f64>, tmp: &mut Vec<f64>, colors: &[usize]) {
    for &col in colors {
        half_sweep(a, b, x, tmp, col);
        std::mem::swap(x, tmp);
    }
}

impl<'a> Multigrid<'a> {
    /// Builds the hierarchy below `a`.
    pub fn new(a: &'a Stencil7) -> Self {
        let mut coarse: Vec<Stencil7> = Vec::new();
        loop {
            let last = coarse.last().unwrap_or(a);
            if last.len() <= COARSEST_CELLS || last.dims.iter().all(|&d| d <= 2) {
                break;
            }
            let next = coarsen(last);
            coarse.push(next);
        }
        let scratch = std::iter::once(a.len())
            .chain(coarse.iter().map(Stencil7::len))
            .map(|n| Mutex::new([vec![0.0; n], vec![0.0; n], vec![0.0; n]]))
            .collect();
        Self {
            fine: a,
            coarse,
            scratch,
        }
    }

    /// Bytes held by the coarse levels and the work vectors of every level.
    pub fn memory_bytes(&self) -> usize {
        let work: usize = std::iter::once(self.fine.len())
            .chain(self.coarse.iter().map(Stencil7::len))
            .map(|n| 3 * n * std::mem::size_of::<f64>())
            .sum();
        self.coarse
            .iter()
            .map(Stencil7::memory_bytes)
            .sum::<usize>()
            + work
    }

    fn level(&self, l: usize) -> &Stencil7 {
        if l == 0 {
            self.fine
        } else {
            &self.coarse[l - 1]
        }
    }

    /// One V-cycle from a zero guess for A·x = b on level `l`; the result is left in
    /// `scratch[l][0]`.
    fn vcycle(&self, l: usize, b: &[f64]) {
        let a = self.level(l);
        let mut guard = self.scratch[l]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let [x, tmp, _] = &mut *guard;
        x.par_iter_mut().for_each(|v| *v = 0.0);
        if l == self.coarse.len() {
            for _ in 0..COARSEST_SWEEPS {
                sweeps(a, b, x, tmp, &[0, 1]);
            }
            for _ in 0..COARSEST_SWEEPS {
                sweeps(a, b, x, tmp, &[1, 0]);
            }
            return;
        }
        for _ in 0..SMOOTH {
            sweeps(a, b, x, tmp, &[0, 1]);
        }
        a.apply(x, tmp);
        tmp.par_iter_mut().zip(b).for_each(|(t, bi)| *t = bi - *t);
        let c = self.level(l + 1);
        let cd = c.dims;
        let fd = a.dims;
        let resid = &*tmp;
        let mut next = self.scratch[l + 1]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let rc = &mut next[2];
        par_fill(cd, rc, |pc| {
            let mut s = 0.0;
            for dk in 0..2 {
                for dj in 0..2 {
                    for di in 0..2 {
                        let p = [2 * pc[0] + di, 2 * pc[1] + dj, 2 * pc[2] + dk];
                        if p[0] < fd[0] && p[1] < fd[1] && p[2] < fd[2] {
                            s += resid[idx(fd, p)];
                        }
                    }
                }
            }
            s
        });
        let rc = std::mem::take(&mut next[2]);
        drop(next);
        self.vcycle(l + 1, &rc);
        let mut next = self.scratch[l + 1]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        next[2] = rc;
        let ec = &next[0];
        let nx = fd[0];
        let ny = fd[1];
        x.par_chunks_mut(nx)
            .with_min_len(ROWS_PER_TASK)
            .enumerate()
            .for_each(|(row, xr)| {
                let (j, k) = (row % ny, row / ny);
                let crow = idx(cd, [0, j / 2, k / 2]);
                for (i, xi) in xr.iter_mut().enumerate() {
                    *xi += ec[crow + i / 2];
                }
            });
        drop(next);
        for _ in 0..SMOOTH {
            sweeps(a, b, x, tmp, &[1, 0]);
        }
    }
}

impl Preconditioner for Multigrid<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.vcycle(0, r);
        let guard = self.scratch[0]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        z.copy_from_slice(&guard[0]);
    }
}
