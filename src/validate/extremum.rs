//! The extremum of a stats series sampled once a frame: a benchmark's "minimum circularity and
//! the time it occurs" read off frames a fixed interval apart.

/// The (time, value) of the smallest (`largest` false) or largest value of `values` sampled at
/// `times` (increasing). Where the extreme sample has a neighbour on each side, the parabola
/// through the three samples gives its vertex instead, so the time is not rounded to the
/// nearest frame (the value moves less: its error is second order in the frame interval).
/// `None` when the series is empty or holds a non-finite value.
pub fn extremum(times: &[f64], values: &[f64], largest: bool) -> Option<(f64, f64)> {
    if values.is_empty() || times.len() != values.len() || values.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let sign = if largest { -1.0 } else { 1.0 };
    let i = (0..values.len()).min_by(|&a, &b| (sign * values[a]).total_cmp(&(sign * values[b])))?;
    if i == 0 || i + 1 == values.len() {
        return Some((times[i], values[i]));
    }
    let (t0, t1, t2) = (times[i - 1], times[i], times[i + 1]);
    let (y0, y1, y2) = (values[i - 1], values[i], values[i + 1]);
    let (s01, s12) = ((y1 - y0) / (t1 - t0), (y2 - y1) / (t2 - t1));
    // The first extreme sample is strictly beyond its left neighbour and not behind its right
    // one, so the parabola opens the right way (sign · curvature > 0) and its vertex lies
    // between the two neighbours.
    let curvature = (s12 - s01) / (t2 - t0);
    let t = (0.5 * (t0 + t1) - s01 / (2.0 * curvature)).clamp(t0, t2);
    Some((t, y0 + (t - t0) * (s01 + curvature * (t - t1))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_vertex_of_a_sampled_parabola_is_found_between_frames() {
        // y = 0.9 + 2 (t − 1.93)², sampled every 0.1: the smallest sample is at 1.9, the
        // minimum at 1.93 with 0.9, exact for a parabola even on uneven samples.
        let times = [1.6, 1.7, 1.8, 1.9, 2.05, 2.1];
        let values: Vec<f64> = times
            .iter()
            .map(|t| 0.9 + 2.0 * (t - 1.93) * (t - 1.93))
            .collect();
        let (t, v) = extremum(&times, &values, false).unwrap();
        assert!(
            (t - 1.93).abs() < 1e-12 && (v - 0.9).abs() < 1e-12,
            "{t} {v}"
        );
        let negated: Vec<f64> = values.iter().map(|v| -v).collect();
        let (t, v) = extremum(&times, &negated, true).unwrap();
        assert!(
            (t - 1.93).abs() < 1e-12 && (v + 0.9).abs() < 1e-12,
            "{t} {v}"
        );
    }

    #[test]
    fn an_extremum_at_an_end_is_the_sample_and_a_tie_is_split() {
        let times = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(
            extremum(&times, &[1.0, 2.0, 3.0, 4.0], true),
            Some((3.0, 4.0))
        );
        assert_eq!(
            extremum(&times, &[1.0, 2.0, 3.0, 4.0], false),
            Some((0.0, 1.0))
        );
        // Two equal smallest samples: the parabola through (0, 2), (1, 1), (2, 1) has its
        // vertex halfway between them, below both.
        assert_eq!(
            extremum(&times, &[2.0, 1.0, 1.0, 2.0], false),
            Some((1.5, 0.875))
        );
        assert_eq!(extremum(&times, &[2.0, f64::NAN, 1.0, 2.0], false), None);
        assert_eq!(extremum(&[], &[], false), None);
    }
}
