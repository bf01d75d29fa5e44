//! Forces concentrated at points of the fluid (N), such as surface tension's pull along a
//! triple curve, where three interfaces meet (ARCHITECTURE.md "Surface tension"): pressure
//! jumps hold each interface, but only a force on the curve itself turns the junction towards
//! the angles at which the three tensions balance (Neumann's triangle).
//!
//! Each force is spread over the faces of each component around its point with trilinear
//! weights w, and gives those faces one velocity change, in proportion to w, that carries
//! exactly its impulse: Δu_f = dt·F·w_f / Σ_g w_g ρ_g h³. A face of light air next to the
//! curve thus moves with the liquids around it instead of taking the whole impulse alone.

use crate::layout::{idx, Layout};
use crate::mac::MacGrid;
use glam::DVec3;

/// Point forces for one step: (point, force in N).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointForces {
    pub(crate) forces: Vec<(DVec3, DVec3)>,
}

impl PointForces {
    /// The forces `(point, force)`; non-finite and zero ones are left out.
    pub fn new(forces: impl IntoIterator<Item = (DVec3, DVec3)>) -> PointForces {
        PointForces {
            forces: forces
                .into_iter()
                .filter(|(x, f)| x.is_finite() && f.is_finite() && *f != DVec3::ZERO)
                .collect(),
        }
    }

    /// Applies the forces' impulses over `dt` to `vel`: open faces only (`open` > 0), with the
    /// face densities `rho`. In list order, so any thread count gives the same velocities.
    pub(crate) fn apply(
        &self,
        vel: &mut MacGrid,
        open: &[Vec<f64>; 3],
        rho: &[Vec<f64>; 3],
        dt: f64,
    ) {
        let (origin, h, layout) = (vel.spec.origin, vel.spec.h, vel.layout);
        for &(x, f) in &self.forces {
            for a in 0..3 {
                if f[a] == 0.0 {
                    continue;
                }
                let faces = stencil(&layout, a, (x - origin) / h);
                let mass: f64 = faces
                    .iter()
                    .filter(|&&(i, _)| open[a][i] > 0.0)
                    .map(|&(i, w)| w * rho[a][i] * h.powi(3))
                    .sum();
                if mass <= 0.0 {
                    continue;
                }
                for &(i, w) in &faces {
                    if open[a][i] > 0.0 {
                        vel.comps[a][i] += dt * f[a] * w / mass;
                    }
                }
            }
        }
    }
}

/// The faces of component `a` around the point `g` (in cells from the origin) with their
/// trilinear weights; along an axis with a single face layer (a slab's z), that layer alone.
fn stencil(layout: &Layout, a: usize, g: DVec3) -> Vec<(usize, f64)> {
    let dims = layout.face_dims(a);
    // Per axis, up to two (index, weight) pairs.
    let per_axis: [Vec<(usize, f64)>; 3] = [0, 1, 2].map(|d| {
        let n = dims[d];
        // Faces of component a sit at whole cells along a, at cell centres across it.
        let s = if d == a { g[d] } else { g[d] - 0.5 };
        if n == 1 {
            return vec![(0, 1.0)];
        }
        if layout.periodic[d] {
            let lo = s.floor();
            let t = s - lo;
            let i = (lo as i64).rem_euclid(n as i64) as usize;
            vec![(i, 1.0 - t), ((i + 1) % n, t)]
        } else {
            let s = s.clamp(0.0, (n - 1) as f64);
            let lo = s.floor().min((n - 2) as f64);
            let t = s - lo;
            let i = lo as usize;
            vec![(i, 1.0 - t), (i + 1, t)]
        }
    });
    let mut out = Vec::with_capacity(8);
    for &(k, wk) in &per_axis[2] {
        for &(j, wj) in &per_axis[1] {
            for &(i, wi) in &per_axis[0] {
                let w = wi * wj * wk;
                if w > 0.0 {
                    out.push((idx(dims, [i, j, k]), w));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Interpolation;
    use crate::layout::unidx;
    use polyphase_grid::GridSpec;

    /// Zero velocities on `n` cells of size `h`, every face open, density 1000 below y = 0.5
    /// and 1 above (a 1000:1 interface through the force's stencil).
    fn setup(n: [usize; 3], h: f64) -> (MacGrid, [Vec<f64>; 3], [Vec<f64>; 3]) {
        let spec = GridSpec {
            origin: DVec3::ZERO,
            h,
            dims: n,
        };
        let layout = Layout {
            n,
            periodic: [false; 3],
        };
        let vel = MacGrid::zeros(spec, layout, Interpolation::Trilinear);
        let open = [0, 1, 2].map(|a| vec![1.0; vel.comps[a].len()]);
        let rho = [0, 1, 2].map(|a| {
            let dims = layout.face_dims(a);
            (0..vel.comps[a].len())
                .map(|f| {
                    if vel.face_position(a, unidx(dims, f)).y < 0.5 {
                        1000.0
                    } else {
                        1.0
                    }
                })
                .collect()
        });
        (vel, open, rho)
    }

    /// Σ ρ h³ u over every face of each component: the momentum the forces gave.
    fn momentum(vel: &MacGrid, rho: &[Vec<f64>; 3]) -> DVec3 {
        let h3 = vel.spec.h.powi(3);
        DVec3::from_array([0, 1, 2].map(|a| {
            vel.comps[a]
                .iter()
                .zip(&rho[a])
                .map(|(u, r)| u * r * h3)
                .sum()
        }))
    }

    #[test]
    fn each_force_gives_exactly_its_impulse_as_one_velocity_change() {
        let (h, dt) = (0.1, 0.01);
        let at = DVec3::new(0.43, 0.51, 0.05);
        for n in [[10, 10, 10], [10, 10, 1]] {
            let (mut vel, open, rho) = setup(n, h);
            let f = DVec3::new(0.3, -0.2, if n[2] == 1 { 0.0 } else { 0.1 });
            PointForces::new([(at, f)]).apply(&mut vel, &open, &rho, dt);
            // Impulse conservation, to rounding.
            let p = momentum(&vel, &rho);
            assert!((p - dt * f).length() < 1e-12 * f.length(), "{n:?}: {p}");
            // Light and heavy faces of the stencil take one velocity change, scaled by their
            // weights only: u / w is the same on all of them.
            let ratios: Vec<f64> = stencil(&vel.layout, 0, at / h)
                .into_iter()
                .map(|(i, w)| vel.comps[0][i] / w)
                .collect();
            assert!(ratios.len() >= 4, "{ratios:?}");
            for r in &ratios {
                assert!(
                    (r - ratios[0]).abs() < 1e-12 * ratios[0].abs(),
                    "{ratios:?}"
                );
            }
        }
    }
}
