//! Preconditioned conjugate gradients for SPD (or consistent positive semi-definite) systems,
//! with deterministic reductions, iteration/residual reporting and typed failure.

use crate::config::LinearSolverSettings;
use crate::error::SolverError;
use crate::linalg::vecops::{dot, first_non_finite, step_and_norm, xpby};
use rayon::prelude::*;

/// A symmetric linear operator y = A·x.
pub(crate) trait LinearOperator: Sync {
    /// Overwrites `y` with A·x.
    fn apply(&self, x: &[f64], y: &mut [f64]);
}

/// An SPD approximation z = M⁻¹·r.
pub(crate) trait Preconditioner: Sync {
    /// Overwrites `z` with M⁻¹·r.
    fn apply(&self, r: &[f64], z: &mut [f64]);
}

/// Outcome of a converged linear solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// CG iterations performed.
    pub iterations: usize,
    /// Final ‖b − A·x‖₂ / ‖b‖₂ (0 when b = 0).
    pub residual: f64,
}

/// Solves A·x = b from the initial guess in `x`; `b` becomes the residual vector, so CG holds
/// four vectors (x, r, p, q), the preconditioned residual z sharing q's storage: q = A·p is dead
/// from the residual update until the next product.
pub(crate) fn pcg(
    a: &dyn LinearOperator,
    m: &dyn Preconditioner,
    b: Vec<f64>,
    x: &mut [f64],
    settings: &LinearSolverSettings,
    system: &'static str,
) -> Result<SolveStats, SolverError> {
    if let Some(index) = first_non_finite(&b) {
        return Err(SolverError::NonFinite {
            what: system,
            index,
        });
    }
    let n = b.len();
    let bnorm = dot(&b, &b).sqrt();
    if bnorm == 0.0 {
        x.par_iter_mut().for_each(|v| *v = 0.0);
        return Ok(SolveStats::default());
    }
    let mut q = vec![0.0; n];
    a.apply(x, &mut q);
    let mut r = b;
    r.par_iter_mut().zip(&q).for_each(|(ri, qi)| *ri -= qi);
    let mut res = dot(&r, &r).sqrt() / bnorm;
    if res <= settings.tolerance {
        return Ok(SolveStats {
            iterations: 0,
            residual: res,
        });
    }
    m.apply(&r, &mut q);
    let mut p = q.clone();
    let mut rz = dot(&r, &q);
    for it in 1..=settings.max_iterations {
        a.apply(&p, &mut q);
        let pq = dot(&p, &q);
        if !pq.is_finite() || !rz.is_finite() {
            return Err(SolverError::NonFinite {
                what: system,
                index: 0,
            });
        }
        if pq <= 0.0 {
            // Breakdown: the operator is not positive definite on the search direction.
            return Err(SolverError::NotConverged {
                system,
                iterations: it,
                residual: res,
                tolerance: settings.tolerance,
            });
        }
        let alpha = rz / pq;
        res = step_and_norm(alpha, &p, &q, x, &mut r).sqrt() / bnorm;
        if !res.is_finite() {
            return Err(SolverError::NonFinite {
                what: system,
                index: 0,
            });
        }
        if res <= settings.tolerance {
            return Ok(SolveStats {
                iterations: it,
                residual: res,
            });
        }
        m.apply(&r, &mut q);
        let rz_new = dot(&r, &q);
        xpby(&q, rz_new / rz, &mut p);
        rz = rz_new;
    }
    Err(SolverError::NotConverged {
        system,
        iterations: settings.max_iterations,
        residual: res,
        tolerance: settings.tolerance,
    })
}

impl LinearOperator for crate::linalg::stencil::Stencil7 {
    fn apply(&self, x: &[f64], y: &mut [f64]) {
        crate::linalg::stencil::Stencil7::apply(self, x, y);
    }
}
