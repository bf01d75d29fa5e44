//! Least squares restricted to the directions a quadric constrains, shared by the flows that
//! fit a vertex motion to its faces and by remeshing operations that restore volumes.

use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// The least-squares solution of `quadric · d = rhs` in the directions the quadric constrains
/// (eigenvalues above `null_space` times the largest), zero along the others.
pub(crate) fn constrained_solution(
    quadric: Matrix3<f64>,
    rhs: Vector3<f64>,
    null_space: f64,
) -> DVec3 {
    let eigen = SymmetricEigen::new(quadric);
    let largest = eigen.eigenvalues.amax();
    if largest <= 0.0 {
        return DVec3::ZERO;
    }
    let mut d = Vector3::<f64>::zeros();
    for k in 0..3 {
        let lambda = eigen.eigenvalues[k];
        if lambda > null_space * largest {
            let e = eigen.eigenvectors.column(k);
            d += e * (e.dot(&rhs) / lambda);
        }
    }
    DVec3::new(d.x, d.y, d.z)
}
