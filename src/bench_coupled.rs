//! `polyphase bench coupled`: a coupled scene run at several tracker resolutions, each in its
//! own process (so peak memory is that run's), with seconds per frame for every stage, the
//! start-up the stages do not cover, peak memory and CPU use, read off each run's summary.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};
use serde_json::Value;

/// One run's figures, from the summary line of its `stats.jsonl`.
struct Row {
    res: i64,
    solver_res: Option<i64>,
    frames: f64,
    steps: u64,
    wall: f64,
    stages: Vec<(String, f64)>,
    peak_mb: Option<f64>,
    cpu: Option<f64>,
}

/// Runs `scene` at each resolution for `frames` frames (the scene's own count when `None`) on
/// `threads` workers, into `out/<res>`, and prints the table.
pub fn run(
    scene: &str,
    res: &[i64],
    frames: Option<i64>,
    threads: Option<usize>,
    out: &Path,
) -> Result<()> {
    let base = polyphase_scenes::load(scene)?;
    if !base.is_coupled() {
        bail!("{scene} is a passive scene; `bench coupled` times the fluid coupling");
    }
    let program = std::env::current_exe().context("cannot find this program's path")?;
    let mut rows = Vec::new();
    for &r in res {
        // Validates the override here, with one clear error, before any run starts.
        let resolved = base.with_overrides(Some(r), frames)?;
        let dir = out.join(r.to_string());
        let mut cmd = Command::new(&program);
        cmd.args(["run", scene, "--resolution", &r.to_string(), "--out"])
            .arg(&dir);
        if let Some(f) = frames {
            cmd.args(["--frames", &f.to_string()]);
        }
        if let Some(t) = threads {
            cmd.args(["--threads", &t.to_string()]);
        }
        eprintln!("bench coupled: {scene} at {r} into {}", dir.display());
        let status = cmd
            .stdout(std::process::Stdio::null())
            .status()
            .context("cannot start the run")?;
        if !status.success() {
            bail!("the run at resolution {r} failed (see above)");
        }
        rows.push(read_row(
            &dir,
            r,
            resolved.file.solver.and_then(|s| s.resolution),
        )?);
        eprintln!("{}", table(&rows));
    }
    println!("{}", table(&rows));
    Ok(())
}

/// The summary of the run in `dir`.
fn read_row(dir: &Path, res: i64, solver_res: Option<i64>) -> Result<Row> {
    let path: PathBuf = dir.join("stats.jsonl");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let summary: Value = text
        .lines()
        .rev()
        .find_map(|l| {
            serde_json::from_str::<Value>(l)
                .ok()
                .and_then(|v| v.get("summary").cloned())
        })
        .with_context(|| format!("{} has no summary line", path.display()))?;
    let num = |v: &Value| v.as_f64();
    let stages = summary["stage_s"]
        .as_object()
        .map(|m| {
            m.iter()
                .map(|(k, v)| (k.clone(), num(v).unwrap_or(0.0)))
                .collect()
        })
        .unwrap_or_default();
    Ok(Row {
        res,
        solver_res,
        frames: num(&summary["frames"]).unwrap_or(0.0),
        steps: summary["steps"].as_u64().unwrap_or(0),
        wall: num(&summary["wall_s"]).unwrap_or(0.0),
        stages,
        peak_mb: num(&summary["process"]["peak_rss_mb"]),
        cpu: num(&summary["process"]["cpu_s"]),
    })
}

/// Stages grouped into the table's columns: tracker, solver, output.
const TRACKER: [&str; 8] = [
    "build",
    "contour",
    "components",
    "specks",
    "succession",
    "query",
    "sample",
    "interface_velocity",
];
const SOLVER: [&str; 4] = ["advect_velocity", "forces", "pressure", "viscosity"];

/// Seconds per frame of each stage and stage group; the start-up (wall seconds no stage covers:
/// building the scene and its exact reference volumes); peak memory; CPU use (CPU seconds over
/// wall seconds: 200 % is two cores busy throughout).
fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{:>41} | {:<63} |", "", "seconds per frame");
    let _ = writeln!(
        s,
        "{:>5} {:>6} {:>6} {:>6} {:>8} {:>6} | {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} {:>7} | {:>7} {:>5}",
        "res", "solver", "frames", "steps", "wall s", "start", "build", "contour", "query",
        "tracker", "press", "visc", "solver", "write", "peak MB", "CPU"
    );
    for r in rows {
        let stage = |n: &str| r.stages.iter().find(|s| s.0 == n).map_or(0.0, |s| s.1);
        let group = |names: &[&str]| names.iter().map(|n| stage(n)).sum::<f64>();
        let covered: f64 = r.stages.iter().map(|s| s.1).sum();
        let per = |x: f64| x / r.frames.max(1.0);
        let _ = writeln!(
            s,
            "{:>5} {:>6} {:>6} {:>6} {:>8.1} {:>6.1} | {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} {:>7.3} | {:>7} {:>5}",
            r.res,
            r.solver_res.map_or("-".into(), |v| v.to_string()),
            r.frames,
            r.steps,
            r.wall,
            (r.wall - covered).max(0.0),
            per(stage("build")),
            per(stage("contour")),
            per(stage("query")),
            per(group(&TRACKER)),
            per(stage("pressure")),
            per(stage("viscosity")),
            per(group(&SOLVER)),
            per(stage("write")),
            r.peak_mb.map_or("-".into(), |m| format!("{m:.0}")),
            r.cpu
                .map_or("-".into(), |c| format!("{:.0}%", 100.0 * c / r.wall.max(1e-9))),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn per_frame_groups_and_start_up() {
        let row = Row {
            res: 64,
            solver_res: Some(32),
            frames: 4.0,
            steps: 40,
            wall: 10.0,
            stages: vec![
                ("build".into(), 2.0),
                ("contour".into(), 1.0),
                ("query".into(), 1.0),
                ("pressure".into(), 2.0),
                ("viscosity".into(), 1.0),
                ("write".into(), 0.4),
            ],
            peak_mb: Some(123.4),
            cpu: Some(15.0),
        };
        let text = table(&[row]);
        let cells: Vec<&str> = text
            .lines()
            .nth(2)
            .expect("a row")
            .split_whitespace()
            .collect();
        // 10 s wall, 7.4 s in stages: 2.6 s start-up; stages over 4 frames; tracker = build +
        // contour + query = 4 s (1 s a frame), solver = pressure + viscosity = 3 s.
        assert_eq!(&cells[..6], ["64", "32", "4", "40", "10.0", "2.6"]);
        assert_eq!(
            &cells[7..15],
            ["0.500", "0.250", "0.250", "1.000", "0.500", "0.250", "0.750", "0.100"]
        );
        // 15 CPU seconds in 10 wall seconds: 150 %.
        assert_eq!(&cells[16..], ["123", "150%"]);
    }
}
