//! MIC(0): modified incomplete Cholesky with zero fill-in of a [`Stencil7`] (Bridson, "Fluid
//! Simulation for Computer Graphics", §5.4; τ = 0.97, safety σ = 0.25). Periodic wrap couplings
//! are left out of the factor, which keeps it SPD (the diagonal keeps their weight).

use crate::layout::unidx;
use crate::linalg::pcg::Preconditioner;
use crate::linalg::stencil::Stencil7;

/// Share of the dropped fill-in moved back to the diagonal.
const TAU: f64 = 0.97;
/// Below σ·diag a pivot is deemed unsafe and replaced by the plain diagonal.
const SIGMA: f64 = 0.25;

/// The factor: inverse square roots of the modified pivots; the off-diagonals are the matrix's.
pub(crate) struct Mic0<'a> {
    a: &'a Stencil7,
    precon: Vec<f64>,
}

/// Coupling of cell `p` (index c) to its +d neighbour, 0 where that coupling wraps around.
#[inline]
fn off_nowrap(a: &Stencil7, p: [usize; 3], c: usize, d: usize) -> f64 {
    if p[d] + 1 < a.dims[d] {
        a.off[d][c]
    } else {
        0.0
    }
}

/// Strides of the linear index per axis.
fn strides(dims: [usize; 3]) -> [usize; 3] {
    [1, dims[0], dims[0] * dims[1]]
}

impl<'a> Mic0<'a> {
    /// Factors `a` (sequential: the recurrence runs in index order).
    pub fn new(a: &'a Stencil7) -> Self {
        let n = a.len();
        let st = strides(a.dims);
        let mut precon = vec![0.0; n];
        for c in 0..n {
            let diag = a.diag[c];
            if diag <= 0.0 {
                continue;
            }
            let p = unidx(a.dims, c);
            let mut e = diag;
            for d in 0..3 {
                if p[d] == 0 {
                    continue;
                }
                let l = c - st[d];
                let mut pl = p;
                pl[d] -= 1;
                let a_l = a.off[d][l];
                let m = precon[l];
                e -= (a_l * m) * (a_l * m);
                let others: f64 = (0..3)
                    .filter(|&d2| d2 != d)
                    .map(|d2| off_nowrap(a, pl, l, d2))
                    .sum();
                e -= TAU * a_l * others * m * m;
            }
            if e < SIGMA * diag {
                e = diag;
            }
            precon[c] = 1.0 / e.sqrt();
        }
        Self { a, precon }
    }

    /// Bytes held by the factor.
    pub fn memory_bytes(&self) -> usize {
        self.precon.len() * std::mem::size_of::<f64>()
    }
}

impl Preconditioner for Mic0<'_> {
    fn apply(&self, r: &[f64], z: &mut [f64]) {
        let a = self.a;
        let n = a.len();
        let st = strides(a.dims);
        let pc = &self.precon;
        // Forward solve L q = r (q stored in z).
        for c in 0..n {
            if pc[c] == 0.0 {
                z[c] = 0.0;
                continue;
            }
            let p = unidx(a.dims, c);
            let mut t = r[c];
            for d in 0..3 {
                if p[d] > 0 {
                    let l = c - st[d];
                    t -= a.off[d][l] * pc[l] * z[l];
                }
            }
            z[c] = t * pc[c];
        }
        // Backward solve Lᵀ z = q.
        for c in (0..n).rev() {
            if pc[c] == 0.0 {
                continue;
            }
            let p = unidx(a.dims, c);
            let mut t = z[c];
            for d in 0..3 {
                if p[d] + 1 < a.dims[d] {
                    let u = c + st[d];
                    t -= a.off[d][c] * pc[c] * z[u];
                }
            }
            z[c] = t * pc[c];
        }
    }
}
