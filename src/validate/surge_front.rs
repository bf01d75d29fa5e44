//! The dam-break surge front in Martin & Moyce's (1952) scaling, against their measurements.
//!
//! A column of width a and height n²·a collapses; the front's distance x from the wall is
//! Z = x / a at T = n·t·√(g/a) = t·√(g·H)/a (H = n²·a, the column's height). The experiment's
//! own t = 0 cannot be matched (its column is released by taking a retaining plate away, which
//! takes a finite time, and its first marks show a front slower than a free collapse), so the
//! comparison may set the time origin where both fronts pass one mark (`align_at`), and reports
//! the error from the release (no shift) beside the aligned one.

use anyhow::{ensure, Context, Result};

use super::metrics::interpolate;

/// How a run's front is scaled and compared.
#[derive(Clone, Copy, Debug)]
pub struct Column {
    /// The column's width a and height H (m).
    pub width: f64,
    pub height: f64,
    /// Gravity's magnitude (m/s²).
    pub g: f64,
}

/// The comparison over a window of T.
#[derive(Clone, Debug)]
pub struct Comparison {
    /// Ours as (T, Z) from the release.
    pub ours: Vec<(f64, f64)>,
    /// What is subtracted from our T so that both fronts pass Z = `align_at` at the same T
    /// (0 without alignment).
    pub shift: f64,
    /// The worst reference point inside the window, aligned: (T, our Z, their Z, relative error).
    pub worst: (f64, f64, f64, f64),
    /// The same from the release (no shift).
    pub worst_unshifted: (f64, f64, f64, f64),
}

impl Column {
    /// (T, Z) of the run's `times` and front positions `fronts` (m from the wall).
    pub fn scale(&self, times: &[f64], fronts: &[f64]) -> Vec<(f64, f64)> {
        let t_unit = self.width / (self.g * self.height).sqrt();
        times
            .iter()
            .zip(fronts)
            .map(|(&t, &x)| (t / t_unit, x / self.width))
            .collect()
    }

    /// Compares ours with `reference` (T, Z) rows at their T inside `window`.
    pub fn compare(
        &self,
        times: &[f64],
        fronts: &[f64],
        reference: &[(f64, f64)],
        align_at: Option<f64>,
        window: [f64; 2],
    ) -> Result<Comparison> {
        let ours = self.scale(times, fronts);
        let (t, z): (Vec<f64>, Vec<f64>) = ours.iter().copied().unzip();
        let shift = match align_at {
            None => 0.0,
            Some(mark) => {
                let (rt, rz): (Vec<f64>, Vec<f64>) = reference.iter().copied().unzip();
                // The first T at which each rising front reaches the mark.
                let theirs = interpolate(&rz, &rt, mark)
                    .with_context(|| format!("the reference never reaches Z = {mark}"))?;
                let mine = interpolate(&z, &t, mark)
                    .with_context(|| format!("the run's front never reaches Z = {mark}"))?;
                mine - theirs
            }
        };
        let worst_at = |shift: f64| -> Option<(f64, f64, f64, f64)> {
            reference
                .iter()
                .filter(|(rt, _)| (window[0]..=window[1]).contains(rt))
                .filter_map(|&(rt, rz)| {
                    let mine = interpolate(&t, &z, rt + shift)?;
                    Some((rt, mine, rz, mine / rz - 1.0))
                })
                .max_by(|a, b| a.3.abs().total_cmp(&b.3.abs()))
        };
        let inside = reference
            .iter()
            .filter(|(rt, _)| (window[0]..=window[1]).contains(rt))
            .count();
        ensure!(inside > 0, "no reference point with T in {window:?}");
        let worst = worst_at(shift)
            .with_context(|| format!("the run ends before the reference's T in {window:?}"))?;
        let worst_unshifted = worst_at(0.0)
            .with_context(|| format!("the run ends before the reference's T in {window:?}"))?;
        Ok(Comparison {
            ours,
            shift,
            worst,
            worst_unshifted,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLUMN: Column = Column {
        width: 0.1,
        height: 0.2,
        g: 9.81,
    };

    #[test]
    fn the_scaling_is_martin_and_moyces() {
        // T = n·t·√(g/a) with n² = H/a = 2: t = 1 s gives √2·√(98.1).
        let s = COLUMN.scale(&[1.0], &[0.25]);
        assert!((s[0].0 - 2f64.sqrt() * 98.1f64.sqrt()).abs() < 1e-12);
        assert_eq!(s[0].1, 2.5);
    }

    #[test]
    fn a_front_late_by_a_constant_time_is_exact_once_aligned() {
        // Theirs: Z = 1 + T² / 2; ours the same curve 0.2 earlier in T.
        let reference: Vec<(f64, f64)> = (0..=30)
            .map(|k| {
                let t = 0.1 * k as f64;
                (t, 1.0 + t * t / 2.0)
            })
            .collect();
        let t_unit = COLUMN.width / (COLUMN.g * COLUMN.height).sqrt();
        let big: Vec<f64> = (0..=400).map(|k| 0.01 * k as f64).collect();
        let times: Vec<f64> = big.iter().map(|t| t * t_unit).collect();
        let fronts: Vec<f64> = big
            .iter()
            .map(|&t| {
                let t = t + 0.2;
                COLUMN.width * (1.0 + t * t / 2.0)
            })
            .collect();
        let c = COLUMN
            .compare(&times, &fronts, &reference, Some(1.5), [1.0, 3.0])
            .unwrap();
        assert!((c.shift + 0.2).abs() < 2e-3, "{}", c.shift);
        // Linear interpolation of a parabola at ΔT = 0.01: error below 1e-4 relative.
        assert!(c.worst.3.abs() < 1e-3, "{:?}", c.worst);
        // Unshifted, ours is ahead: at T = 1, (1 + 1.2²/2)/(1 + 1/2) − 1 = 14.7 %.
        assert!(c.worst_unshifted.3 > 0.14, "{:?}", c.worst_unshifted);
    }

    #[test]
    fn a_run_that_never_reaches_the_mark_is_an_error() {
        let err = COLUMN
            .compare(
                &[0.0, 0.1],
                &[0.1, 0.11],
                &[(1.0, 1.5)],
                Some(1.44),
                [1.0, 3.0],
            )
            .unwrap_err()
            .to_string();
        assert!(err.contains("never reaches Z = 1.44"), "{err}");
    }
}
