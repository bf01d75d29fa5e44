//! Normal flow with area-weighted vertex normals (paper 000 §8.1, §8.3): each vertex moves
//! by the speed of its sheet along the sheet's area-weighted normal, so a sphere's vertices
//! stay on the sphere of radius r0 + s·t. Where sheets of several phase pairs meet (a triple
//! curve), the vertex takes the motion that keeps each sheet moving at its own speed, in the
//! least-squares sense.

use glam::DVec3;
use nalgebra::{Matrix3, Vector3};
use polyphase_grid::PhaseId;
use rayon::prelude::*;

use super::offset::NULL_SPACE;
use super::{interface_faces, normal_speed, PairSpeed};
use crate::front::connectivity::Connectivity;
use crate::front::least_squares::constrained_solution;

/// Velocity of every vertex (zero for unused vertices and those only on domain walls), with
/// every speed multiplied by `sign` (−1 for the reversed flow).
pub(super) fn velocities(c: &Connectivity, speeds: &[PairSpeed], sign: f64) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .into_par_iter()
        .map(|v| sign * vertex_velocity(c, speeds, v))
        .collect()
}

fn vertex_velocity(c: &Connectivity, speeds: &[PairSpeed], v: u32) -> DVec3 {
    // Per unordered pair: (pair, Σ area normal oriented into the pair's higher phase, Σ area).
    let mut sheets: Vec<([PhaseId; 2], DVec3, f64)> = Vec::new();
    for (labels, area_normal) in interface_faces(c, v) {
        let key = [labels[0].min(labels[1]), labels[0].max(labels[1])];
        let oriented = if labels[0] == key[1] {
            area_normal
        } else {
            -area_normal
        };
        let area = 0.5 * area_normal.length();
        match sheets.iter_mut().find(|e| e.0 == key) {
            Some(e) => {
                e.1 += oriented;
                e.2 += area;
            }
            None => sheets.push((key, oriented, area)),
        }
    }
    // Each sheet's normal and its speed along it (positive toward the higher phase).
    let sheet = |(key, normal, _): &([PhaseId; 2], DVec3, f64)| {
        (
            normal.normalize_or_zero(),
            normal_speed(speeds, [key[1], key[0]]),
        )
    };
    match &sheets[..] {
        [] => DVec3::ZERO,
        [one] => {
            let (n, s) = sheet(one);
            s * n
        }
        // Where sheets meet, the vertex takes the motion that best keeps every sheet moving at
        // its own speed, Σ Aₖ (d·nₖ − sₖ)² least, solved in the directions the sheets
        // constrain: at a triple curve that is the curve's own motion (a lens of two shrinking
        // spheres: the curve moves at s / sin of the sheets' half-angle), where the area-weighted
        // mean of the sheets' motions lagged it by half and more, a zero-speed sheet diluting it.
        _ => {
            let mut quadric = Matrix3::<f64>::zeros();
            let mut rhs = Vector3::<f64>::zeros();
            for e in &sheets {
                let (n, s) = sheet(e);
                let n = Vector3::new(n.x, n.y, n.z);
                quadric += e.2 * n * n.transpose();
                rhs += e.2 * s * n;
            }
            constrained_solution(quadric, rhs, NULL_SPACE)
        }
    }
}
