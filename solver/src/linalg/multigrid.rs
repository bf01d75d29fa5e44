//! Geometric multigrid preconditioner for [`Stencil7`] matrices: 2×2×2 aggregation, coarse
//! matrices by Galerkin summation of the fine couplings across each coarse face, scaled by ½
//! (piecewise-constant prolongation overweights the coarse Laplacian by 2 in 3D), mass-like
//! diagonal parts summed unscaled. One symmetric V-cycle (red–black Gauss–Seidel, red→black
//! before, black→red after) is an SPD preconditioner for CG. Parallel and deterministic: each
//! colour update reads only the previous iterate. [`Multigrid::with_line_smoothing`] relaxes
//! whole x-rows at once (red–black by row, in place), for matrices coupled far more strongly
//! along x than across; each row's tridiagonal factorisation is computed once, at set-up. The
//! hierarchy is stored in the precision of its matrix ([`Real`]): f32 for a
//! preconditioner-only matrix.

use crate::layout::idx;
use crate::linalg::pcg::Preconditioner;
use crate::linalg::stencil::{Real, Stencil7};
use rayon::prelude::*;
use std::sync::{Mutex, PoisonError};

/// Smoothing sweep pairs before and after the coarse correction.
const SMOOTH: usize = 2;
/// Line-sweep pairs before and after the coarse correction: the viscosity bench (128³, 1000:1)
/// takes 12 CG iterations with one pair and 11 with two, so the second pair does not pay.
const LINE_SMOOTH: usize = 1;
/// Sweep pairs on the coarsest level.
const COARSEST_SWEEPS: usize = 30;
/// Stop coarsening when a level has at most this many unknowns.
const COARSEST_CELLS: usize = 64;
/// Scale of the aggregated couplings (see module doc).
const COARSE_SCALE: f64 = 0.5;
/// Minimum x-rows per rayon task: keeps the small levels from drowning in task overhead.
const ROWS_PER_TASK: usize = 32;
/// Rows of a line sweep solved side by side (see [`solve_rows`]): on the viscosity bench (128³)
/// a preconditioner application (three blocks' V-cycles) takes 0.090–0.095 s with 4,
/// 0.104–0.108 s with 8 and 0.097–0.103 s with 2.
const LINE_GROUP: usize = 4;

/// Work vectors of one level: iterate, scratch (empty where line sweeps run in place),
/// restricted residual of the level below.
type Work<T> = Mutex<[Vec<T>; 3]>;

/// The hierarchy: level 0 is the matrix itself.
pub(crate) struct Multigrid<'a, T: Real = f64> {
    fine: &'a Stencil7<T>,
    coarse: Vec<Stencil7<T>>,
    /// Per-level work vectors, reused across applications; PCG applies the preconditioner
    /// sequentially.
    scratch: Vec<Work<T>>,
    /// Per level, the inverse pivots of each x-row's tridiagonal block (0 where the diagonal
    /// is not positive); empty without line smoothing.
    pivots: Vec<Vec<T>>,
    /// Smoothing sweep pairs before and after each coarse correction (at least one: the first
    /// starts from the zero guess).
    smooth: usize,
}

/// Galerkin coarse matrix of `a` (see module doc), summed in f64.
fn coarsen<T: Real>(a: &Stencil7<T>) -> Stencil7<T> {
    let fd = a.dims;
    let cd = fd.map(|d| d.div_ceil(2));
    let mut s = Stencil7::zeros(cd, a.periodic);
    let Stencil7 { diag, off, .. } = &mut s;
    let [off0, off1, off2] = off;
    // Pass 1: couplings across each coarse face, and each aggregate's row sums in `diag`.
    diag.par_chunks_mut(cd[0])
        .zip(off0.par_chunks_mut(cd[0]))
        .zip(off1.par_chunks_mut(cd[0]))
        .zip(off2.par_chunks_mut(cd[0]))
        .enumerate()
        .for_each(|(row, (((dg, o0), o1), o2))| {
            let (jc, kc) = (row % cd[1], row / cd[1]);
            for ic in 0..cd[0] {
                let pc = [ic, jc, kc];
                let mut out = [0.0; 4];
                for dk in 0..2 {
                    for dj in 0..2 {
                        for di in 0..2 {
                            let p = [2 * ic + di, 2 * jc + dj, 2 * kc + dk];
                            if p[0] >= fd[0] || p[1] >= fd[1] || p[2] >= fd[2] {
                                continue;
                            }
                            let c = idx(fd, p);
                            let mut extra = a.diag[c].to_f64();
                            for d in 0..3 {
                                if a.up(p, d).is_some() {
                                    let o = a.off[d][c].to_f64();
                                    extra += o;
                                    // A coupling between two aggregates (the +d neighbour
                                    // wraps to node 0 past the end).
                                    let ud = if p[d] + 1 < fd[d] { p[d] + 1 } else { 0 };
                                    if ud / 2 != pc[d] {
                                        out[1 + d] += COARSE_SCALE * o;
                                    }
                                }
                                if let Some(l) = a.down(p, d) {
                                    extra += a.off[d][l].to_f64();
                                }
                            }
                            out[0] += extra.max(0.0);
                        }
                    }
                }
                dg[ic] = T::from_f64(out[0]);
                o0[ic] = T::from_f64(out[1]);
                o1[ic] = T::from_f64(out[2]);
                o2[ic] = T::from_f64(out[3]);
            }
        });
    // Pass 2: diagonal = row sum minus the coarse couplings.
    let mut diag = std::mem::take(&mut s.diag);
    diag.par_chunks_mut(cd[0])
        .enumerate()
        .for_each(|(row, dg)| {
            let (j, k) = (row % cd[1], row / cd[1]);
            for (i, v) in dg.iter_mut().enumerate() {
                let p = [i, j, k];
                let c = row * cd[0] + i;
                let mut dsum = v.to_f64();
                for d in 0..3 {
                    if s.up(p, d).is_some() {
                        dsum -= s.off[d][c].to_f64();
                    }
                    if let Some(l) = s.down(p, d) {
                        dsum -= s.off[d][l].to_f64();
                    }
                }
                *v = T::from_f64(dsum);
            }
        });
    s.diag = diag;
    s
}

/// Inverse pivots of the tridiagonal factorisation of each x-row of `a` (couplings along x,
/// the periodic wrap excepted), 0 where the diagonal is not positive; computed in f64.
fn line_pivots<T: Real>(a: &Stencil7<T>) -> Vec<T> {
    let nx = a.dims[0];
    let mut pivots = vec![T::ZERO; a.len()];
    pivots.par_chunks_mut(nx).enumerate().for_each(|(row, pr)| {
        let base = row * nx;
        let mut prev_upper = 0.0;
        for (i, v) in pr.iter_mut().enumerate() {
            let d = a.diag[base + i].to_f64();
            if d <= 0.0 {
                prev_upper = 0.0;
                continue;
            }
            let lower = if i > 0 {
                a.off[0][base + i - 1].to_f64()
            } else {
                0.0
            };
            let m = d - lower * prev_upper;
            *v = T::from_f64(1.0 / m);
            let up = if i + 1 < nx {
                a.off[0][base + i].to_f64()
            } else {
                0.0
            };
            prev_upper = up / m;
        }
    });
    pivots
}

/// One red–black half-sweep: unknowns of `color` get their Gauss–Seidel value from `x`
/// (`None`: a zero guess, which is then not read; the same values as from zeros).
fn half_sweep<T: Real>(a: &Stencil7<T>, b: &[T], x: Option<&[T]>, out: &mut [T], color: usize) {
    let nx = a.dims[0];
    let ny = a.dims[1];
    out.par_chunks_mut(nx)
        .with_min_len(ROWS_PER_TASK)
        .enumerate()
        .for_each(|(row, o)| {
            let (j, k) = (row % ny, row / ny);
            let base = row * nx;
            match x {
                Some(x) => a.offdiag_row(row, x, o),
                None => o.iter_mut().for_each(|v| *v = T::ZERO),
            }
            let first = (color + j + k) % 2;
            for (i, oi) in o.iter_mut().enumerate() {
                let c = base + i;
                *oi = if i % 2 == first && a.diag[c] > T::ZERO {
                    (b[c] - *oi) / a.diag[c]
                } else {
                    x.map_or(T::ZERO, |x| x[c])
                };
            }
        });
}

/// Whether every x-row's y and z neighbours have the other colour ((j + k) mod 2), so that a
/// line half-sweep may overwrite its rows in place: not where a periodic axis across the rows
/// has an odd length (its wrap joins two rows of one colour).
fn rows_two_coloured<T: Real>(a: &Stencil7<T>) -> bool {
    (1..3).all(|d| !(a.periodic[d] && a.dims[d] > 1 && a.dims[d] % 2 == 1))
}

/// Solves the x-rows in `rows` (index, values) of one colour exactly for their own tridiagonal
/// blocks (couplings along x, those across a periodic wrap excepted; `pivots` from
/// [`line_pivots`]), overwriting them, with the couplings to other rows read through `read`
/// (never one of `rows`). A row's own wrap coupling and its unknowns with no positive
/// diagonal use the values it holds, which must be the previous iterate's. `zero`: the
/// previous iterate is zero, nothing is read and such unknowns become 0. The rows of a group
/// of [`LINE_GROUP`] are eliminated side by side: each row's recurrence is a serial chain, and
/// interleaving independent chains keeps the core busy.
fn solve_rows<'x, T: Real>(
    a: &Stencil7<T>,
    pivots: &[T],
    b: &[T],
    rows: &mut [(usize, &mut [T])],
    read: impl Fn(usize) -> &'x [T] + Sync,
    zero: bool,
) {
    let nx = a.dims[0];
    let off = &a.off[0];
    rows.par_chunks_mut(LINE_GROUP)
        .with_min_len(ROWS_PER_TASK.div_ceil(LINE_GROUP))
        .for_each_init(
            || {
                (
                    vec![T::ZERO; nx * LINE_GROUP],
                    vec![T::ZERO; nx * LINE_GROUP],
                )
            },
            |(upper, acc), group| {
                for ((row, o), acc) in group.iter().zip(acc.chunks_mut(nx)) {
                    acc.iter_mut().for_each(|v| *v = T::ZERO);
                    if zero {
                        continue;
                    }
                    let base = row * nx;
                    if a.periodic[0] && nx > 1 {
                        acc[nx - 1] += off[base + nx - 1] * o[0];
                        acc[0] += off[base + nx - 1] * o[nx - 1];
                    }
                    a.cross_row_from(*row, &read, acc);
                }
                // Forward elimination with the stored pivots; an unknown with no positive
                // diagonal keeps its value.
                let mut prev = [T::ZERO; LINE_GROUP];
                for i in 0..nx {
                    for (lane, (row, o)) in group.iter_mut().enumerate() {
                        let c = *row * nx + i;
                        let inv = pivots[c];
                        if inv == T::ZERO {
                            upper[lane * nx + i] = T::ZERO;
                            if zero {
                                o[i] = T::ZERO;
                            }
                        } else {
                            let lower = if i > 0 { off[c - 1] } else { T::ZERO };
                            let up = if i + 1 < nx { off[c] } else { T::ZERO };
                            upper[lane * nx + i] = up * inv;
                            o[i] = (b[c] - acc[lane * nx + i] - lower * prev[lane]) * inv;
                        }
                        prev[lane] = o[i];
                    }
                }
                for i in (0..nx.saturating_sub(1)).rev() {
                    for (lane, (_, o)) in group.iter_mut().enumerate() {
                        let next = o[i + 1];
                        o[i] -= upper[lane * nx + i] * next;
                    }
                }
            },
        );
}

/// One red–black line half-sweep on `x`: each x-row of `color` ((j + k) mod 2) gets the exact
/// solution of its own tridiagonal block given the other rows (see [`solve_rows`]). Every row
/// solve reads only rows of the other colour, so the sweep is parallel and deterministic, and
/// it runs in place where the rows are two-coloured ([`rows_two_coloured`]); elsewhere the
/// previous iterate is first copied to `tmp` and read from there. `zero`: `x` is taken as
/// zero, not read.
fn line_half_sweep<T: Real>(
    a: &Stencil7<T>,
    pivots: &[T],
    b: &[T],
    x: &mut [T],
    tmp: &mut [T],
    zero: bool,
    color: usize,
) {
    let nx = a.dims[0];
    let ny = a.dims[1];
    let coloured = |row: usize| (row % ny + row / ny) % 2 == color;
    if zero {
        x.par_chunks_mut(nx)
            .with_min_len(ROWS_PER_TASK)
            .enumerate()
            .filter(|(row, _)| !coloured(*row))
            .for_each(|(_, r)| r.iter_mut().for_each(|v| *v = T::ZERO));
    }
    if !zero && !rows_two_coloured(a) {
        tmp.copy_from_slice(x);
        let old: &[T] = tmp;
        let mut rows: Vec<(usize, &mut [T])> = x
            .chunks_mut(nx)
            .enumerate()
            .filter(|(row, _)| coloured(*row))
            .collect();
        solve_rows(
            a,
            pivots,
            b,
            &mut rows,
            |r| &old[r * nx..(r + 1) * nx],
            zero,
        );
        return;
    }
    let mut rows: Vec<(usize, &mut [T])> = Vec::with_capacity(x.len() / nx / 2 + 1);
    let mut others: Vec<&[T]> = Vec::with_capacity(x.len() / nx);
    for (row, r) in x.chunks_mut(nx).enumerate() {
        if coloured(row) {
            rows.push((row, r));
            others.push(&[]);
        } else {
            others.push(r);
        }
    }
    solve_rows(
        a,
        pivots,
        b,
        &mut rows,
        |r| {
            debug_assert!(!coloured(r), "row {r} is being written");
            others[r]
        },
        zero,
    );
}

/// Half-sweeps of the given colours on `x`, point or line (`pivots` non-empty) Gauss–Seidel;
/// `zero`: the first starts from zero, without reading `x`. Point sweeps, and line sweeps
/// whose rows are not two-coloured, write into `tmp` (then swapped with `x`) or read from it.
fn sweeps<T: Real>(
    a: &Stencil7<T>,
    pivots: &[T],
    b: &[T],
    x: &mut Vec<T>,
    tmp: &mut Vec<T>,
    mut zero: bool,
    colors: &[usize],
) {
    for &col in colors {
        if pivots.is_empty() {
            half_sweep(a, b, (!zero).then_some(&x[..]), tmp, col);
            std::mem::swap(x, tmp);
        } else {
            line_half_sweep(a, pivots, b, x, tmp, zero, col);
        }
        zero = false;
    }
}

/// The residual b − A·x summed over each 2×2×2 aggregate into `out` (a box of `cd`), in one
/// pass: each coarse row computes the residual of its up to four fine rows into a buffer and
/// sums them there, the same values and order as forming the whole residual first.
fn restrict_residual<T: Real>(a: &Stencil7<T>, b: &[T], x: &[T], cd: [usize; 3], out: &mut [T]) {
    let fd = a.dims;
    let nx = fd[0];
    out.par_chunks_mut(cd[0]).enumerate().for_each_init(
        || vec![T::ZERO; 4 * nx],
        |rows, (crow, o)| {
            let (jc, kc) = (crow % cd[1], crow / cd[1]);
            let mut present = [false; 4];
            for dk in 0..2 {
                for dj in 0..2 {
                    let (j, k) = (2 * jc + dj, 2 * kc + dk);
                    if j >= fd[1] || k >= fd[2] {
                        continue;
                    }
                    let row = j + fd[1] * k;
                    let base = row * nx;
                    let r = &mut rows[(2 * dk + dj) * nx..][..nx];
                    a.offdiag_row(row, x, r);
                    for (i, ri) in r.iter_mut().enumerate() {
                        *ri += a.diag[base + i] * x[base + i];
                        *ri = b[base + i] - *ri;
                    }
                    present[2 * dk + dj] = true;
                }
            }
            for (ic, oi) in o.iter_mut().enumerate() {
                let mut s = T::ZERO;
                for q in (0..4).filter(|&q| present[q]) {
                    for di in 0..2 {
                        let i = 2 * ic + di;
                        if i < nx {
                            s += rows[q * nx + i];
                        }
                    }
                }
                *oi = s;
            }
        },
    );
}

impl<'a, T: Real> Multigrid<'a, T> {
    /// Builds the hierarchy below `a`.
    pub fn new(a: &'a Stencil7<T>) -> Self {
        Self::build(a, false)
    }

    /// Builds the hierarchy below `a`, smoothing with red–black x-line Gauss–Seidel.
    pub fn with_line_smoothing(a: &'a Stencil7<T>) -> Self {
        Self::build(a, true)
    }

    fn build(a: &'a Stencil7<T>, lines: bool) -> Self {
        let mut coarse: Vec<Stencil7<T>> = Vec::new();
        loop {
            let last = coarse.last().unwrap_or(a);
            if last.len() <= COARSEST_CELLS || last.dims.iter().all(|&d| d <= 2) {
                break;
            }
            let next = coarsen(last);
            coarse.push(next);
        }
        // Line sweeps on two-coloured rows run in place and need no scratch vector.
        let scratch = std::iter::once(a)
            .chain(&coarse)
            .map(|m| {
                let n = m.len();
                let tmp = if lines && rows_two_coloured(m) { 0 } else { n };
                Mutex::new([vec![T::ZERO; n], vec![T::ZERO; tmp], vec![T::ZERO; n]])
            })
            .collect();
        let mut mg = Self {
            fine: a,
            coarse,
            scratch,
            pivots: Vec::new(),
            smooth: SMOOTH,
        };
        if lines {
            mg.pivots = (0..=mg.coarse.len())
                .map(|l| line_pivots(mg.level(l)))
                .collect();
            mg.smooth = LINE_SMOOTH;
        }
        mg
    }

    /// Bytes held by the coarse levels, the line pivots and the work vectors of every level.
    pub fn memory_bytes(&self) -> usize {
        let work: usize = self
            .scratch
            .iter()
            .map(|w| {
                let w = w.lock().unwrap_or_else(PoisonError::into_inner);
                w.iter().map(Vec::len).sum::<usize>()
            })
            .sum();
        let pivots: usize = self.pivots.iter().map(Vec::len).sum();
        self.coarse
            .iter()
            .map(Stencil7::memory_bytes)
            .sum::<usize>()
            + (work + pivots) * std::mem::size_of::<T>()
    }

    fn level(&self, l: usize) -> &Stencil7<T> {
        if l == 0 {
            self.fine
        } else {
            &self.coarse[l - 1]
        }
    }

    /// Line pivots of level `l` (empty for point smoothing).
    fn level_pivots(&self, l: usize) -> &[T] {
        self.pivots.get(l).map_or(&[], Vec::as_slice)
    }

    /// One V-cycle from a zero guess for A·x = b on level `l`; the result is left in
    /// `scratch[l][0]`.
    fn vcycle(&self, l: usize, b: &[T]) {
        let a = self.level(l);
        let piv = self.level_pivots(l);
        let mut guard = self.scratch[l]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        let [x, tmp, _] = &mut *guard;
        // The first half-sweep starts from zero and writes every unknown.
        sweeps(a, piv, b, x, tmp, true, &[0, 1]);
        if l == self.coarse.len() {
            for _ in 1..COARSEST_SWEEPS {
                sweeps(a, piv, b, x, tmp, false, &[0, 1]);
            }
            for _ in 0..COARSEST_SWEEPS {
                sweeps(a, piv, b, x, tmp, false, &[1, 0]);
            }
            return;
        }
        for _ in 1..self.smooth {
            sweeps(a, piv, b, x, tmp, false, &[0, 1]);
        }
        let c = self.level(l + 1);
        let cd = c.dims;
        let fd = a.dims;
        let mut next = self.scratch[l + 1]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        restrict_residual(a, b, x, cd, &mut next[2]);
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
        for _ in 0..self.smooth {
            sweeps(a, piv, b, x, tmp, false, &[1, 0]);
        }
    }

    /// One V-cycle whose right-hand side `fill` writes and whose result `read` takes, both
    /// in the level-0 work vectors (the restricted-residual slot is free on level 0), so a
    /// caller that renumbers vectors needs no copies of its own.
    pub fn apply_with(&self, fill: impl FnOnce(&mut [T]), read: impl FnOnce(&[T])) {
        let mut rhs = {
            let mut guard = self.scratch[0]
                .lock()
                .unwrap_or_else(PoisonError::into_inner);
            std::mem::take(&mut guard[2])
        };
        fill(&mut rhs);
        self.vcycle(0, &rhs);
        let mut guard = self.scratch[0]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        read(&guard[0]);
        guard[2] = rhs;
    }
}

impl Preconditioner for Multigrid<'_, f64> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        self.vcycle(0, r);
        let guard = self.scratch[0]
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        z.copy_from_slice(&guard[0]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An SPD M-matrix on a 7×6×5 box, periodic along y, with x-couplings 10⁴ times the
    /// others in half of it: the anisotropy a viscosity jump leaves.
    fn anisotropic() -> Stencil7 {
        anisotropic_on([7, 6, 5], [false, true, false])
    }

    /// [`anisotropic`] on another box.
    fn anisotropic_on(dims: [usize; 3], periodic: [bool; 3]) -> Stencil7 {
        let mut s = Stencil7::zeros(dims, periodic);
        let coupled = |p: [usize; 3], d: usize| periodic[d] || p[d] + 1 < dims[d];
        for c in 0..s.len() {
            let p = crate::layout::unidx(s.dims, c);
            let strong = if p[2] < 3 { 1e4 } else { 1.0 };
            s.off[0][c] = if coupled(p, 0) {
                -strong * (1.0 + (c % 3) as f64)
            } else {
                0.0
            };
            s.off[1][c] = if coupled(p, 1) {
                -1.0 - (c % 2) as f64
            } else {
                0.0
            };
            s.off[2][c] = if coupled(p, 2) { -0.5 } else { 0.0 };
        }
        for c in 0..s.len() {
            let p = crate::layout::unidx(s.dims, c);
            let mut d = 0.1 + (c % 5) as f64 * 0.01;
            for k in 0..3 {
                d -= s.off[k][c];
                if let Some(l) = s.down(p, k) {
                    d -= s.off[k][l];
                }
            }
            s.diag[c] = d;
        }
        s
    }

    /// Dense M⁻¹ column by column.
    fn dense(m: &Multigrid<'_>, n: usize) -> Vec<Vec<f64>> {
        (0..n)
            .map(|j| {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                let mut z = vec![0.0; n];
                m.apply(&e, &mut z);
                z
            })
            .collect()
    }

    /// Rows two-coloured (swept in place), and periodic axes of odd length across them, whose
    /// wrap joins rows of one colour (swept from a copy).
    fn line_cases() -> [Stencil7; 3] {
        [
            anisotropic(),
            anisotropic_on([6, 5, 4], [true, true, false]),
            anisotropic_on([5, 4, 3], [false, false, true]),
        ]
    }

    #[test]
    fn line_smoothed_multigrid_is_symmetric_positive_definite() {
        for a in line_cases() {
            check_spd(&a);
        }
    }

    /// Line sweeps' defining property: a half-sweep leaves the rows of the other colour as
    /// they were, and each row of its colour solving its own equations exactly given the
    /// previous iterate on the other rows.
    #[test]
    fn a_line_half_sweep_solves_its_rows_given_the_others() {
        for a in line_cases() {
            let n = a.len();
            let nx = a.dims[0];
            let ny = a.dims[1];
            let b: Vec<f64> = (0..n).map(|c| ((c * 7) % 11) as f64 - 5.0).collect();
            let x0: Vec<f64> = (0..n).map(|c| ((c * 5) % 13) as f64 - 6.0).collect();
            let pivots = line_pivots(&a);
            for color in 0..2 {
                let mut x = x0.clone();
                let mut tmp = vec![0.0; n];
                line_half_sweep(&a, &pivots, &b, &mut x, &mut tmp, false, color);
                for row in 0..n / nx {
                    let base = row * nx;
                    let (new, old) = (&x[base..base + nx], &x0[base..base + nx]);
                    if (row % ny + row / ny) % 2 != color {
                        assert_eq!(new, old, "row {row} of the other colour changed");
                        continue;
                    }
                    let mut r = vec![0.0; nx];
                    a.cross_row(row, &x0, &mut r);
                    let off = &a.off[0][base..base + nx];
                    for i in 0..nx {
                        let mut ax = r[i] + a.diag[base + i] * new[i];
                        if i + 1 < nx {
                            ax += off[i] * new[i + 1];
                        }
                        if i > 0 {
                            ax += off[i - 1] * new[i - 1];
                        }
                        // The wrap coupling along a periodic x is taken from the previous
                        // iterate (the row's tridiagonal block leaves it out).
                        if a.periodic[0] && i == 0 {
                            ax += off[nx - 1] * old[nx - 1];
                        }
                        if a.periodic[0] && i == nx - 1 {
                            ax += off[nx - 1] * old[0];
                        }
                        // Pivots up to ~6e4 against right-hand sides of order 10: round-off
                        // far below 1e-8 of the diagonal's scale.
                        let scale = a.diag[base + i];
                        assert!(
                            (ax - b[base + i]).abs() < 1e-8 * scale,
                            "row {row}, {i}: {ax} vs {}",
                            b[base + i]
                        );
                    }
                }
            }
        }
    }

    /// M⁻¹ of the line-smoothed hierarchy on `a` is symmetric positive definite.
    fn check_spd(a: &Stencil7) {
        let n = a.len();
        let m = Multigrid::with_line_smoothing(a);
        let cols = dense(&m, n);
        let scale = cols.iter().flatten().fold(0.0_f64, |s, v| s.max(v.abs()));
        for (i, ci) in cols.iter().enumerate() {
            for (j, cj) in cols.iter().enumerate().take(i) {
                // Symmetric up to round-off of the V-cycle's sums (~1e-16 per operation,
                // a few hundred operations per entry).
                assert!(
                    (ci[j] - cj[i]).abs() < 1e-10 * scale,
                    "({i},{j}): {} vs {}",
                    ci[j],
                    cj[i]
                );
            }
        }
        // Positive definite: dense Cholesky of the symmetrised M⁻¹ has positive pivots.
        let mut l: Vec<Vec<f64>> = Vec::with_capacity(n);
        for i in 0..n {
            let mut row = vec![0.0; i + 1];
            for j in 0..=i {
                let lj = if j < i { &l[j] } else { &row };
                let dot: f64 = row[..j].iter().zip(&lj[..j]).map(|(p, q)| p * q).sum();
                let s = 0.5 * (cols[i][j] + cols[j][i]) - dot;
                if i == j {
                    assert!(s > 0.0, "pivot {i}: {s}");
                    row[i] = s.sqrt();
                } else {
                    row[j] = s / l[j][j];
                }
            }
            l.push(row);
        }
    }

    #[test]
    fn a_line_sweep_solves_decoupled_lines_exactly() {
        let mut a = anisotropic();
        a.off[1].iter_mut().for_each(|v| *v = 0.0);
        a.off[2].iter_mut().for_each(|v| *v = 0.0);
        let n = a.len();
        let x_true: Vec<f64> = (0..n).map(|c| ((c * 5) % 13) as f64 - 6.0).collect();
        let mut b = vec![0.0; n];
        a.apply(&x_true, &mut b);
        let mut x = vec![0.0; n];
        let mut tmp = vec![0.0; n];
        sweeps(&a, &line_pivots(&a), &b, &mut x, &mut tmp, false, &[0, 1]);
        for (c, (got, want)) in x.iter().zip(&x_true).enumerate() {
            // Tridiagonal elimination with pivots up to ~6e4 against entries of order 1:
            // round-off well below 1e-9 of the values.
            assert!((got - want).abs() < 1e-9, "{c}: {got} vs {want}");
        }
    }
}
