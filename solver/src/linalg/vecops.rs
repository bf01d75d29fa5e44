//! Vector kernels with fixed-order reductions: partial sums over fixed-size chunks, combined
//! in chunk order, so results are bit-identical for any number of rayon threads.

use rayon::prelude::*;

/// Chunk length of every reduction; fixed so the summation tree never depends on threads.
const CHUNK: usize = 4096;

/// Dot product, deterministic.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(x, y)| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// Sum of entries, deterministic.
pub(crate) fn sum(a: &[f64]) -> f64 {
    let partial: Vec<f64> = a.par_chunks(CHUNK).map(|x| x.iter().sum::<f64>()).collect();
    partial.iter().sum()
}

/// Maximum absolute entry (order-independent, so exact with any threads).
pub(crate) fn max_abs(a: &[f64]) -> f64 {
    a.par_iter().map(|v| v.abs()).reduce(|| 0.0, f64::max)
}

/// The CG step x += alpha·p, r −= alpha·q in one pass, returning the new r·r (summed in the
/// same fixed chunks as [`dot`], so deterministic).
pub(crate) fn step_and_norm(alpha: f64, p: &[f64], q: &[f64], x: &mut [f64], r: &mut [f64]) -> f64 {
    let partial: Vec<f64> = x
        .par_chunks_mut(CHUNK)
        .zip(r.par_chunks_mut(CHUNK))
        .zip(p.par_chunks(CHUNK).zip(q.par_chunks(CHUNK)))
        .map(|((xc, rc), (pc, qc))| {
            let mut s = 0.0;
            for (((xi, ri), pi), qi) in xc.iter_mut().zip(rc.iter_mut()).zip(pc).zip(qc) {
                *xi += alpha * pi;
                *ri -= alpha * qi;
                s += *ri * *ri;
            }
            s
        })
        .collect();
    partial.iter().sum()
}

/// p = z + beta·p.
pub(crate) fn xpby(z: &[f64], beta: f64, p: &mut [f64]) {
    p.par_iter_mut()
        .zip(z)
        .for_each(|(pi, zi)| *pi = zi + beta * *pi);
}

/// Index of the first non-finite entry.
pub(crate) fn first_non_finite(a: &[f64]) -> Option<usize> {
    a.par_iter().position_first(|v| !v.is_finite())
}
