//! The exact references of the surface-tension cases: Laplace's pressure jump of a drop at
//! rest, and Lamb's (1932, §275) period of a drop's small shape oscillations.

use std::f64::consts::TAU;

/// Laplace's jump σκ (Pa) across a drop of radius `r` at rest: κ = 2/r for a sphere, 1/r for
/// a disc (a slab scene's drop, a cylinder along z).
pub fn laplace_jump(sigma: f64, r: f64, slab: bool) -> f64 {
    sigma * if slab { 1.0 / r } else { 2.0 / r }
}

/// The period (s) of mode `n` of an inviscid drop (density `inner`) of radius `r` in an
/// inviscid fluid (`outer`), tension `sigma` (Lamb 1932, §275):
/// sphere ω² = n(n−1)(n+1)(n+2)·σ / (r³·((n+1)ρ_i + n·ρ_o)),
/// disc ω² = n(n²−1)·σ / (r³·(ρ_i + ρ_o)).
pub fn lamb_period(n: u32, sigma: f64, inner: f64, outer: f64, r: f64, slab: bool) -> f64 {
    let n = f64::from(n);
    let omega2 = if slab {
        n * (n * n - 1.0) * sigma / (r.powi(3) * (inner + outer))
    } else {
        n * (n - 1.0) * (n + 1.0) * (n + 2.0) * sigma
            / (r.powi(3) * ((n + 1.0) * inner + n * outer))
    };
    TAU / omega2.sqrt()
}

/// The period of `a(t)` oscillating about `mean`: twice the mean time between its crossings
/// of `mean` (linear interpolation between samples), from the first crossing to the last
/// counted. A crossing counts while the half cycle before it reached `min_amplitude` from
/// `mean`: once the oscillation has decayed below that, noise moves its crossings (a drop's
/// late wiggles within a fraction of a cell of R). `None` with fewer than three crossings (a
/// period needs two half periods).
pub fn crossing_period(times: &[f64], a: &[f64], mean: f64, min_amplitude: f64) -> Option<f64> {
    let mut crossings = Vec::new();
    let mut reached = a.first().map_or(0.0, |v| (v - mean).abs());
    for (t, v) in times.windows(2).zip(a.windows(2)) {
        let (d0, d1) = (v[0] - mean, v[1] - mean);
        if d0 != d1 && d0 * d1 <= 0.0 && d1 != 0.0 {
            if reached < min_amplitude {
                break;
            }
            crossings.push(t[0] + (t[1] - t[0]) * d0 / (d0 - d1));
            reached = 0.0;
        }
        reached = reached.max(d1.abs());
    }
    if crossings.len() < 3 {
        return None;
    }
    let span = crossings[crossings.len() - 1] - crossings[0];
    Some(2.0 * span / (crossings.len() - 1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambs_frequencies() {
        // Rayleigh's drop in vacuum, n = 2: ω² = 8σ/(ρr³).
        let t = lamb_period(2, 0.07, 1000.0, 0.0, 0.01, false);
        let omega = (8.0 * 0.07 / (1000.0 * 1e-6f64)).sqrt();
        assert!((t - TAU / omega).abs() < 1e-12 * t);
        // Disc, n = 2: ω² = 6σ/((ρ_i + ρ_o) r³).
        let t = lamb_period(2, 0.07, 1000.0, 1.0, 0.01, true);
        let omega = (6.0 * 0.07 / (1001.0 * 1e-6f64)).sqrt();
        assert!((t - TAU / omega).abs() < 1e-12 * t);
        // σ/R for a disc, 2σ/R for a sphere (to round-off).
        assert!((laplace_jump(0.07, 0.01, true) - 7.0).abs() < 1e-12);
        assert!((laplace_jump(0.07, 0.01, false) - 14.0).abs() < 1e-12);
    }

    #[test]
    fn the_period_of_a_sampled_damped_cosine() {
        // a = 1 + 0.1·e^(−t/5)·cos(2πt/0.3), sampled 40 times a period over 2.5 periods: the
        // crossings' spacing is the period exactly for a damped cosine (its zeros are evenly
        // spaced), up to the linear interpolation's error between samples (< 1e-3 of a period).
        let times: Vec<f64> = (0..=100).map(|k| 0.0075 * k as f64).collect();
        let a: Vec<f64> = times
            .iter()
            .map(|&t| 1.0 + 0.1 * (-t / 5.0).exp() * (TAU * t / 0.3).cos())
            .collect();
        let p = crossing_period(&times, &a, 1.0, 0.0).unwrap();
        assert!((p / 0.3 - 1.0).abs() < 1e-3, "{p}");
        assert_eq!(crossing_period(&times[..10], &a[..10], 1.0, 0.0), None);
    }

    #[test]
    fn crossings_of_a_decayed_oscillation_do_not_count() {
        // a = 1 + 0.1·e^(−t/0.6)·cos(2πt/0.3) + 0.01·sin(2πt/0.07): from the fourth half cycle
        // on, the amplitude has fallen below half the start's, and the fast wiggle moves the
        // crossings and adds more. The three counted crossings give the period to within the
        // wiggle's shift of each (0.01/(0.08·2π/0.3) ≈ 6e-3 s, 2 % of the period each, 3 %
        // at worst on their spacing); all of them give it 34 % short.
        let times: Vec<f64> = (0..=300).map(|k| 0.0025 * k as f64).collect();
        let a: Vec<f64> = times
            .iter()
            .map(|&t| {
                1.0 + 0.1 * (-t / 0.6).exp() * (TAU * t / 0.3).cos() + 0.01 * (TAU * t / 0.07).sin()
            })
            .collect();
        let counted = crossing_period(&times, &a, 1.0, 0.05).unwrap();
        let all = crossing_period(&times, &a, 1.0, 0.0).unwrap();
        assert!((counted / 0.3 - 1.0).abs() < 0.03, "{counted}");
        assert!((all / 0.3 - 1.0).abs() > 0.1, "{all}");
    }
}
