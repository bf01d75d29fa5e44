//! Normal flow by face offsetting (Jiao 2007, used by paper 000 §8.2 for the cyclic flow):
//! every face wants to move by its own offset along its normal; each vertex takes the
//! displacement that best satisfies its faces in the least-squares sense, solved only in the
//! directions the faces constrain (the eigenvectors of the normal quadric Σ wₜ nₜnₜᵀ with
//! significant eigenvalues). At a ridge or a triple curve two or three directions are
//! constrained and the corner moves exactly; on a smooth sheet only the normal one, so
//! vertices do not drift tangentially.

use glam::DVec3;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;

use super::{interface_faces, normal_speed, PairSpeed};
use crate::front::connectivity::Connectivity;
use crate::front::least_squares::constrained_solution;

/// Eigenvalues below this fraction of the largest are the quadric's null space: two sheets
/// meeting at dihedral angle θ give the ratio tan²(θ/2), 0.03 at θ ≈ 20°, while the normals
/// of a smooth one-ring a tenth of the curvature radius across spread by under 0.01.
pub(super) const NULL_SPACE: f64 = 0.03;

/// Velocity of every vertex (zero where no face constrains it), every speed multiplied by
/// `sign` (−1 for the reversed flow).
pub(super) fn velocities(c: &Connectivity, speeds: &[PairSpeed], sign: f64) -> Vec<DVec3> {
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
                rhs += area * sign * normal_speed(speeds, labels) * n;
            }
            constrained_solution(quadric, rhs, NULL_SPACE)
        })
        .collect()
}
