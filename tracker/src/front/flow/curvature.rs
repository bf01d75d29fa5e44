//! Mean-curvature flow (paper 000 §8.4): the gradient flow of the total interface area with
//! the cotangent discretisation of Meyer et al. 2002 summed over every incident triangle, so
//! it holds unchanged at non-manifold curves (a triple curve feels the pull of its three
//! sheets). Domain walls (`OUTSIDE` faces) carry no tension.

use glam::DVec3;
use polyphase_grid::OUTSIDE;
use rayon::prelude::*;

use crate::front::connectivity::Connectivity;

/// Velocity of every vertex: −rate · ∇ₓA / Aᵥ, the area gradient over the vertex's
/// barycentric area Aᵥ (a third of its incident triangles' area). On a sphere of radius r
/// this is the mean-curvature normal 2/r pointing inward, so r² = r0² − 4·rate·t.
pub(super) fn velocities(c: &Connectivity, rate: f64) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .into_par_iter()
        .map(|v| {
            let x = c.position(v);
            let (mut gradient, mut area) = (DVec3::ZERO, 0.0);
            for &t in c.vertex_triangles(v) {
                if c.labels(t).contains(&OUTSIDE) {
                    continue;
                }
                let tri = c.triangle(t);
                let k = tri.iter().position(|&u| u == v).unwrap_or(0);
                let p = c.position(tri[(k + 1) % 3]);
                let q = c.position(tri[(k + 2) % 3]);
                let (g, a) = area_gradient(x, p, q);
                gradient += g;
                area += a;
            }
            if area > 0.0 {
                -rate * gradient / (area / 3.0)
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

/// Gradient of the area of triangle (x, p, q) with respect to x, and the area: the
/// cotangent form ½[cot∠q (x − p) + cot∠p (x − q)] (Meyer et al. 2002, Eq. 4 per triangle).
fn area_gradient(x: DVec3, p: DVec3, q: DVec3) -> (DVec3, f64) {
    let cross = (p - x).cross(q - x);
    let twice = cross.length();
    if twice <= 0.0 {
        return (DVec3::ZERO, 0.0);
    }
    let cot = |at: DVec3, a: DVec3, b: DVec3| (a - at).dot(b - at) / twice;
    let cot_q = cot(q, x, p);
    let cot_p = cot(p, x, q);
    (0.5 * (cot_q * (x - p) + cot_p * (x - q)), 0.5 * twice)
}
