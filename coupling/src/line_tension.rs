//! Surface tension's pull on triple curves, where three phases meet: each interface pulls
//! the curve into itself with its own σ, along its conormal (across the curve, in the
//! direction the interface leaves it). The sum Σ σ_i ν_i vanishes exactly where the angles
//! between the interfaces are Neumann's, so this force turns a junction towards them and
//! leaves one at rest there; the Laplace jumps alone hold each interface but leave its angles
//! free (every lens of circular arcs whose jumps agree would be at rest).

use glam::DVec3;
use polyphase_tracker::{LabeledMesh, PhaseId};

use crate::junction::junction_edges;

/// The force (N) on each edge of the mesh's triple curves, at the edge's midpoint: the edge's
/// length times Σ σ(pair)·ν over the interfaces that meet there, ν fitted over `reach` of
/// each ([`junction_edges`]).
pub fn triple_curve_forces(
    mesh: &LabeledMesh,
    reach: f64,
    sigma: impl Fn(PhaseId, PhaseId) -> f64,
) -> Vec<(DVec3, DVec3)> {
    junction_edges(mesh, reach)
        .into_iter()
        .map(|edge| {
            let pull: DVec3 = edge
                .branches
                .iter()
                .map(|&((a, b), nu)| sigma(a, b) * nu)
                .sum();
            (edge.point, edge.length * pull)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three half-planes of phases 0|1, 1|2 and 0|2 meeting along the z axis (z from 0 to 1),
    /// each a strip of triangles leaving the axis in direction `dirs[k]` (in the xy plane),
    /// vertices every 0.1 along it out to 1.
    fn junction(dirs: [f64; 3]) -> LabeledMesh {
        let mut mesh = LabeledMesh::default();
        mesh.vertices.push(DVec3::ZERO);
        mesh.vertices.push(DVec3::Z);
        let pairs = [[0, 1], [1, 2], [2, 0]];
        for (k, angle) in dirs.into_iter().enumerate() {
            let out = DVec3::new(angle.cos(), angle.sin(), 0.0);
            let (mut lo, mut hi) = (0u32, 1u32);
            for i in 1..=10 {
                let v = mesh.vertices.len() as u32;
                mesh.vertices.push(0.1 * i as f64 * out);
                mesh.vertices.push(0.1 * i as f64 * out + DVec3::Z);
                mesh.triangles.push([lo, v, hi]);
                mesh.triangles.push([hi, v, v + 1]);
                mesh.labels.push(pairs[k]);
                mesh.labels.push(pairs[k]);
                (lo, hi) = (v, v + 1);
            }
        }
        mesh
    }

    #[test]
    fn equal_tensions_at_120_degrees_balance() {
        let third = std::f64::consts::TAU / 3.0;
        let mesh = junction([0.0, third, 2.0 * third]);
        let forces = triple_curve_forces(&mesh, 1.0, |_, _| 0.07);
        // The one shared edge (the axis) is the only triple edge.
        assert_eq!(forces.len(), 1);
        let (at, f) = forces[0];
        assert_eq!(at, 0.5 * DVec3::Z);
        // The three unit conormals of a symmetric junction sum to zero (to rounding).
        assert!(f.length() < 1e-12, "{f}");
    }

    #[test]
    fn an_unbalanced_junction_is_pulled_towards_the_strongest_interface() {
        // Interfaces at 0°, 90° and 180° with σ = 1, 2, 1 on pairs 0|1, 1|2, 0|2: the x pulls
        // cancel and the 1|2 interface (along +y) pulls with 2 N/m over the unit edge.
        let mesh = junction([0.0, std::f64::consts::FRAC_PI_2, std::f64::consts::PI]);
        let sigma = |a: PhaseId, b: PhaseId| if (a, b) == (1, 2) { 2.0 } else { 1.0 };
        let forces = triple_curve_forces(&mesh, 1.0, sigma);
        assert_eq!(forces.len(), 1);
        let f = forces[0].1;
        assert!((f - DVec3::new(0.0, 2.0, 0.0)).length() < 1e-12, "{f}");
    }
}
