//! Analytic velocity fields for passive advection tests.

use std::f64::consts::PI;

use glam::DVec3;
use polyphase_grid::VelocityField;

/// A resolved analytic field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnalyticVelocity {
    Still,
    /// Rigid rotation about the axis through `center` parallel to +z.
    Rotation {
        center: DVec3,
        omega: f64,
    },
    /// Enright et al. 2002 three-dimensional deformation, period T.
    Enright {
        period: f64,
    },
    /// Single vortex on the unit square (paper 004 Eq. 2), period T, no z component.
    /// The extracted text of Eq. (2) reads cos(2π x₁) / cos(2π x₀) in the last factors; that
    /// field is not divergence-free (∂v₀/∂x₀ + ∂v₁/∂x₁ = π cos(πt/T)(sin 2πx₁ cos 2πx₀ −
    /// sin 2πx₀ cos 2πx₁) ≠ 0), contradicting the volume conservation of Fig. 11. We use the
    /// standard divergence-free single vortex with sin(2π ·) factors, which the garbling fits.
    Vortex {
        period: f64,
    },
}

impl AnalyticVelocity {
    /// An upper bound on |v| over the box `lo..hi` and all times, for time-step control.
    pub fn max_speed(&self, lo: DVec3, hi: DVec3) -> f64 {
        match *self {
            AnalyticVelocity::Still => 0.0,
            AnalyticVelocity::Rotation { center, omega } => {
                let dx = (lo.x - center.x).abs().max((hi.x - center.x).abs());
                let dy = (lo.y - center.y).abs().max((hi.y - center.y).abs());
                omega.abs() * dx.hypot(dy)
            }
            // Component bounds 2, 1, 1.
            AnalyticVelocity::Enright { .. } => 6f64.sqrt(),
            // Component bounds 1, 1.
            AnalyticVelocity::Vortex { .. } => 2f64.sqrt(),
        }
    }
}

impl VelocityField for AnalyticVelocity {
    fn velocity(&self, x: DVec3, t: f64) -> DVec3 {
        match *self {
            AnalyticVelocity::Still => DVec3::ZERO,
            AnalyticVelocity::Rotation { center, omega } => {
                let r = x - center;
                DVec3::new(-omega * r.y, omega * r.x, 0.0)
            }
            AnalyticVelocity::Enright { period } => {
                // sin 2πx = 2 sin πx cos πx: three sin_cos instead of six sines (the sines were
                // 12 % of `enright` 64³'s CPU time under perf).
                let c = (PI * t / period).cos();
                let [(sx, cx), (sy, cy), (sz, cz)] = [x.x, x.y, x.z].map(|v| (PI * v).sin_cos());
                let (s2x, s2y, s2z) = (2.0 * sx * cx, 2.0 * sy * cy, 2.0 * sz * cz);
                DVec3::new(
                    2.0 * sx * sx * s2y * s2z,
                    -s2x * sy * sy * s2z,
                    -s2x * s2y * sz * sz,
                ) * c
            }
            AnalyticVelocity::Vortex { period } => {
                let c = (PI * t / period).cos();
                let (sx, sy) = ((PI * x.x).sin(), (PI * x.y).sin());
                DVec3::new(
                    -sx * sx * (2.0 * PI * x.y).sin(),
                    sy * sy * (2.0 * PI * x.x).sin(),
                    0.0,
                ) * c
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central-difference divergence; the fields are smooth, so O(ε²) ≈ 1e-8 truncation.
    fn divergence(f: &AnalyticVelocity, x: DVec3, t: f64) -> f64 {
        let e = 1e-4;
        let d = |a: DVec3| (f.velocity(x + a * e, t) - f.velocity(x - a * e, t)) / (2.0 * e);
        d(DVec3::X).x + d(DVec3::Y).y + d(DVec3::Z).z
    }

    /// 200 points spread over the unit cube (golden-ratio-like strides), each with a time in
    /// [0, 0.3).
    fn samples() -> impl Iterator<Item = (DVec3, f64)> {
        (0..200).map(|i| {
            let s = i as f64;
            let x = DVec3::new(
                (s * 0.618).fract(),
                (s * 0.414).fract(),
                (s * 0.732).fract(),
            );
            (x, 0.3 * s / 200.0)
        })
    }

    #[test]
    fn fields_are_divergence_free_and_bounded() {
        let fields = [
            AnalyticVelocity::Rotation {
                center: DVec3::new(0.5, 0.5, 0.0),
                omega: 2.0 * PI,
            },
            AnalyticVelocity::Enright { period: 3.0 },
            AnalyticVelocity::Vortex { period: 4.0 },
        ];
        for f in &fields {
            let bound = f.max_speed(DVec3::ZERO, DVec3::ONE);
            for (x, t) in samples() {
                // Truncation of the central difference is ~1e-7 for these O(10) derivatives.
                assert!(divergence(f, x, t).abs() < 1e-6, "{f:?} at {x}");
                assert!(f.velocity(x, 0.0).length() <= bound + 1e-12);
            }
        }
    }

    #[test]
    fn enright_field_is_enright_et_al_formula() {
        let f = AnalyticVelocity::Enright { period: 3.0 };
        for (x, t) in samples() {
            let sin = |k: f64, v: f64| (k * PI * v).sin();
            let u = DVec3::new(
                2.0 * sin(1.0, x.x).powi(2) * sin(2.0, x.y) * sin(2.0, x.z),
                -sin(2.0, x.x) * sin(1.0, x.y).powi(2) * sin(2.0, x.z),
                -sin(2.0, x.x) * sin(2.0, x.y) * sin(1.0, x.z).powi(2),
            ) * (PI * t / 3.0).cos();
            // Products of a few sines of magnitude ≤ 2: the two evaluations differ by rounding.
            assert!((f.velocity(x, t) - u).length() < 1e-14, "{x}");
        }
    }

    #[test]
    fn periodic_fields_reverse_at_half_period() {
        let f = AnalyticVelocity::Enright { period: 3.0 };
        let x = DVec3::new(0.3, 0.6, 0.2);
        // cos(π (T − t)/T) = −cos(π t/T): the flow at T − t is the reverse of the flow at t.
        let a = f.velocity(x, 0.4);
        let b = f.velocity(x, 3.0 - 0.4);
        assert!((a + b).length() < 1e-12);
    }
}
