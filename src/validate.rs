//! `polyphase validate [CASE…] [--quick] [--json FILE]`: physics regression against published
//! data and analytic solutions. Each case is a folder (`validation/<case>/`, or any folder
//! with a `case.toml`) naming a scene, the reference's source and the metrics with their
//! tolerances; the run goes to `out/validate/<case>/` like any `polyphase run`, the metrics
//! are read off its `stats.jsonl`, and any failed metric makes the exit status non-zero.

mod capillary;
mod case;
mod extremum;
mod indicator;
mod layered_flow;
mod metrics;
mod plot;
mod surge_front;

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use polyphase_scenes::{Scene, TrackerKind};
use serde_json::{json, Value};

use crate::run::{self, RunOptions};
use case::Case;
use metrics::{evaluate, Outcome};

/// Arguments of `polyphase validate`.
#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Case names (folders of `validation/`) or paths to case folders; default: every case in
    /// `validation/`.
    pub cases: Vec<String>,
    /// Run the coarse version of each case (its `quick_resolution`), as the test suite does.
    #[arg(long)]
    pub quick: bool,
    /// Also write the results as JSON to FILE.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Folder for the cases' runs (default: out/validate).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// The folder of the shipped cases: `validation/` under the working directory, else the one
/// in the source tree this program was built from.
fn cases_dir() -> PathBuf {
    let here = PathBuf::from("validation");
    if here.is_dir() {
        here
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("validation")
    }
}

/// Every case folder under `dir`, sorted by name.
fn all_cases(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut found: Vec<PathBuf> = fs::read_dir(dir)
        .with_context(|| format!("cannot read the cases folder {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("case.toml").is_file())
        .collect();
    found.sort();
    Ok(found)
}

/// The folder of one case argument: a path to a case folder, or a name under `dir`.
fn find_case(arg: &str, dir: &Path) -> Result<PathBuf> {
    let path = PathBuf::from(arg);
    if path.join("case.toml").is_file() {
        return Ok(path);
    }
    let named = dir.join(arg);
    if named.join("case.toml").is_file() {
        return Ok(named);
    }
    let names: Vec<String> = all_cases(dir)?
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    bail!(
        "unknown validation case '{arg}' (no {}/case.toml; cases: {})",
        arg,
        names.join(", ")
    )
}

/// The cases named on the command line (names under `validation/` or case folders), loaded;
/// every shipped case when none is named.
pub(crate) fn load_cases(names: &[String]) -> Result<Vec<Case>> {
    let dir = cases_dir();
    let folders = if names.is_empty() {
        all_cases(&dir)?
    } else {
        names
            .iter()
            .map(|c| find_case(c, &dir))
            .collect::<Result<_>>()?
    };
    folders.iter().map(|f| Case::load(f)).collect()
}

/// One case's run and results; a case that cannot run is one failed row with the reason.
struct CaseResult {
    case: Case,
    outcomes: Result<Vec<Outcome>>,
}

/// Runs the cases, prints the table, writes the JSON, and fails if any metric failed.
pub fn validate(args: &ValidateArgs) -> Result<()> {
    let cases = load_cases(&args.cases)?;
    // A JSON file that cannot be written is refused before any case runs.
    if let Some(json) = &args.json {
        let parent = json
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        anyhow::ensure!(
            parent.is_dir(),
            "--json {}: the folder {} does not exist",
            json.display(),
            parent.display()
        );
    }
    let out_root = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join("validate"));
    let mut results = Vec::new();
    for case in cases {
        let suffix = if args.quick { "-quick" } else { "" };
        let out = out_root.join(format!("{}{suffix}", case.name));
        eprintln!("validate: {} ({})", case.name, case.file.description);
        let outcomes = run_case(&case, &out, args.quick);
        results.push(CaseResult { case, outcomes });
    }
    print!("{}", table(&results));
    if let Some(path) = &args.json {
        let text = serde_json::to_string_pretty(&to_json(&results))?;
        crate::output::write_atomic(path, text.as_bytes())?;
    }
    let failed: Vec<String> = results
        .iter()
        .flat_map(|r| match &r.outcomes {
            Ok(list) => list
                .iter()
                .filter(|o| o.verdict().1)
                .map(|o| format!("{}: {}", r.case.name, o.metric))
                .collect(),
            Err(_) => vec![format!("{}: did not run", r.case.name)],
        })
        .collect();
    if failed.is_empty() {
        Ok(())
    } else {
        bail!("{} failed: {}", failed.len(), failed.join(", "))
    }
}

/// Runs one case into `out` and evaluates its metrics. A case whose metrics all need no run
/// (the first-step kinds) only builds its tracker.
fn run_case(case: &Case, out: &Path, quick: bool) -> Result<Vec<Outcome>> {
    let resolution = match quick {
        true => case.file.quick_resolution.or(case.file.resolution),
        false => case.file.resolution,
    };
    let metrics = &case.file.metrics;
    let label = |m: &case::MetricSpec| format!("case '{}', metric '{}'", case.name, m.name);
    if metrics.iter().all(|m| indicator::is_static(&m.kind)) {
        if case.file.tracker == Some(TrackerKind::Front) {
            bail!(
                "case '{}': first-step metrics measure the contouring tracker (paper 004 \
                 Table 2), not tracker = \"front\"",
                case.name
            );
        }
        let scene = polyphase_scenes::load(&case.scene_arg())?.with_overrides(resolution, None)?;
        let samples = metrics.iter().find_map(|m| m.samples);
        let first = indicator::FirstStep::measure(&scene, samples);
        return metrics
            .iter()
            .map(|m| first.evaluate(m, quick).with_context(|| label(m)))
            .collect();
    }
    if let Some(m) = metrics.iter().find(|m| indicator::is_static(&m.kind)) {
        bail!(
            "{}: first-step metrics need a case of their own (they run no scene)",
            label(m)
        );
    }
    let root = run::run(&RunOptions {
        scene: case.scene_arg(),
        out: Some(out.to_path_buf()),
        resolution,
        frames: None,
        tracker: case.file.tracker,
        resume: false,
    })
    .with_context(|| format!("case '{}'", case.name))?;
    let resolved = root.join("scene.toml");
    let text = fs::read_to_string(&resolved)?;
    let scene = Scene::parse(&text, &resolved.display().to_string())?;
    let stats = fs::read_to_string(root.join("stats.jsonl"))?;
    let frames: Vec<Value> = stats
        .lines()
        .map(serde_json::from_str::<Value>)
        .filter(|v| v.as_ref().map_or(true, |v| v.get("time").is_some()))
        .collect::<Result<_, _>>()?;
    let outcomes: Vec<Outcome> = metrics
        .iter()
        .map(|m| evaluate(m, &frames, &scene, &case.dir, quick).with_context(|| label(m)))
        .collect::<Result<_>>()?;
    write_plots(&outcomes, &root.join("plots"))?;
    Ok(outcomes)
}

/// Each metric's plot as `DIR/<metric>.svg` (the name's letters and digits, `_` for the rest).
fn write_plots(outcomes: &[Outcome], dir: &Path) -> Result<()> {
    for o in outcomes {
        let Some(svg) = o.plot.as_ref().and_then(|p| p.svg()) else {
            continue;
        };
        fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        let name: String = o
            .metric
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        crate::output::write_atomic(&dir.join(format!("{name}.svg")), svg.as_bytes())?;
    }
    Ok(())
}

fn table(results: &[CaseResult]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<18} {:<28} {:>12} {:>12} {:>10} {:>10}  result",
        "case", "metric", "ours", "reference", "error", "tolerance"
    );
    for r in results {
        match &r.outcomes {
            Ok(list) => {
                for o in list {
                    let _ = writeln!(
                        s,
                        "{:<18} {:<28} {:>12.5e} {:>12.5e} {:>10.3e} {:>10.3e}  {}",
                        r.case.name,
                        o.metric,
                        o.ours,
                        o.reference,
                        o.error,
                        o.tolerance,
                        o.verdict().0
                    );
                    for said in [&o.note, &o.known_gap].into_iter().flatten() {
                        let _ = writeln!(s, "{:<18} ({said})", "");
                    }
                }
            }
            Err(e) => {
                let _ = writeln!(s, "{:<18} did not run: {e:#}", r.case.name);
            }
        }
    }
    s
}

fn to_json(results: &[CaseResult]) -> Value {
    let rows: Vec<Value> = results
        .iter()
        .flat_map(|r| match &r.outcomes {
            Ok(list) => list
                .iter()
                .map(|o| {
                    json!({
                        "case": r.case.name,
                        "description": r.case.file.description,
                        "source": r.case.file.source,
                        "metric": o.metric,
                        "ours": o.ours,
                        "reference": o.reference,
                        "error": o.error,
                        "tolerance": o.tolerance,
                        "pass": o.pass,
                        "note": o.note,
                        "known_gap": o.known_gap,
                        "verdict": o.verdict().0,
                    })
                })
                .collect::<Vec<_>>(),
            Err(e) => vec![json!({
                "case": r.case.name,
                "source": r.case.file.source,
                "error": format!("{e:#}"),
                "pass": false,
            })],
        })
        .collect();
    json!(rows)
}
