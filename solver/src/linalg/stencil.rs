//! Symmetric 7-point stencil matrices on a box of unknowns (pressure cells, or the faces of one
//! velocity component), with optional periodic wrap per axis. Stored matrix-free-style as a
//! diagonal plus one coupling per axis to the +axis neighbour: cache-friendly, and the form
//! MIC(0) and multigrid both want.

use crate::layout::idx;
use rayon::prelude::*;
use std::ops::{Add, AddAssign, Div, Mul, Sub, SubAssign};

/// Storage precision of a [`Stencil7`] and of the multigrid hierarchy on it: f64 where the
/// matrix is the operator itself (pressure), f32 where it only preconditions (viscosity), which
/// halves the memory and the bandwidth of every sweep.
pub(crate) trait Real:
    Copy
    + Send
    + Sync
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    const ZERO: Self;
    /// Nearest value to `v`.
    fn from_f64(v: f64) -> Self;
    /// Exact widening.
    fn to_f64(self) -> f64;
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

/// A symmetric matrix with entries only between axis neighbours.
#[derive(Clone, Debug)]
pub(crate) struct Stencil7<T = f64> {
    pub dims: [usize; 3],
    pub periodic: [bool; 3],
    /// Diagonal entries.
    pub diag: Vec<T>,
    /// `off[d][c]`: entry between c and its +d neighbour (wrapped when periodic; 0 at the end
    /// of a non-periodic axis). Non-positive for the M-matrices built here.
    pub off: [Vec<T>; 3],
}

impl<T: Real> Stencil7<T> {
    /// All-zero matrix.
    pub fn zeros(dims: [usize; 3], periodic: [bool; 3]) -> Self {
        let n = dims[0] * dims[1] * dims[2];
        Self {
            dims,
            periodic,
            diag: vec![T::ZERO; n],
            off: [vec![T::ZERO; n], vec![T::ZERO; n], vec![T::ZERO; n]],
        }
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.diag.len()
    }

    /// Bytes held by the matrix.
    pub fn memory_bytes(&self) -> usize {
        4 * self.len() * std::mem::size_of::<T>()
    }

    /// Index of the +d neighbour of `p`, None past a non-periodic end.
    #[inline]
    pub fn up(&self, p: [usize; 3], d: usize) -> Option<usize> {
        up_neighbour(self.dims, self.periodic, p, d)
    }

    /// Index of the −d neighbour of `p`, None past a non-periodic end.
    #[inline]
    pub fn down(&self, p: [usize; 3], d: usize) -> Option<usize> {
        let mut q = p;
        if p[d] > 0 {
            q[d] -= 1;
        } else if self.periodic[d] && self.dims[d] > 1 {
            q[d] = self.dims[d] - 1;
        } else {
            return None;
        }
        Some(idx(self.dims, q))
    }

    /// Off-diagonal part of A·x for x-row `row` (fixed j, k) into `acc`: whole rows at a time
    /// so the inner loops are straight strided sweeps.
    pub fn offdiag_row(&self, row: usize, x: &[T], acc: &mut [T]) {
        let nx = self.dims[0];
        let base = row * nx;
        let o0 = &self.off[0][base..base + nx];
        let xr = &x[base..base + nx];
        for i in 0..nx {
            let mut s = T::ZERO;
            if i + 1 < nx {
                s += o0[i] * xr[i + 1];
            }
            if i > 0 {
                s += o0[i - 1] * xr[i - 1];
            }
            acc[i] = s;
        }
        if self.periodic[0] && nx > 1 {
            acc[nx - 1] += o0[nx - 1] * xr[0];
            acc[0] += o0[nx - 1] * xr[nx - 1];
        }
        self.cross_row(row, x, acc);
    }

    /// Adds the y and z couplings of x-row `row` (fixed j, k) to `acc`: the part of A·x that
    /// comes from other rows.
    pub fn cross_row(&self, row: usize, x: &[T], acc: &mut [T]) {
        let nx = self.dims[0];
        self.cross_row_from(row, |r| &x[r * nx..(r + 1) * nx], acc);
    }

    /// [`Stencil7::cross_row`] with the other rows' values from `rows` (row index to its
    /// values), so that a sweep may read rows of one colour while it writes the others.
    #[inline]
    pub fn cross_row_from<'x>(&self, row: usize, rows: impl Fn(usize) -> &'x [T], acc: &mut [T]) {
        let [nx, ny, nz] = self.dims;
        let (j, k) = (row % ny, row / ny);
        let base = row * nx;
        let neighbour_rows = [
            (
                1,
                self.step_row(j, ny, self.periodic[1], true)
                    .map(|jj| jj + ny * k),
            ),
            (
                1,
                self.step_row(j, ny, self.periodic[1], false)
                    .map(|jj| jj + ny * k),
            ),
            (
                2,
                self.step_row(k, nz, self.periodic[2], true)
                    .map(|kk| j + ny * kk),
            ),
            (
                2,
                self.step_row(k, nz, self.periodic[2], false)
                    .map(|kk| j + ny * kk),
            ),
        ];
        for (n, (d, other)) in neighbour_rows.into_iter().enumerate() {
            let Some(other) = other else { continue };
            let ob = other * nx;
            let xo = rows(other);
            // Upward couplings are stored on this row, downward ones on the other row.
            let coupling = if n % 2 == 0 {
                &self.off[d][base..base + nx]
            } else {
                &self.off[d][ob..ob + nx]
            };
            for ((a, &c), &xv) in acc.iter_mut().zip(coupling).zip(xo) {
                *a += c * xv;
            }
        }
    }

    /// Neighbouring index of `j` among `n` (up or down), wrapping when periodic.
    #[inline]
    fn step_row(&self, j: usize, n: usize, periodic: bool, up: bool) -> Option<usize> {
        if up {
            if j + 1 < n {
                Some(j + 1)
            } else if periodic && n > 1 {
                Some(0)
            } else {
                None
            }
        } else if j > 0 {
            Some(j - 1)
        } else if periodic && n > 1 {
            Some(n - 1)
        } else {
            None
        }
    }

    /// y = A·x, parallel over x-rows.
    pub fn apply(&self, x: &[T], y: &mut [T]) {
        let nx = self.dims[0];
        y.par_chunks_mut(nx).enumerate().for_each(|(row, yr)| {
            self.offdiag_row(row, x, yr);
            let base = row * nx;
            for (i, yi) in yr.iter_mut().enumerate() {
                *yi += self.diag[base + i] * x[base + i];
            }
        });
    }
}

/// Index of the +d neighbour of `p` in a box of `dims`, None past a non-periodic end.
#[inline]
pub(crate) fn up_neighbour(
    dims: [usize; 3],
    periodic: [bool; 3],
    p: [usize; 3],
    d: usize,
) -> Option<usize> {
    let mut q = p;
    if p[d] + 1 < dims[d] {
        q[d] += 1;
    } else if periodic[d] && dims[d] > 1 {
        q[d] = 0;
    } else {
        return None;
    }
    Some(idx(dims, q))
}

/// The axes in the order [`rotate`] numbers them: `a`, then the other two in natural order,
/// so consecutive rows stay neighbours in memory and renumbering runs through the cache.
pub(crate) fn first_axes(a: usize) -> [usize; 3] {
    match a {
        0 => [0, 1, 2],
        1 => [1, 0, 2],
        _ => [2, 0, 1],
    }
}

/// Width of the bands [`transpose`] moves at a time: each source row gives a band its
/// consecutive values and each of the band's destination rows fills in order, so both sides
/// stay in the cache however far apart consecutive rows lie.
const TILE: usize = 16;

/// `dst` = `src` (values on a box of `dims`) renumbered with axis `a` first: p moves to
/// (p[axes[0]], p[axes[1]], p[axes[2]]), axes = [`first_axes`]. Line smoothing runs along the
/// contiguous first axis, so this puts any axis there. Values convert between the two
/// precisions on the way.
///
/// Each renumbering is a transpose of stacked matrices: along y, the x–y plane of each z
/// layer (rows j, columns i); along z, the whole box as rows k of x–y planes.
pub(crate) fn rotate<S: Real, D: Real>(dims: [usize; 3], a: usize, src: &[S], dst: &mut [D]) {
    match a {
        0 => convert(src, dst),
        1 => transpose(src, dst, dims[1], dims[0]),
        _ => transpose(src, dst, dims[2], dims[0] * dims[1]),
    }
}

/// Inverse of [`rotate`]: `dst` (on a box of `dims`) from `src` numbered with axis `a` first.
pub(crate) fn unrotate<S: Real, D: Real>(dims: [usize; 3], a: usize, src: &[S], dst: &mut [D]) {
    match a {
        0 => convert(src, dst),
        1 => transpose(src, dst, dims[0], dims[1]),
        _ => transpose(src, dst, dims[0] * dims[1], dims[2]),
    }
}

/// `dst` = `src` converted.
fn convert<S: Real, D: Real>(src: &[S], dst: &mut [D]) {
    dst.par_chunks_mut(1 << 14)
        .zip(src.par_chunks(1 << 14))
        .for_each(|(d, s)| {
            for (di, si) in d.iter_mut().zip(s) {
                *di = D::from_f64(si.to_f64());
            }
        });
}

/// Transposes each `rows` × `cols` matrix stacked in `src` (row-major, entry (r, c) at
/// r·cols + c) into `dst` (entry (r, c) at c·rows + r), a band of [`TILE`] columns at a
/// time, converting values.
fn transpose<S: Real, D: Real>(src: &[S], dst: &mut [D], rows: usize, cols: usize) {
    let size = rows * cols;
    if size == 0 {
        return;
    }
    // One task per band of TILE destination rows (source columns) of one matrix.
    let bands = cols.div_ceil(TILE);
    let band_len = |b: usize| TILE.min(cols - b * TILE) * rows;
    let mut chunks: Vec<(usize, usize, &mut [D])> = Vec::with_capacity(dst.len() / size * bands);
    let mut rest = dst;
    for m in 0..src.len() / size {
        for b in 0..bands {
            let (head, tail) = rest.split_at_mut(band_len(b));
            chunks.push((m, b, head));
            rest = tail;
        }
    }
    chunks.into_par_iter().for_each(|(m, b, out)| {
        let s = &src[m * size..(m + 1) * size];
        let c0 = b * TILE;
        let width = TILE.min(cols - c0);
        for r in 0..rows {
            let line = &s[r * cols + c0..r * cols + c0 + width];
            for (dc, v) in line.iter().enumerate() {
                out[dc * rows + r] = D::from_f64(v.to_f64());
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×3×5 stencil, periodic along y, with distinct entries everywhere.
    fn sample() -> Stencil7 {
        let mut s = Stencil7::zeros([4, 3, 5], [false, true, false]);
        for c in 0..s.len() {
            s.diag[c] = 10.0 + c as f64;
            for d in 0..3 {
                s.off[d][c] = -1.0 - ((c * 7 + d * 3) % 11) as f64;
            }
        }
        s
    }

    #[test]
    fn rotation_moves_every_value_to_its_renumbered_place_across_tiles() {
        // Sides of one full band plus a partial one (and several layers), so whole bands,
        // a narrower last band and stacked matrices are all exercised.
        let dims = [TILE + 5, 2 * TILE + 3, 7];
        let n = dims[0] * dims[1] * dims[2];
        let x: Vec<f64> = (0..n).map(|c| c as f64).collect();
        for a in 0..3 {
            let axes = first_axes(a);
            let rd = axes.map(|d| dims[d]);
            let mut xr = vec![0.0_f32; n];
            rotate(dims, a, &x, &mut xr);
            for (c, &v) in x.iter().enumerate() {
                let p = crate::layout::unidx(dims, c);
                // Indices below 2²⁴ are exact in f32.
                assert_eq!(xr[idx(rd, axes.map(|d| p[d]))], v as f32, "axis {a}, {p:?}");
            }
            let mut back = vec![0.0; n];
            unrotate(dims, a, &xr, &mut back);
            assert_eq!(back, x, "axis {a}");
        }
    }

    #[test]
    fn rotation_renumbers_the_matrix_and_vectors_consistently() {
        let s = sample();
        let x: Vec<f64> = (0..s.len()).map(|c| ((c * 13) % 17) as f64 - 8.0).collect();
        let mut ax = vec![0.0; s.len()];
        s.apply(&x, &mut ax);
        for a in 0..3 {
            let axes = first_axes(a);
            let mut r = Stencil7::zeros(axes.map(|d| s.dims[d]), axes.map(|d| s.periodic[d]));
            rotate(s.dims, a, &s.diag, &mut r.diag);
            for (out, &d) in r.off.iter_mut().zip(&axes) {
                rotate(s.dims, a, &s.off[d], out);
            }
            let (mut xr, mut axr, mut rax) = (vec![0.0; s.len()], vec![0.0; s.len()], vec![]);
            rotate(s.dims, a, &x, &mut xr);
            r.apply(&xr, &mut axr);
            rax.resize(s.len(), 0.0);
            rotate(s.dims, a, &ax, &mut rax);
            // The same products summed in another order: equal up to round-off of integers,
            // which is exact here.
            assert_eq!(axr, rax, "axis {a}");
            let mut back = vec![0.0; s.len()];
            unrotate(s.dims, a, &xr, &mut back);
            assert_eq!(back, x, "axis {a}");
        }
    }
}
