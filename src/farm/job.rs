//! A farmed job's description (`<folder>/slurm/job.json`): what each array task runs, written
//! by `polyphase submit` and read by the tasks themselves and by `polyphase status`; and the
//! record each task leaves when it ends (`task-K.json`).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::output::write_atomic;

/// The folder, inside the farmed folder, that holds the job's files.
pub const SLURM_DIR: &str = "slurm";

/// A job array: one task per variant, case or frame range.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Job {
    /// `wedge`, `validate` or `render`.
    pub kind: String,
    /// Slurm's job id, once submitted.
    pub job_id: Option<String>,
    pub tasks: Vec<Task>,
    /// A task run once every task of the array succeeded (a render's movie and plots); its
    /// index is `tasks.len()`.
    #[serde(default)]
    pub finish: Option<Task>,
    /// Slurm's job id of `finish`, once submitted.
    #[serde(default)]
    pub finish_id: Option<String>,
}

impl Job {
    /// Task `k`: one of the array's, or the finishing task at `k = tasks.len()`.
    pub fn task(&self, k: usize) -> Option<&Task> {
        self.tasks
            .get(k)
            .or(self.finish.as_ref().filter(|_| k == self.tasks.len()))
    }

    /// Every task, the finishing one last.
    pub fn all_tasks(&self) -> impl Iterator<Item = &Task> {
        self.tasks.iter().chain(self.finish.as_ref())
    }
}

/// One array task: a `polyphase` command line and what it is, for status tables.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Task {
    pub label: String,
    /// Arguments after the program name, e.g. `["run", "w/v-0/scene.toml", "--out", …]`.
    pub args: Vec<String>,
}

/// How a task ended, written atomically by the task when its command returns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskRecord {
    /// 0 when the command succeeded, 1 when it returned an error.
    pub exit: i32,
    /// The command's error, one line.
    pub error: Option<String>,
    pub seconds: f64,
}

/// The files of a farmed folder's job.
pub struct JobFiles {
    pub dir: PathBuf,
}

impl JobFiles {
    /// The job files of the farmed folder `root` (`root/slurm/`).
    pub fn of(root: &Path) -> JobFiles {
        JobFiles {
            dir: root.join(SLURM_DIR),
        }
    }

    pub fn job(&self) -> PathBuf {
        self.dir.join("job.json")
    }

    pub fn script(&self) -> PathBuf {
        self.dir.join("job.sbatch")
    }

    /// Task `k`'s stdout and stderr (Slurm's `--output`, `%a` being the array index).
    pub fn log(&self, k: usize) -> PathBuf {
        self.dir.join(format!("task-{k}.log"))
    }

    pub fn record(&self, k: usize) -> PathBuf {
        self.dir.join(format!("task-{k}.json"))
    }

    /// Reads `job.json`.
    pub fn read_job(&self) -> Result<Job> {
        let path = self.job();
        let text = fs::read_to_string(&path).with_context(|| {
            format!(
                "{} holds no farmed job (no {}; submit one with `polyphase submit`)",
                self.dir.parent().unwrap_or(&self.dir).display(),
                path.display()
            )
        })?;
        serde_json::from_str(&text).with_context(|| format!("{} is malformed", path.display()))
    }

    pub fn write_job(&self, job: &Job) -> Result<()> {
        fs::create_dir_all(&self.dir)
            .with_context(|| format!("cannot create {}", self.dir.display()))?;
        write_atomic(&self.job(), serde_json::to_string_pretty(job)?.as_bytes())
    }

    /// Task `k`'s record, `None` while it has not ended (or ended without writing one).
    pub fn read_record(&self, k: usize) -> Option<TaskRecord> {
        let text = fs::read_to_string(self.record(k)).ok()?;
        serde_json::from_str(&text).ok()
    }

    pub fn write_record(&self, k: usize, record: &TaskRecord) -> Result<()> {
        write_atomic(
            &self.record(k),
            serde_json::to_string_pretty(record)?.as_bytes(),
        )
    }

    /// The last line of task `k`'s log that reads as an error (else its last line).
    pub fn last_error_line(&self, k: usize) -> Option<String> {
        let text = fs::read_to_string(self.log(k)).ok()?;
        let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
        lines
            .iter()
            .rev()
            .find(|l| l.to_ascii_lowercase().contains("error"))
            .or(lines.last())
            .map(|l| l.trim().to_string())
    }
}
