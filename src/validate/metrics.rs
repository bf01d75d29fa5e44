//! The metrics a validation case can ask for, each read off the run's `stats.jsonl` (and the
//! resolved scene) and compared with its reference.

use std::f64::consts::PI;
use std::fs;
use std::path::Path;

use anyhow::{bail, ensure, Context, Result};
use polyphase_coupling::RtLinear;
use polyphase_scenes::{BoundaryKind, MeasureKind, Scene, WALLS};
use serde_json::Value;

use super::capillary::{crossing_period, lamb_period, laplace_jump};
use super::case::MetricSpec;
use super::extremum::extremum;
use super::layered_flow::{Layer, LayeredFlow};
use super::plot::{Plot, Series};
use super::surge_front::Column;
use polyphase_grid::PhaseId;

/// One metric's result.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub metric: String,
    pub ours: f64,
    pub reference: f64,
    /// Relative error, or for bounds (`max_value`, `roundness`) the value itself.
    pub error: f64,
    pub tolerance: f64,
    pub pass: bool,
    /// Ours against the reference over the run (or along the profile).
    pub plot: Option<Plot>,
    /// What else the table should say about this figure (e.g. the figure without a shift).
    pub note: Option<String>,
    /// The case file's `known_gap`: why the metric fails today.
    pub known_gap: Option<String>,
}

impl Outcome {
    /// The table's word for the result, and whether it fails the command.
    pub fn verdict(&self) -> (&'static str, bool) {
        match (self.pass, &self.known_gap) {
            (true, None) => ("pass", false),
            (false, None) => ("FAIL", true),
            (false, Some(_)) => ("known gap", false),
            (true, Some(_)) => ("FAIL: passes, remove known_gap", true),
        }
    }
}

/// A line of ours and the reference's line (or data points, `markers`).
fn curves(
    ours: Vec<(f64, f64)>,
    reference_label: &str,
    reference: Vec<(f64, f64)>,
    markers: bool,
) -> Vec<Series> {
    vec![
        Series {
            label: "polyphase".into(),
            points: ours,
            markers: false,
        },
        Series {
            label: reference_label.into(),
            points: reference,
            markers,
        },
    ]
}

/// Evaluates `spec` on the frames of a finished run of `scene`.
pub fn evaluate(
    spec: &MetricSpec,
    frames: &[Value],
    scene: &Scene,
    case_dir: &Path,
    quick: bool,
) -> Result<Outcome> {
    ensure!(frames.len() >= 2, "the run wrote fewer than two frames");
    let tolerance = spec.tolerance_for(quick);
    let key = || {
        spec.key
            .as_deref()
            .with_context(|| format!("metric '{}' ({}) needs `key`", spec.name, spec.kind))
    };
    let (first, last) = (&frames[0], &frames[frames.len() - 1]);
    let t_end = number(last, "time")?;
    let times: Vec<f64> = frames
        .iter()
        .map(|f| number(f, "time"))
        .collect::<Result<_>>()?;
    let over_time = |y: &str, series: Vec<Series>| Plot {
        title: format!("{}: {}", scene.file.name, spec.name),
        x: "t (s)".into(),
        y: y.into(),
        series,
    };
    let bound = |b: f64| vec![(times[0], b), (t_end, b)];
    let relative = |ours: f64, reference: f64| {
        let error = ours / reference - 1.0;
        (ours, reference, error, error.abs() <= tolerance)
    };
    let mut note = None;
    let ((ours, reference, error, pass), plot) = match spec.kind.as_str() {
        "rt_linear_growth" => {
            let k = key()?;
            let amplitude = |f: &Value| -> Result<f64> {
                Ok(0.5 * (number(f, &format!("{k}.max"))? - number(f, &format!("{k}.min"))?))
            };
            let a0 = amplitude(first)?;
            let ours = (amplitude(last)? / a0).ln() / t_end;
            let mut mine = Vec::new();
            let mut theory = Vec::new();
            for (f, &t) in frames.iter().zip(&times) {
                mine.push((t, amplitude(f)? / a0));
                theory.push((t, rt_theory(spec, scene, t)?));
            }
            let plot = over_time("a / a₀", curves(mine, "exact linear theory", theory, false));
            (
                relative(ours, rt_theory(spec, scene, t_end)?.ln() / t_end),
                Some(plot),
            )
        }
        "free_fall" => {
            let k = key()?;
            let g = gravity(scene)?;
            let down = g.normalize();
            let centroid = |f: &Value| -> Result<glam::DVec3> {
                let c = |a: usize| number(f, &format!("{k}.0.centroid.{a}"));
                Ok(glam::DVec3::new(c(0)?, c(1)?, c(2)?))
            };
            let start = centroid(first)?;
            let drop = (centroid(last)? - start).dot(down);
            let mut mine = Vec::new();
            for (f, &t) in frames.iter().zip(&times) {
                mine.push((t, (centroid(f)? - start).dot(down)));
            }
            let exact = times
                .iter()
                .map(|&t| (t, 0.5 * g.length() * t * t))
                .collect();
            let plot = over_time("centroid drop (m)", curves(mine, "g t² / 2", exact, false));
            (relative(drop, 0.5 * g.length() * t_end * t_end), Some(plot))
        }
        "roundness" => {
            let k = key()?;
            let mut worst: f64 = 0.0;
            let mut mine = Vec::new();
            for (f, &t) in frames.iter().zip(&times) {
                let near = number(f, &format!("{k}.0.nearest"))?;
                let far = number(f, &format!("{k}.0.farthest"))?;
                let here = (1.0 - near).abs().max((far - 1.0).abs());
                mine.push((t, here));
                worst = worst.max(here);
            }
            let plot = over_time(
                "|1 − r / r_eq|, worst",
                curves(mine, "tolerance", bound(tolerance), false),
            );
            ((worst, 0.0, worst, worst <= tolerance), Some(plot))
        }
        "max_value" => {
            let k = key()?;
            let mut worst = f64::NEG_INFINITY;
            let mut mine = Vec::new();
            for (f, &t) in frames[1..].iter().zip(&times[1..]) {
                let v = number(f, k)?;
                mine.push((t, v));
                worst = worst.max(v);
            }
            let plot = over_time(k, curves(mine, "bound", bound(tolerance), false));
            ((worst, tolerance, worst, worst <= tolerance), Some(plot))
        }
        "series" => {
            let k = key()?;
            let file = spec
                .reference
                .as_deref()
                .with_context(|| format!("metric '{}' (series) needs `reference`", spec.name))?;
            let rows = read_series(&case_dir.join(file))?;
            let values: Vec<f64> = frames.iter().map(|f| number(f, k)).collect::<Result<_>>()?;
            let mut worst: Option<(f64, f64, f64)> = None;
            for &(t, r) in &rows {
                let Some(o) = interpolate(&times, &values, t) else {
                    continue;
                };
                let e = (o - r) / r;
                if worst.is_none_or(|w| e.abs() > w.2.abs()) {
                    worst = Some((o, r, e));
                }
            }
            let (o, r, e) =
                worst.with_context(|| format!("{file}: no reference time inside the run"))?;
            let mine = times.iter().copied().zip(values.iter().copied()).collect();
            let plot = over_time(k, curves(mine, file, rows, true));
            ((o, r, e, e.abs() <= tolerance), Some(plot))
        }
        "surge_front" => {
            let (result, plot, said) = surge_front(spec, key()?, frames, &times, scene, case_dir)?;
            note = Some(said);
            (
                (result.0, result.1, result.2, result.2.abs() <= tolerance),
                Some(plot),
            )
        }
        "laplace" => {
            let (_, sigma, r) = capillary_inputs(spec, scene)?;
            let exact = laplace_jump(sigma, r, scene.file.domain.slab);
            let k = key()?;
            let mut mine = Vec::new();
            for (f, &t) in frames[1..].iter().zip(&times[1..]) {
                mine.push((t, number(f, k)?));
            }
            let ours = number(last, k)?;
            let plot = over_time(
                "p_inside − p_outside (Pa)",
                curves(mine, "σκ", bound(exact), false),
            );
            (relative(ours, exact), Some(plot))
        }
        "oscillation_period" => {
            let (pair, sigma, r) = capillary_inputs(spec, scene)?;
            let k = key()?;
            let mut a = Vec::with_capacity(frames.len());
            for f in frames {
                a.push(0.5 * (number(f, &format!("{k}.max"))? - number(f, &format!("{k}.min"))?));
            }
            // Half cycles that reach half the start's amplitude count (`crossing_period`).
            let amplitude = a.first().map_or(0.0, |a0| 0.5 * (a0 - r).abs());
            let ours = crossing_period(&times, &a, r, amplitude).with_context(|| {
                format!(
                    "'{k}' crosses the radius {r} fewer than three times with half cycles of \
                     at least half the start's amplitude: run longer"
                )
            })?;
            let density = |p: PhaseId| scene.file.phases[usize::from(p)].density;
            let exact = lamb_period(
                spec.mode.unwrap_or(2),
                sigma,
                density(pair.0),
                density(pair.1),
                r,
                scene.file.domain.slab,
            );
            let mine = times.iter().copied().zip(a).collect();
            let plot = over_time("half extent (m)", curves(mine, "radius", bound(r), false));
            note = Some(format!("Lamb's period {exact:.5} s, ours {ours:.5} s"));
            (relative(ours, exact), Some(plot))
        }
        "final_max" => {
            let k = key()?;
            let worst = final_max(last, k)?;
            ((worst, tolerance, worst, worst <= tolerance), None)
        }
        "profile" => {
            let k = key()?;
            let (ours, reference, error, plot) = profile_error(spec, k, last, scene)?;
            ((ours, reference, error, error <= tolerance), Some(plot))
        }
        kind @ ("minimum" | "maximum" | "time_of_minimum" | "time_of_maximum" | "final_value") => {
            let k = key()?;
            let reference = spec.value.filter(|v| v.is_finite()).with_context(|| {
                format!("metric '{}' ({kind}) needs a finite `value`", spec.name)
            })?;
            let values: Vec<f64> = frames
                .iter()
                .map(|f| {
                    let less = spec.minus.as_deref().map_or(Ok(0.0), |m| number(f, m))?;
                    Ok(number(f, k)? - less)
                })
                .collect::<Result<_>>()?;
            let mine: Vec<(f64, f64)> = times.iter().copied().zip(values.iter().copied()).collect();
            let (ours, plot) = if kind == "final_value" {
                note = Some(format!("at t = {t_end}"));
                let plot = over_time(k, curves(mine, "reference", bound(reference), false));
                (values[values.len() - 1], plot)
            } else {
                let largest = kind.ends_with("maximum");
                let timed = kind.starts_with("time_of_");
                let (t, v) = extremum(&times, &values, largest)
                    .with_context(|| format!("stats '{k}' hold a non-finite value"))?;
                let plot = if timed {
                    let (lo, hi) = values
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                            (lo.min(v), hi.max(v))
                        });
                    let which = kind.trim_start_matches("time_of_");
                    note = Some(format!("the {which} {v:.5} at t = {t:.4}"));
                    over_time(
                        k,
                        curves(
                            mine,
                            "reference time",
                            vec![(reference, lo), (reference, hi)],
                            false,
                        ),
                    )
                } else {
                    note = Some(format!("at t = {t:.4}"));
                    over_time(k, curves(mine, "reference", bound(reference), false))
                };
                (if timed { t } else { v }, plot)
            };
            (relative(ours, reference), Some(plot))
        }
        other => bail!(
            "metric '{}': unknown kind '{other}' (kinds: rt_linear_growth, free_fall, roundness, \
             max_value, final_max, series, surge_front, profile, laplace, oscillation_period, \
             minimum, maximum, time_of_minimum, time_of_maximum, final_value)",
            spec.name
        ),
    };
    Ok(Outcome {
        metric: spec.name.clone(),
        ours,
        reference,
        error,
        tolerance,
        pass: pass && ours.is_finite(),
        plot,
        note,
        known_gap: spec.gap(quick),
    })
}

/// The index of the scene's phase `name`, which the metric names.
fn phase_id(spec: &MetricSpec, scene: &Scene, name: &str) -> Result<usize> {
    scene
        .file
        .phases
        .iter()
        .position(|p| p.name == name)
        .with_context(|| format!("metric '{}': unknown phase '{name}'", spec.name))
}

/// The drop and surrounding phases' ids, their tension and the drop's radius of a capillary
/// metric.
fn capillary_inputs(spec: &MetricSpec, scene: &Scene) -> Result<((PhaseId, PhaseId), f64, f64)> {
    let [drop, around] = spec
        .phases
        .as_ref()
        .with_context(|| format!("metric '{}' needs `phases = [drop, around]`", spec.name))?;
    let (a, b) = (
        phase_id(spec, scene, drop)? as PhaseId,
        phase_id(spec, scene, around)? as PhaseId,
    );
    let sigma = scene.tension.sigma(a, b);
    ensure!(
        sigma > 0.0,
        "metric '{}': the scene has no tension between '{drop}' and '{around}'",
        spec.name
    );
    let r = spec
        .radius
        .filter(|r| *r > 0.0)
        .with_context(|| format!("metric '{}' needs a positive `radius`", spec.name))?;
    Ok(((a, b), sigma, r))
}

/// The `surge_front` metric: ours (Z, at the worst reference point), theirs, the relative
/// error, the plot in T and Z, and a note with the shift and the unshifted error.
fn surge_front(
    spec: &MetricSpec,
    key: &str,
    frames: &[Value],
    times: &[f64],
    scene: &Scene,
    case_dir: &Path,
) -> Result<((f64, f64, f64), Plot, String)> {
    let need = |what: &str| format!("metric '{}' (surge_front) needs `{what}`", spec.name);
    let [width, height] = spec.column.with_context(|| need("column"))?;
    let window = spec.window.with_context(|| need("window"))?;
    let file = spec
        .reference
        .as_deref()
        .with_context(|| need("reference"))?;
    ensure!(
        width > 0.0 && height > 0.0,
        "metric '{}': column sizes must be positive",
        spec.name
    );
    let reference = read_series(&case_dir.join(file))?;
    let fronts: Vec<f64> = frames
        .iter()
        .map(|f| number(f, key))
        .collect::<Result<_>>()?;
    let column = Column {
        width,
        height,
        g: gravity(scene)?.length(),
    };
    let c = column.compare(times, &fronts, &reference, spec.align_at, window)?;
    let (t, ours, theirs, error) = c.worst;
    let (tu, _, _, eu) = c.worst_unshifted;
    let said = match spec.align_at {
        Some(mark) => format!(
            "time origin where both fronts pass Z = {mark}: ours shifted by ΔT = {:+.3}; worst at \
             T = {t:.2}; from the release (no shift) the worst is {:+.1} % at T = {tu:.2}",
            -c.shift,
            100.0 * eu
        ),
        None => format!("worst at T = {t:.2}, time from the release"),
    };
    let shifted = c.ours.iter().map(|&(t, z)| (t - c.shift, z)).collect();
    let mut series = curves(shifted, file, reference, true);
    if c.shift != 0.0 {
        series[0].label = "polyphase, origin aligned".into();
        series.push(Series {
            label: "polyphase, from the release".into(),
            points: c.ours,
            markers: false,
        });
    }
    let plot = Plot {
        title: format!("{}: {}", scene.file.name, spec.name),
        x: "T = t √(g H) / a".into(),
        y: "Z = x / a".into(),
        series,
    };
    Ok(((ours, theirs, error), plot, said))
}

/// The largest magnitude among the numbers at `key` of the last frame: the number itself, or
/// the entries of an object such as `volume_error` {phase: relative error}.
fn final_max(last: &Value, key: &str) -> Result<f64> {
    let mut v = last;
    for part in key.split('.') {
        v = &v[part];
    }
    match v {
        Value::Object(map) if !map.is_empty() => map
            .iter()
            .map(|(name, x)| {
                x.as_f64()
                    .map(f64::abs)
                    .with_context(|| format!("stats '{key}.{name}' is not a number"))
            })
            .try_fold(0.0f64, |m, x| Ok(m.max(x?))),
        _ => v
            .as_f64()
            .map(f64::abs)
            .with_context(|| format!("the last frame's stats have no number at '{key}'")),
    }
}

/// a(t)/a₀ of the exact linear theory from rest at time `t` (1 at the start), for the
/// metric's two phases; cosh(√(Agk) t) when either fluid is inviscid.
fn rt_theory(spec: &MetricSpec, scene: &Scene, t: f64) -> Result<f64> {
    let [heavy, light] = spec
        .phases
        .as_ref()
        .with_context(|| format!("metric '{}' needs `phases = [heavy, light]`", spec.name))?;
    let lambda = spec
        .wavelength
        .with_context(|| format!("metric '{}' needs `wavelength`", spec.name))?;
    let props = |name: &str| -> Result<(f64, f64)> {
        let p = &scene.file.phases[phase_id(spec, scene, name)?];
        Ok((p.density, p.viscosity))
    };
    let rt = RtLinear {
        k: 2.0 * PI / lambda,
        g: gravity(scene)?.length(),
        heavy: props(heavy)?,
        light: props(light)?,
    };
    if t <= 0.0 {
        return Ok(1.0);
    }
    if rt.heavy.1 > 0.0 && rt.light.1 > 0.0 {
        Ok(rt.amplitude_ratio(t))
    } else {
        let atwood = (rt.heavy.0 - rt.light.0) / (rt.heavy.0 + rt.light.0);
        Ok(((atwood * rt.g * rt.k).sqrt() * t).cosh())
    }
}

/// The last frame's velocity profile `key` against the exact steady flow of the metric's
/// `layers` (see `layered_flow.rs`), the walls, gravity and phases taken from the scene:
/// (ours, exact) at the worst sample and the largest |ours − exact| over the largest |exact|.
fn profile_error(
    spec: &MetricSpec,
    key: &str,
    last: &Value,
    scene: &Scene,
) -> Result<(f64, f64, f64, Plot)> {
    let what = |field: &str| format!("metric '{}' (profile) needs `{field}`", spec.name);
    let names = spec.layers.as_deref().with_context(|| what("layers"))?;
    let interfaces = spec.interfaces.as_deref().unwrap_or_default();
    ensure!(
        interfaces.len() + 1 == names.len(),
        "metric '{}': {} layers need {} interfaces, got {}",
        spec.name,
        names.len(),
        names.len() - 1,
        interfaces.len()
    );
    let Some(&MeasureKind::VelocityProfile { component, axis }) = scene
        .measures
        .iter()
        .find(|m| m.name == key)
        .map(|m| &m.kind)
    else {
        bail!(
            "metric '{}': the scene has no [[measure]] of kind 'velocity_profile' named '{key}'",
            spec.name
        );
    };
    let solver = scene
        .file
        .solver
        .as_ref()
        .context("the metric needs a coupled scene")?;
    let grid = scene
        .solver_grid
        .context("the metric needs a coupled scene")?;
    ensure!(
        solver.boundary.axes()[axis] == BoundaryKind::NoSlip,
        "metric '{}': the profile's axis needs no-slip walls (solver.boundary)",
        spec.name
    );
    let wall = |w: usize| {
        solver
            .boundary
            .wall_velocity
            .get(WALLS[w])
            .map_or(0.0, |v| v[component])
    };
    let low = grid.origin[axis];
    let width = grid.dims[axis] as f64 * grid.h;
    let g = gravity(scene)?[component];
    let mut layers = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        let phase = scene
            .file
            .phases
            .iter()
            .find(|p| p.name == *name)
            .with_context(|| format!("metric '{}': unknown phase '{name}'", spec.name))?;
        layers.push(Layer {
            top: interfaces.get(k).map_or(width, |s| s - low),
            viscosity: phase.viscosity,
            force: phase.density * g,
        });
    }
    let flow = LayeredFlow::new(layers, (wall(2 * axis), wall(2 * axis + 1)))
        .with_context(|| format!("metric '{}'", spec.name))?;
    let samples = |field: &str| -> Result<Vec<f64>> {
        last[key][field]
            .as_array()
            .and_then(|a| a.iter().map(Value::as_f64).collect())
            .with_context(|| format!("stats have no number list at '{key}.{field}'"))
    };
    let (position, value) = (samples("position")?, samples("value")?);
    ensure!(
        !position.is_empty() && position.len() == value.len(),
        "stats '{key}': positions and values differ in number or are empty"
    );
    let exact: Vec<f64> = position.iter().map(|x| flow.velocity(x - low)).collect();
    let scale = exact.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    ensure!(
        scale > 0.0,
        "metric '{}': the exact profile is zero everywhere",
        spec.name
    );
    let worst = (0..value.len())
        .max_by(|&i, &j| {
            (value[i] - exact[i])
                .abs()
                .total_cmp(&(value[j] - exact[j]).abs())
        })
        .unwrap_or(0);
    let dense = (0..=200)
        .map(|i| {
            let x = low + width * i as f64 / 200.0;
            (x, flow.velocity(x - low))
        })
        .collect();
    let axis_name = ["x", "y", "z"][axis];
    let plot = Plot {
        title: format!("{}: {}", scene.file.name, spec.name),
        x: format!("{axis_name} (m)"),
        y: format!("velocity {} (m/s)", ["u", "v", "w"][component]),
        series: vec![
            Series {
                label: "exact layered flow".into(),
                points: dense,
                markers: false,
            },
            Series {
                label: "polyphase".into(),
                points: position
                    .iter()
                    .copied()
                    .zip(value.iter().copied())
                    .collect(),
                markers: true,
            },
        ],
    };
    Ok((
        value[worst],
        exact[worst],
        (value[worst] - exact[worst]).abs() / scale,
        plot,
    ))
}

fn gravity(scene: &Scene) -> Result<glam::DVec3> {
    let spec = scene
        .file
        .solver
        .as_ref()
        .context("the metric needs a coupled scene (gravity)")?;
    Ok(glam::DVec3::from_array(spec.gravity))
}

/// The number at a dotted `path` of a stats line (`tips.max`, `pieces_water.0.centroid.1`).
fn number(line: &Value, path: &str) -> Result<f64> {
    let mut v = line;
    for part in path.split('.') {
        v = match part.parse::<usize>() {
            Ok(i) if v.is_array() => &v[i],
            _ => &v[part],
        };
    }
    v.as_f64()
        .with_context(|| format!("stats have no number at '{path}' (is it a [[measure]]?)"))
}

/// (time, value) rows of a CSV file; `#` lines are comments, and a first row that does not
/// parse is a header.
fn read_series(path: &Path) -> Result<Vec<(f64, f64)>> {
    let text =
        fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut rows = Vec::new();
    let mut first = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let header = std::mem::replace(&mut first, false);
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed = match cells.as_slice() {
            [t, v] => t.parse::<f64>().ok().zip(v.parse::<f64>().ok()),
            _ => None,
        };
        match parsed {
            Some((t, v)) if t.is_finite() && v.is_finite() => rows.push((t, v)),
            _ if header => continue,
            _ => bail!("{}:{}: expected `time,value`", path.display(), i + 1),
        }
    }
    ensure!(!rows.is_empty(), "{}: no rows", path.display());
    Ok(rows)
}

/// Piecewise-linear y(x) on the first segment of `xs` whose ends bracket x (xs increasing, or
/// non-decreasing as a front that pauses); `None` when none does.
pub(super) fn interpolate(xs: &[f64], ys: &[f64], x: f64) -> Option<f64> {
    xs.windows(2).zip(ys.windows(2)).find_map(|(x2, y2)| {
        (x2[0] <= x && x <= x2[1]).then(|| {
            if x2[1] > x2[0] {
                y2[0] + (y2[1] - y2[0]) * (x - x2[0]) / (x2[1] - x2[0])
            } else {
                y2[0]
            }
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn dotted_paths_reach_into_objects_and_arrays() {
        let line = json!({"tips": {"max": 2.5}, "pieces_water": [{"centroid": [1.0, 0.5, 0.25]}]});
        assert_eq!(number(&line, "tips.max").unwrap(), 2.5);
        assert_eq!(number(&line, "pieces_water.0.centroid.1").unwrap(), 0.5);
        let err = number(&line, "tips.min").unwrap_err().to_string();
        assert!(err.contains("'tips.min'"), "{err}");
    }

    #[test]
    fn series_files_take_comments_a_header_and_refuse_bad_rows() {
        let dir = std::env::temp_dir().join(format!("polyphase-series-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.csv");
        fs::write(&good, "# source\ntime,value\n0.1, 2.5\n\n0.2,3\n").unwrap();
        assert_eq!(read_series(&good).unwrap(), vec![(0.1, 2.5), (0.2, 3.0)]);
        let bad = dir.join("bad.csv");
        fs::write(&bad, "time,value\n0.1,2.5\n0.2,x\n").unwrap();
        let err = read_series(&bad).unwrap_err().to_string();
        assert!(err.ends_with("bad.csv:3: expected `time,value`"), "{err}");
        fs::remove_dir_all(&dir).unwrap();
    }

    /// The couette2 case's metric and scene, and a last frame whose `u_profile` holds
    /// `values` at the 32 solver cell centres across the channel.
    fn couette(values: impl Fn(f64) -> f64) -> (MetricSpec, Scene, Value) {
        let text = include_str!("../../validation/couette2/scene.toml");
        let scene = Scene::parse(text, "couette2/scene.toml").unwrap();
        let case = include_str!("../../validation/couette2/case.toml");
        let file: super::super::case::CaseFile = toml::from_str(case).unwrap();
        let position: Vec<f64> = (0..32).map(|j| (j as f64 + 0.5) / 32.0).collect();
        let value: Vec<f64> = position.iter().map(|&y| values(y)).collect();
        let last = json!({"u_profile": {"position": position, "value": value}});
        (file.metrics[0].clone(), scene, last)
    }

    #[test]
    fn a_profile_is_compared_with_the_layered_flow_of_the_scene() {
        // couette2: μ 10 below y = 0.4, 1 above, lid 0.01 m/s: τ = 0.01/(0.04 + 0.6), so the
        // interface moves at 0.4 τ/10 and the profile is linear on each side.
        let tau = 0.01 / (0.4 / 10.0 + 0.6 / 1.0);
        let exact = move |y: f64| {
            if y < 0.4 {
                tau * y / 10.0
            } else {
                tau * (0.04 + (y - 0.4))
            }
        };
        let (spec, scene, last) = couette(exact);
        let (_, _, error, _) = profile_error(&spec, "u_profile", &last, &scene).unwrap();
        assert!(error < 1e-12, "{error}");
        // The samples above y = 0.9 are 2e-4 m/s (2 % of the lid speed) off: the error is that
        // over the largest exact velocity, the top sample's.
        let (spec, scene, last) = couette(|y| exact(y) + if y > 0.9 { 2e-4 } else { 0.0 });
        let (_, _, error, _) = profile_error(&spec, "u_profile", &last, &scene).unwrap();
        let top = exact(31.5 / 32.0);
        assert!((error - 2e-4 / top).abs() < 1e-9, "{error}");
    }

    #[test]
    fn a_profile_metric_names_what_it_misses() {
        let (mut spec, scene, last) = couette(|_| 0.0);
        let err = profile_error(&spec, "max_speed", &last, &scene)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("no [[measure]] of kind 'velocity_profile' named 'max_speed'"),
            "{err}"
        );
        spec.interfaces = None;
        let err = profile_error(&spec, "u_profile", &last, &scene)
            .unwrap_err()
            .to_string();
        assert!(err.contains("2 layers need 1 interfaces, got 0"), "{err}");
    }

    #[test]
    fn extremes_and_the_final_value_are_read_against_the_cases_value() {
        // The bubble_rise2 case's metrics on frames 0.1 apart whose circularity, a parabola,
        // dips to 0.9 at t = 0.2 and whose centroid ends at 1.1.
        let case = include_str!("../../validation/bubble_rise2/case.toml");
        let file: super::super::case::CaseFile = toml::from_str(case).unwrap();
        let scene = Scene::parse(
            include_str!("../../validation/bubble_rise2/scene.toml"),
            "bubble_rise2/scene.toml",
        )
        .unwrap();
        let frames: Vec<Value> = (0..5)
            .map(|i| {
                let t = 0.1 * i as f64;
                json!({"time": t, "circularity": 0.9 + (t - 0.2) * (t - 0.2),
                       "centroid": [0.5, 1.0 + 0.025 * i as f64, 0.0]})
            })
            .collect();
        let dir = Path::new("validation/bubble_rise2");
        let run = |spec: &MetricSpec| evaluate(spec, &frames, &scene, dir, false);
        let minimum = run(&file.metrics[0]).unwrap();
        assert!((minimum.ours - 0.9).abs() < 1e-12, "{minimum:?}");
        assert!((minimum.error - (0.9 / 0.9013 - 1.0)).abs() < 1e-12);
        let when = run(&file.metrics[1]).unwrap();
        assert!((when.ours - 0.2).abs() < 1e-12, "{when:?}");
        let last = run(&file.metrics[4]).unwrap();
        assert_eq!(last.ours, 1.1);
        assert_eq!(last.note.as_deref(), Some("at t = 0.4"));
        let mut spec = file.metrics[4].clone();
        spec.value = None;
        let err = run(&spec).unwrap_err().to_string();
        assert!(
            err.contains("(final_value) needs a finite `value`"),
            "{err}"
        );
    }

    #[test]
    fn final_max_takes_a_number_or_the_largest_entry() {
        let last: Value = serde_json::from_str(
            r#"{"hausdorff": {"over_h": 0.4}, "volume_error": {"a": -0.02, "b": 0.01}}"#,
        )
        .unwrap();
        assert_eq!(final_max(&last, "hausdorff.over_h").unwrap(), 0.4);
        assert_eq!(final_max(&last, "volume_error").unwrap(), 0.02);
        assert!(final_max(&last, "missing").is_err());
    }

    #[test]
    fn interpolation_is_linear_and_stays_inside() {
        let (xs, ys) = ([0.0, 1.0, 3.0], [0.0, 2.0, 3.0]);
        assert_eq!(interpolate(&xs, &ys, 0.5), Some(1.0));
        assert_eq!(interpolate(&xs, &ys, 2.0), Some(2.5));
        assert_eq!(interpolate(&xs, &ys, 3.5), None);
    }
}
