//! Deterministic pseudo-random points (SplitMix64) for accuracy measurements and tests: the
//! same seed gives the same points on every machine and thread count.

use glam::DVec3;

/// SplitMix64 generator (Steele, Lea & Flood 2014); the state is the tuple field.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// Uniform in [0, 1), 53 random bits.
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in the box [lo, hi).
    pub fn point(&mut self, lo: DVec3, hi: DVec3) -> DVec3 {
        let u = DVec3::new(self.next_f64(), self.next_f64(), self.next_f64());
        lo + (hi - lo) * u
    }
}
