//! Farming out independent runs on Slurm (issue 18): `polyphase submit` turns a wedge folder's
//! variants, the validation cases or a run folder's frames into one job array (one task each,
//! `<folder>/slurm/job.sbatch`), `polyphase status` shows what finished, failed or waits, and
//! each array task runs the hidden `polyphase task`, which runs the same command a local user
//! would (`run … --resume`, `validate CASE`, `render DIR --frames A-B`) into the same output
//! layout, and records how it ended. A task re-queued after a node failure resumes its run from
//! the last checkpoint. Polyphase grows no scheduler of its own.

mod job;
mod queue;
mod sbatch;

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand};

use crate::render::RenderArgs;
use crate::wedge::WedgeIndex;
use job::{Job, JobFiles, Task, TaskRecord};
use sbatch::SlurmOptions;

/// Arguments of `polyphase submit`.
#[derive(Args, Debug)]
pub struct SubmitArgs {
    #[command(subcommand)]
    what: SubmitWhat,
    #[command(flatten)]
    slurm: SlurmOptions,
}

/// What `polyphase submit` farms out.
#[derive(Subcommand, Debug)]
enum SubmitWhat {
    /// Every variant of a wedge folder (`polyphase wedge`), one task each, each run into
    /// `DIR/<variant>/run` as `polyphase run DIR/<variant>/scene.toml --out DIR/<variant>/run`
    /// would.
    Wedge {
        /// The wedge folder.
        dir: PathBuf,
    },
    /// Validation cases, one task each (default: every case in `validation/`), into the
    /// layout of `polyphase validate --out DIR`, plus `DIR/<case>.json`.
    Validate {
        /// Case names or case folders.
        cases: Vec<String>,
        /// The coarse versions.
        #[arg(long)]
        quick: bool,
        /// Folder for the cases' runs (default: out/validate).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Every frame of a run folder, `--per-task` frames a task, into `DIR/render/` as
    /// `polyphase render DIR` would; then one more job, once every frame rendered, makes the
    /// movie and plots from them (`polyphase render DIR --only-missing`).
    Render {
        #[command(flatten)]
        render: RenderArgs,
        /// Frames rendered by one task.
        #[arg(long, default_value_t = 8)]
        per_task: usize,
    },
}

/// Writes the job's script and description, submits it, and prints the job id.
pub fn submit(args: &SubmitArgs) -> Result<()> {
    args.slurm.check()?;
    let mut finish = None;
    let (kind, root, tasks) = match &args.what {
        SubmitWhat::Wedge { dir } => ("wedge", dir.clone(), wedge_tasks(dir)?),
        SubmitWhat::Validate { cases, quick, out } => {
            let out = out.clone().unwrap_or_else(|| PathBuf::from("out/validate"));
            fs::create_dir_all(&out)
                .with_context(|| format!("cannot create the output folder {}", out.display()))?;
            let tasks = validate_tasks(cases, *quick, &absolute(&out)?)?;
            ("validate", out, tasks)
        }
        SubmitWhat::Render { render, per_task } => {
            let tasks = render_tasks(render, *per_task)?;
            finish = finish_task(render)?;
            // The tasks would wait on each other to create the render environment: create it
            // here, once.
            crate::render::prepare(render)?;
            ("render", render.dir.clone(), tasks)
        }
    };
    sbatch::check_reachable()?;
    let root = absolute(&root)?;
    let files = JobFiles::of(&root);
    if let Ok(old) = files.read_job() {
        if let Some(id) = &old.job_id {
            let active = queue::task_states(id)
                .values()
                .filter(|s| is_active(s))
                .count();
            if active > 0 {
                bail!(
                    "{} has job {id} with {active} task(s) still queued or running; wait for it \
                     (`polyphase status {}`) or cancel it with `scancel {id}`",
                    root.display(),
                    root.display()
                );
            }
        }
    }
    let mut job = Job {
        kind: kind.to_string(),
        job_id: None,
        tasks,
        finish,
        finish_id: None,
    };
    fs::create_dir_all(&files.dir)
        .with_context(|| format!("cannot create {}", files.dir.display()))?;
    for k in 0..(job.tasks.len() + 1).max(old_task_count(&files)) {
        fs::remove_file(files.record(k)).ok();
        fs::remove_file(files.log(k)).ok();
    }
    files.write_job(&job)?;
    let program = std::env::current_exe().context("cannot find this program's path")?;
    let workdir = std::env::current_dir().context("cannot read the working directory")?;
    let shape = sbatch::Shape::Array(job.tasks.len());
    let text = sbatch::script(kind, shape, &files, &program, &workdir, &args.slurm);
    crate::output::write_atomic(&files.script(), text.as_bytes())?;
    let id = sbatch::submit(&files.script())?;
    job.job_id = Some(id.clone());
    files.write_job(&job)?;
    println!(
        "submitted job {id}: {} {kind} task(s); `polyphase status {}` shows their progress",
        job.tasks.len(),
        root.display()
    );
    if job.finish.is_some() {
        let shape = sbatch::Shape::After {
            index: job.tasks.len(),
            after: &id,
        };
        let name = format!("{kind}-finish");
        let text = sbatch::script(&name, shape, &files, &program, &workdir, &args.slurm);
        let path = files.dir.join("finish.sbatch");
        crate::output::write_atomic(&path, text.as_bytes())?;
        let finish_id = sbatch::submit(&path)?;
        println!("submitted job {finish_id}: the movie and plots, once job {id} succeeded");
        job.finish_id = Some(finish_id);
        files.write_job(&job)?;
    }
    Ok(())
}

/// The task that makes a farmed render's movie and plots from its frames (rendering any that
/// are missing), unless both are switched off.
fn finish_task(render: &RenderArgs) -> Result<Option<Task>> {
    if render.no_movie && render.no_plots {
        return Ok(None);
    }
    let mut task = render.clone();
    task.dir = absolute(&render.dir)?;
    task.only_missing = true;
    Ok(Some(Task {
        label: "movie and plots".into(),
        args: task.to_cli(),
    }))
}

/// The number of `task-K.*` files a previous job left (so a smaller job clears them all).
fn old_task_count(files: &JobFiles) -> usize {
    fs::read_dir(&files.dir)
        .map(|entries| {
            entries
                .flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    let k = name
                        .strip_prefix("task-")?
                        .split('.')
                        .next()?
                        .parse::<usize>();
                    k.ok().map(|k| k + 1)
                })
                .max()
                .unwrap_or(0)
        })
        .unwrap_or(0)
}

/// A path made absolute against the working directory (tasks run there too, but job files
/// should not depend on it).
fn absolute(path: &Path) -> Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("cannot resolve {}", path.display()))
}

/// One task per wedge variant: `run <scene> --out <variant>/run --resume`.
fn wedge_tasks(dir: &Path) -> Result<Vec<Task>> {
    let dir = absolute(dir)?;
    let index = WedgeIndex::read(&dir)?;
    Ok(index
        .variants
        .iter()
        .map(|v| Task {
            label: format!("{} {}", v.name, v.label(" ")),
            args: vec![
                "run".into(),
                v.scene_file(&dir).display().to_string(),
                "--out".into(),
                v.run_dir(&dir).display().to_string(),
                "--resume".into(),
            ],
        })
        .collect())
}

/// One task per validation case.
fn validate_tasks(names: &[String], quick: bool, out: &Path) -> Result<Vec<Task>> {
    let cases = crate::validate::load_cases(names)?;
    Ok(cases
        .iter()
        .map(|case| {
            let mut args = vec![
                "validate".to_string(),
                absolute(&case.dir)
                    .unwrap_or_else(|_| case.dir.clone())
                    .display()
                    .to_string(),
                "--out".into(),
                out.display().to_string(),
                "--json".into(),
                out.join(format!("{}.json", case.name))
                    .display()
                    .to_string(),
            ];
            if quick {
                args.push("--quick".into());
            }
            Task {
                label: case.name.clone(),
                args,
            }
        })
        .collect())
}

/// One task per `per_task` consecutive frames on disk.
fn render_tasks(render: &RenderArgs, per_task: usize) -> Result<Vec<Task>> {
    if per_task == 0 {
        bail!("--per-task must be at least 1");
    }
    if render.frames != "all" {
        bail!(
            "--frames {}: `submit render` renders every frame; render a selection locally with \
             `polyphase render`",
            render.frames
        );
    }
    let dir = absolute(&render.dir)?;
    let frames = crate::render::frames_on_disk(&dir)?;
    Ok(frames
        .chunks(per_task)
        .map(|chunk| {
            let range = format!("{}-{}", chunk[0], chunk[chunk.len() - 1]);
            let mut task = render.clone();
            task.dir = dir.clone();
            task.frames = range.clone();
            task.no_movie = true;
            task.no_plots = true;
            Task {
                label: format!("frames {range}"),
                args: task.to_cli(),
            }
        })
        .collect())
}

/// Runs task `k` of the job in `slurm_dir` (the hidden `polyphase task`, what each array task
/// executes) with `run`, which runs a `polyphase` command line, and records how it ended.
pub fn task(slurm_dir: &Path, k: usize, run: impl FnOnce(&[String]) -> Result<()>) -> Result<()> {
    let files = JobFiles {
        dir: slurm_dir.to_path_buf(),
    };
    let job = files.read_job()?;
    let task = job
        .task(k)
        .with_context(|| format!("the job has no task {k}"))?;
    fs::remove_file(files.record(k)).ok();
    eprintln!("task {k}: polyphase {}", task.args.join(" "));
    let start = Instant::now();
    let result = run(&task.args);
    let record = TaskRecord {
        exit: i32::from(result.is_err()),
        error: result.as_ref().err().map(|e| {
            e.chain()
                .map(|c| c.to_string())
                .collect::<Vec<_>>()
                .join(": ")
        }),
        seconds: start.elapsed().as_secs_f64(),
    };
    files.write_record(k, &record)?;
    result
}

/// Arguments of `polyphase status`.
#[derive(Args, Debug)]
pub struct StatusArgs {
    /// A folder given to `polyphase submit` (wedge folder, validation output, run folder).
    pub dir: PathBuf,
    /// Wait until no task is queued or running, then show the table.
    #[arg(long)]
    pub wait: bool,
    /// With `--wait`: give up after this many seconds (the table is shown, and the command
    /// fails), e.g. for a task that a partition that is down will never start.
    #[arg(long, value_name = "SECONDS", requires = "wait")]
    pub timeout: Option<f64>,
}

/// Prints every task's state; fails when a task failed or was lost.
pub fn status(args: &StatusArgs) -> Result<()> {
    let files = JobFiles::of(&args.dir);
    let job = files.read_job()?;
    if let Some(t) = args.timeout {
        if !(t.is_finite() && t >= 0.0) {
            bail!("--timeout {t}: expected a number of seconds, at least 0");
        }
    }
    let start = Instant::now();
    let (rows, busy) = loop {
        let rows = task_rows(&job, &files);
        let busy = rows
            .iter()
            .any(|r| matches!(r.state, State::Pending | State::Running));
        let out_of_time = args
            .timeout
            .is_some_and(|t| start.elapsed().as_secs_f64() >= t);
        if !(args.wait && busy) || out_of_time {
            break (rows, busy);
        }
        std::thread::sleep(Duration::from_secs(2));
    };
    print!("{}", table(&job, &rows));
    if args.wait && busy {
        bail!(
            "tasks still queued or running after {} s (--timeout)",
            args.timeout.unwrap_or(0.0)
        );
    }
    let bad = rows.iter().filter(|r| r.state == State::Failed).count();
    if bad > 0 {
        bail!("{bad} of {} task(s) failed", rows.len());
    }
    Ok(())
}

/// A task's state as `polyphase status` shows it.
#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    Done,
    Failed,
    Running,
    Pending,
    NotSubmitted,
}

/// One row of the status table.
struct Row {
    state: State,
    detail: String,
}

/// Slurm states of a task that is not over yet.
fn is_active(state: &str) -> bool {
    matches!(
        state,
        "PENDING" | "CONFIGURING" | "REQUEUED" | "REQUEUE_HOLD" | "RESIZING" | "SUSPENDED"
    ) || matches!(state, "RUNNING" | "COMPLETING" | "STAGE_OUT")
}

/// Each task's state, the finishing task last.
fn task_rows(job: &Job, files: &JobFiles) -> Vec<Row> {
    let slurm = job
        .job_id
        .as_deref()
        .map(queue::task_states)
        .unwrap_or_default();
    let mut rows: Vec<Row> = (0..job.tasks.len())
        .map(|k| {
            row(
                files,
                k,
                slurm.get(&k).map(String::as_str),
                job.job_id.is_some(),
            )
        })
        .collect();
    if job.finish.is_some() {
        let state = job.finish_id.as_deref().and_then(queue::job_state);
        let k = job.tasks.len();
        rows.push(row(files, k, state.as_deref(), job.finish_id.is_some()));
    }
    rows
}

/// Task `k`'s state: Slurm's while it is queued or running, else its record, else Slurm's end
/// state (a task killed with its node leaves no record), else lost.
fn row(files: &JobFiles, k: usize, slurm: Option<&str>, submitted: bool) -> Row {
    let last_line = || files.last_error_line(k).unwrap_or_default();
    match (slurm, files.read_record(k)) {
        (Some(s), _) if is_active(s) => Row {
            state: if s == "RUNNING" || s == "COMPLETING" {
                State::Running
            } else {
                State::Pending
            },
            detail: s.to_ascii_lowercase(),
        },
        (_, Some(r)) if r.exit == 0 => Row {
            state: State::Done,
            detail: format!("{:.1} s", r.seconds),
        },
        (_, Some(r)) => Row {
            state: State::Failed,
            detail: r.error.unwrap_or_else(last_line),
        },
        (Some(s), None) => Row {
            state: State::Failed,
            detail: format!("{s} without a record: {}", last_line()),
        },
        (None, None) if !submitted => Row {
            state: State::NotSubmitted,
            detail: String::new(),
        },
        (None, None) => Row {
            state: State::Failed,
            detail: format!("lost (not queued, no record): {}", last_line()),
        },
    }
}

/// The status table.
fn table(job: &Job, rows: &[Row]) -> String {
    let count = |s: State| rows.iter().filter(|r| r.state == s).count();
    let mut out = format!(
        "job {} ({}, {} tasks): {} done, {} failed, {} running, {} pending\n",
        job.job_id.as_deref().unwrap_or("not submitted"),
        job.kind,
        rows.len(),
        count(State::Done),
        count(State::Failed),
        count(State::Running),
        count(State::Pending),
    );
    let width = job.all_tasks().map(|t| t.label.len()).max().unwrap_or(4);
    let _ = writeln!(
        out,
        "{:<5} {:<8} {:<width$}  detail",
        "task", "state", "what"
    );
    for (k, (task, row)) in job.all_tasks().zip(rows).enumerate() {
        let state = match row.state {
            State::Done => "done",
            State::Failed => "failed",
            State::Running => "running",
            State::Pending => "pending",
            State::NotSubmitted => "-",
        };
        let _ = writeln!(
            out,
            "{k:<5} {state:<8} {:<width$}  {}",
            task.label, row.detail
        );
    }
    out
}
