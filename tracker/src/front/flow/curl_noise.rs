//! A divergence-free "curl noise" field (Bridson, Hourihan & Nordenstam 2007; the field
//! paper 000 §8.1 alternates with normal flow, after Brochu & Bridson 2009): the curl of a
//! vector potential ψ. Our ψ is a fixed sum of sinusoidal modes (not Perlin noise), so the
//! field is smooth, deterministic and its curl exact; the modes' wave vectors and phases
//! come from a seeded generator.

use glam::DVec3;
use polyphase_grid::VelocityField;

/// Sinusoidal modes of the potential: component j of ψ is Σₘ sin(kₘ·x + φₘⱼ).
const MODES: usize = 6;

/// The curl of a sum of sinusoidal potentials with wavelengths around `scale`, peak speed
/// about `amplitude`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurlNoise {
    waves: [DVec3; MODES],
    phases: [[f64; 3]; MODES],
    amplitude: f64,
}

impl CurlNoise {
    /// Modes from `seed`, wave numbers of magnitude 2π/`scale`, normalised so the speed
    /// never exceeds `amplitude`.
    pub fn new(amplitude: f64, scale: f64, seed: u64) -> CurlNoise {
        let mut state = seed ^ 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            // SplitMix64: a fixed, portable sequence.
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let k = 2.0 * std::f64::consts::PI / scale;
        let mut waves = [DVec3::ZERO; MODES];
        let mut phases = [[0.0; 3]; MODES];
        for m in 0..MODES {
            let z = 2.0 * next() - 1.0;
            let a = 2.0 * std::f64::consts::PI * next();
            let r = (1.0 - z * z).sqrt();
            waves[m] = k * DVec3::new(r * a.cos(), r * a.sin(), z);
            phases[m] = [0, 1, 2].map(|_| 2.0 * std::f64::consts::PI * next());
        }
        CurlNoise {
            waves,
            phases,
            amplitude,
        }
    }

    /// Bound on the speed, for time-step control.
    pub fn max_speed(&self) -> f64 {
        self.amplitude
    }
}

impl VelocityField for CurlNoise {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        // ∇×ψ with ψⱼ = Σ sin(k·x + φⱼ): ∂ᵢψⱼ = kᵢ cos(k·x + φⱼ), so each mode adds k × g.
        let mut v = DVec3::ZERO;
        for (k, phase) in self.waves.iter().zip(&self.phases) {
            let g = phase.map(|p| (k.dot(x) + p).cos());
            v += DVec3::new(
                k.y * g[2] - k.z * g[1],
                k.z * g[0] - k.x * g[2],
                k.x * g[1] - k.y * g[0],
            );
        }
        let k = self.waves[0].length();
        // |k × g| ≤ |k|·|g| ≤ √3·|k| per mode.
        v * self.amplitude / (MODES as f64 * 3f64.sqrt() * k)
    }
}
