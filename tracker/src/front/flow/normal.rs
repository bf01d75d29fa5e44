//! Normal flow with area-weighted vertex normals (paper 000 §8.1, §8.3): each vertex moves
//! by the speed of its sheet along the sheet's area-weighted normal, so a sphere's vertices
//! stay on the sphere of radius r0 + s·t. Where sheets of several phase pairs meet (a triple
//! curve), the vertex takes the area-weighted mean of their motions.

use glam::DVec3;
use polyphase_grid::PhaseId;
use rayon::prelude::*;

use super::{interface_faces, normal_speed, PairSpeed};
use crate::front::connectivity::Connectivity;

/// Velocity of every vertex (zero for unused vertices and those only on domain walls).
pub(super) fn velocities(c: &Connectivity, speeds: &[PairSpeed]) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .into_par_iter()
        .map(|v| vertex_velocity(c, speeds, v))
        .collect()
}

fn vertex_velocity(c: &Connectivity, speeds: &[PairSpeed], v: u32) -> DVec3 {
    // Per unordered pair: (pair, Σ speed × area normal, Σ area, |speed|).
    let mut sheets: Vec<([PhaseId; 2], DVec3, f64, f64)> = Vec::new();
    for (labels, area_normal) in interface_faces(c, v) {
        let s = normal_speed(speeds, labels);
        let key = [labels[0].min(labels[1]), labels[0].max(labels[1])];
        let area = 0.5 * area_normal.length();
        match sheets.iter_mut().find(|e| e.0 == key) {
            Some(e) => {
                e.1 += s * area_normal;
                e.2 += area;
            }
            None => sheets.push((key, s * area_normal, area, s.abs())),
        }
    }
    let total: f64 = sheets.iter().map(|e| e.2).sum();
    if total <= 0.0 {
        return DVec3::ZERO;
    }
    sheets
        .iter()
        .map(|(_, m, area, speed)| m.normalize_or_zero() * *speed * *area)
        .sum::<DVec3>()
        / total
}
