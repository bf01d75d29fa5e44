//! Normal flow by face offsetting (Jiao 2007, used by paper 000 §8.2 for the cyclic flow):
//! every face wants to move by its own offset along its normal; each vertex takes the
//! displacement that best satisfies its faces in the least-squares sense, solved only in the
//! directions the faces constrain (the eigenvectors of the normal quadric Σ wₜ nₜnₜᵀ with
//! significant eigenvalues). At a ridge or a triple curve two or three directions are
//! constrained and the corner moves exactly; on a smooth sheet only the normal one, so
//! vertices do not drift tangentially.

use glam::DVec3;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;

use super::{interface_faces, normal_speed, PairSpeed};
use crate::front::connectivity::Connectivity;

/// Eigenvalues below this fraction of the largest are the quadric's null space: two sheets
/// meeting at dihedral angle θ give the ratio tan²(θ/2), 0.03 at θ ≈ 20°, while the normals
/// of a smooth one-ring a tenth of the curvature radius across spread by under 0.01.
const NULL_SPACE: f64 = 0.03;

/// Velocity of every vertex (zero where no face constrains it).
pub(super) fn velocities(c: &Connectivity, speeds: &[PairSpeed]) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .into_par_iter()
        .map(|v| {
            let mut quadric = Matrix3::<f64>::zeros();
            let mut rhs = Vector3::<f64>::zeros();
            for (labels, area_normal) in interface_faces(c, v) {
                let area = 0.5 * area_normal.length();
                let n = area_normal.normalize_or_zero();
                let n = Vector3::new(n.x, n.y, n.z);
                quadric += area * n * n.transpose();
                rhs += area * normal_speed(speeds, labels) * n;
            }
            constrained_solution(quadric, rhs)
        })
        .collect()
}

/// The least-squares solution of `quadric · d = rhs` in the directions the quadric constrains
/// (eigenvalues above [`NULL_SPACE`] of the largest), zero along the others.
pub(super) fn constrained_solution(quadric: Matrix3<f64>, rhs: Vector3<f64>) -> DVec3 {
    let eigen = SymmetricEigen::new(quadric);
    let largest = eigen.eigenvalues.amax();
    if largest <= 0.0 {
        return DVec3::ZERO;
    }
    let mut d = Vector3::<f64>::zeros();
    for k in 0..3 {
        let lambda = eigen.eigenvalues[k];
        if lambda > NULL_SPACE * largest {
            let e = eigen.eigenvectors.column(k);
            d += e * (e.dot(&rhs) / lambda);
        }
    }
    DVec3::new(d.x, d.y, d.z)
}
