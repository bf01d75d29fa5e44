//! `polyphase bench front`: the front tracker next to the contouring tracker on one periodic
//! scene (issue 6: Enright at a 128³ edge length): volume error, Hausdorff distance to the
//! start, triangle count, time per step and the share of collision handling vs remeshing.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result};
use polyphase_coupling::build_tracker;
use polyphase_scenes::{Scene, TrackerKind};
use polyphase_tracker::{metrics, InterfaceTracker};

/// One tracker's run over the scene.
struct Row {
    tracker: &'static str,
    steps: usize,
    start_triangles: usize,
    max_triangles: usize,
    mean_edge: f64,
    step_s: f64,
    /// Seconds per stage, summed over the steps.
    stages: Vec<(&'static str, f64)>,
    /// Worst relative volume error of the non-background phases: against the exact shapes,
    /// and against the tracker's own first mesh.
    error_exact: f64,
    error_start: f64,
    hausdorff_h: f64,
}

/// Runs `scene` at each resolution with both trackers, or only `only` (the first `steps`
/// steps when given, else the whole period), and prints the table.
pub fn run(
    scene: &str,
    res: &[i64],
    steps: Option<usize>,
    only: Option<TrackerKind>,
) -> Result<()> {
    let base = polyphase_scenes::load(scene)?;
    let wanted = |kind: TrackerKind| only.is_none_or(|o| o == kind);
    let mut out = String::new();
    for &r in res {
        let contour = base.with_overrides(Some(r), None)?;
        let front = contour.with_tracker(TrackerKind::Front)?;
        let mut rows = Vec::new();
        for (scene, name) in [(&contour, "contour"), (&front, "front")] {
            if !wanted(scene.file.tracker.kind) {
                continue;
            }
            eprintln!("{} {r}³: {name} tracker", scene.file.name);
            let (tracker, _) = build_tracker(scene, None)?;
            rows.push(measure(scene, name, tracker, steps)?);
        }
        let _ = writeln!(
            out,
            "{} at {r}³ (h = {:.5})",
            base.file.name, contour.grid.h
        );
        out.push_str(&table(&rows));
        out.push('\n');
        eprint!("{out}");
    }
    print!("{out}");
    Ok(())
}

fn measure<T: InterfaceTracker>(
    scene: &Scene,
    name: &'static str,
    mut tracker: T,
    limit: Option<usize>,
) -> Result<Row> {
    let reference = scene.reference_volumes();
    let initial = tracker.mesh().clone();
    let start_volumes = tracker.phase_volumes();
    let per_frame = scene.steps_per_frame(tracker.max_travel());
    let total = per_frame * scene.file.time.frames as usize;
    let steps = limit.unwrap_or(total).min(total);
    let dt = scene.frame_dt() / per_frame as f64;
    let mut stages: Vec<(&'static str, f64)> = Vec::new();
    let mut max_triangles = initial.triangle_count();
    let started = Instant::now();
    for s in 0..steps {
        let stats = tracker
            .advance(&scene.velocity, s as f64 * dt, dt)
            .with_context(|| format!("{name} tracker, step {s}"))?;
        for (stage, secs) in stats.stages {
            match stages.iter_mut().find(|(n, _)| *n == stage) {
                Some(e) => e.1 += secs,
                None => stages.push((stage, secs)),
            }
        }
        max_triangles = max_triangles.max(tracker.mesh().triangle_count());
        if s % 50 == 49 {
            eprintln!(
                "  step {}/{steps}: {} triangles",
                s + 1,
                tracker.mesh().triangle_count()
            );
        }
    }
    let step_s = started.elapsed().as_secs_f64() / steps.max(1) as f64;
    let end = tracker.phase_volumes();
    let worst = |against: &[f64]| {
        (0..end.len())
            .filter(|&p| p != scene.initial.background as usize && against[p] > 0.0)
            .map(|p| ((end[p] - against[p]) / against[p]).abs())
            .fold(0.0, f64::max)
    };
    Ok(Row {
        tracker: name,
        steps,
        start_triangles: initial.triangle_count(),
        max_triangles,
        mean_edge: tracker.mesh().mean_edge_length(),
        step_s,
        stages,
        error_exact: worst(&reference),
        error_start: worst(&start_volumes),
        hausdorff_h: metrics::hausdorff(tracker.mesh(), &initial) / scene.grid.h,
    })
}

fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let line = |s: &mut String, label: &str, f: &dyn Fn(&Row) -> String| {
        let _ = write!(s, "{label:<30}");
        for r in rows {
            let _ = write!(s, "{:>14}", f(r));
        }
        s.push('\n');
    };
    let share = |r: &Row, name: &str| {
        let total: f64 = r.stages.iter().map(|x| x.1).sum();
        match r.stages.iter().find(|x| x.0 == name) {
            Some(&(_, part)) => format!("{:.0}%", 100.0 * part / total.max(1e-300)),
            None => "-".into(),
        }
    };
    line(&mut s, "Tracker", &|r| r.tracker.to_string());
    line(&mut s, "Steps", &|r| r.steps.to_string());
    line(&mut s, "Triangles (start / max)", &|r| {
        format!("{}/{}", r.start_triangles, r.max_triangles)
    });
    line(&mut s, "Mean edge at end", &|r| {
        format!("{:.5}", r.mean_edge)
    });
    line(&mut s, "Time per step (s)", &|r| format!("{:.4}", r.step_s));
    line(&mut s, "Collision share", &|r| share(r, "collide"));
    line(&mut s, "Remeshing share", &|r| share(r, "remesh"));
    line(&mut s, "Worst volume error, exact", &|r| {
        format!("{:.3}%", 100.0 * r.error_exact)
    });
    line(&mut s, "Worst volume error, start", &|r| {
        format!("{:.3}%", 100.0 * r.error_start)
    });
    line(&mut s, "Hausdorff to start / h", &|r| {
        format!("{:.2}", r.hausdorff_h)
    });
    s
}
