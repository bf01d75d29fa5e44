//! The flux each triangle sweeps, to second order in its size. A flat triangle whose corners
//! move with the velocity sweeps the flux of the velocity's *linear* interpolant across it
//! (the corner rule): where the velocity curves over a triangle, as at the rim of a liquid
//! sheet spreading on a floor, a divergence-free velocity still changes the enclosed volumes
//! (measured: `balls` at 64, the landed water ball lost 0.03–0.1 % per step by the corner
//! rule, 1.26 % by t = 1/3 s; 0.03 % with the midpoint flux). The edge-midpoint rule is exact
//! for quadratic velocities; moving each vertex by the normal part of its triangles'
//! difference between the two rules sweeps the midpoint rule's flux instead. No volume target
//! enters: this is the surface's motion discretised one order higher, not a correction toward
//! a volume.

use glam::DVec3;
use polyphase_grid::VelocityField;
use rayon::prelude::*;

use crate::mesh::LabeledMesh;

/// Extra displacement per vertex over a step of `dt` from `x0` to `x1` in `velocity` at
/// `t`: Σ_T A_T n_T (n_T · δu_T) / Σ_T A_T over the vertex's triangles, where δu_T is the
/// mean velocity at the edge midpoints less the mean at the corners, both read on the
/// triangle halfway between `x0` and `x1` at `t + dt / 2`.
pub(super) fn flux_displacements(
    mesh: &LabeledMesh,
    velocity: &dyn VelocityField,
    x0: &[DVec3],
    x1: &[DVec3],
    t: f64,
    dt: f64,
) -> Vec<DVec3> {
    let half = t + 0.5 * dt;
    let mid: Vec<DVec3> = x0.iter().zip(x1).map(|(a, b)| 0.5 * (*a + *b)).collect();
    let corner: Vec<DVec3> = mid
        .par_iter()
        .map(|&x| velocity.velocity(x, half))
        .collect();
    // Per triangle: A n (n · δu) and A.
    let per_triangle: Vec<(DVec3, f64)> = mesh
        .triangles
        .par_iter()
        .map(|&[a, b, c]| {
            let [pa, pb, pc] = [a, b, c].map(|v| mid[v as usize]);
            let area_normal = 0.5 * (pb - pa).cross(pc - pa);
            let area = area_normal.length();
            if area == 0.0 {
                return (DVec3::ZERO, 0.0);
            }
            let edges = velocity.velocity(0.5 * (pa + pb), half)
                + velocity.velocity(0.5 * (pb + pc), half)
                + velocity.velocity(0.5 * (pc + pa), half);
            let corners = corner[a as usize] + corner[b as usize] + corner[c as usize];
            let n = area_normal / area;
            (area_normal * n.dot(edges - corners) / 3.0, area)
        })
        .collect();
    let mut sum = vec![(DVec3::ZERO, 0.0); x0.len()];
    for (tri, &(flux, area)) in mesh.triangles.iter().zip(&per_triangle) {
        for &v in tri {
            let s = &mut sum[v as usize];
            s.0 += flux;
            s.1 += area;
        }
    }
    sum.into_iter()
        .map(|(flux, area)| match area > 0.0 {
            true => dt * flux / area,
            false => DVec3::ZERO,
        })
        .collect()
}
