//! The sbatch script of a job array, and its submission.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};

use super::job::JobFiles;

/// Scheduling options of `polyphase submit`, passed to Slurm.
#[derive(clap::Args, Debug, Clone)]
pub struct SlurmOptions {
    /// Slurm partition (default: the cluster's default partition).
    #[arg(long, global = true)]
    pub partition: Option<String>,
    /// Time limit of each task, `HH:MM:SS` or `D-HH:MM:SS` (default: the partition's).
    #[arg(long, global = true)]
    pub time: Option<String>,
    /// CPUs per task; the task's worker threads follow it.
    #[arg(long, global = true, default_value_t = 1)]
    pub cpus: usize,
}

impl SlurmOptions {
    /// Checks the options before anything is written.
    pub fn check(&self) -> Result<()> {
        if self.cpus == 0 {
            bail!("--cpus must be at least 1");
        }
        if let Some(t) = &self.time {
            if !is_slurm_time(t) {
                bail!("--time {t}: expected HH:MM:SS or D-HH:MM:SS, e.g. 02:00:00");
            }
        }
        if let Some(p) = &self.partition {
            if p.is_empty()
                || !p
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c))
            {
                bail!("--partition '{p}': a partition name is letters, digits, '-', '_' or '.'");
            }
        }
        Ok(())
    }
}

/// `HH:MM:SS` or `D-HH:MM:SS` with minutes and seconds below 60.
fn is_slurm_time(t: &str) -> bool {
    let (days, hms) = match t.split_once('-') {
        Some((d, rest)) => (Some(d), rest),
        None => (None, t),
    };
    let num = |s: &str| !s.is_empty() && s.len() <= 3 && s.bytes().all(|b| b.is_ascii_digit());
    let parts: Vec<&str> = hms.split(':').collect();
    days.is_none_or(num)
        && parts.len() == 3
        && parts.iter().all(|p| num(p))
        && parts[1].parse::<u32>().is_ok_and(|m| m < 60)
        && parts[2].parse::<u32>().is_ok_and(|s| s < 60)
}

/// A single-quoted shell word.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// What one sbatch script runs: the tasks of an array, or one task after another job.
pub enum Shape<'a> {
    /// Tasks `0..n`, task `$SLURM_ARRAY_TASK_ID` each.
    Array(usize),
    /// Task `index` alone, once job `after` has ended with every task successful (cancelled
    /// by Slurm when that can no longer happen).
    After { index: usize, after: &'a str },
}

/// The script of a job: each task runs `polyphase task <slurm dir> K`, and is re-queued after
/// a node failure (a re-queued run resumes from its checkpoint).
pub fn script(
    name: &str,
    shape: Shape,
    files: &JobFiles,
    program: &Path,
    workdir: &Path,
    opts: &SlurmOptions,
) -> String {
    let dir = files.dir.display().to_string();
    let (head, index) = match shape {
        Shape::Array(n) => (
            format!(
                "#SBATCH --array=0-{}\n#SBATCH --output={dir}/task-%a.log\n",
                n - 1
            ),
            "\"$SLURM_ARRAY_TASK_ID\"".to_string(),
        ),
        Shape::After { index, after } => (
            format!(
                "#SBATCH --dependency=afterok:{after}\n#SBATCH --kill-on-invalid-dep=yes\n\
                 #SBATCH --output={}\n",
                files.log(index).display()
            ),
            index.to_string(),
        ),
    };
    let mut s = format!(
        "#!/bin/bash\n\
         # Written by `polyphase submit`; `polyphase status` reads its progress.\n\
         #SBATCH --job-name=polyphase-{name}\n\
         {head}\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --requeue\n\
         #SBATCH --chdir={workdir}\n",
        cpus = opts.cpus,
        workdir = workdir.display(),
    );
    if let Some(p) = &opts.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &opts.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s += &format!(
        "export RAYON_NUM_THREADS=\"${{SLURM_CPUS_PER_TASK:-{cpus}}}\"\n\
         exec {program} task {dir} {index}\n",
        cpus = opts.cpus,
        program = quote(&program.display().to_string()),
        dir = quote(&dir),
    );
    s
}

/// Fails with Slurm's own last line unless its controller answers (`squeue`), so a job is
/// never half prepared for a cluster that cannot take it.
pub fn check_reachable() -> Result<()> {
    let out = Command::new("squeue")
        .args(["-h", "-o", "%i"])
        .output()
        .context("cannot run squeue (is Slurm installed and this a submit host?)")?;
    if !out.status.success() {
        bail!("Slurm does not answer: {}", last_line(&out.stderr));
    }
    Ok(())
}

/// The last non-empty line of a command's output.
fn last_line(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    text.lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("")
        .trim()
        .to_string()
}

/// Submits the script with `sbatch --parsable`; returns the job id.
pub fn submit(script: &Path) -> Result<String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .arg(script)
        .output()
        .context("cannot run sbatch (is Slurm installed and this a submit host?)")?;
    if !out.status.success() {
        bail!(
            "sbatch refused {}: {}",
            script.display(),
            last_line(&out.stderr)
        );
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        bail!("sbatch printed no job id: '{}'", text.trim());
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_times() {
        for ok in ["00:30:00", "2-12:00:00", "100:00:00"] {
            assert!(is_slurm_time(ok), "{ok}");
        }
        for bad in ["30", "1:60:00", "00:00:60", "a-01:00:00", "01:00", ""] {
            assert!(!is_slurm_time(bad), "{bad}");
        }
    }

    #[test]
    fn script_quotes_paths_and_sets_the_array() {
        let files = JobFiles {
            dir: "/w/it's/slurm".into(),
        };
        let opts = SlurmOptions {
            partition: Some("gpu".into()),
            time: None,
            cpus: 2,
        };
        let s = script(
            "wedge",
            Shape::Array(3),
            &files,
            Path::new("/bin/polyphase"),
            Path::new("/w"),
            &opts,
        );
        assert!(s.contains("#SBATCH --array=0-2\n"));
        assert!(s.contains("#SBATCH --partition=gpu\n"));
        assert!(!s.contains("--time"));
        assert!(
            s.contains("exec '/bin/polyphase' task '/w/it'\\''s/slurm' \"$SLURM_ARRAY_TASK_ID\"")
        );
        let s = script(
            "render-finish",
            Shape::After {
                index: 3,
                after: "41",
            },
            &files,
            Path::new("/bin/polyphase"),
            Path::new("/w"),
            &opts,
        );
        assert!(s.contains("#SBATCH --dependency=afterok:41\n"));
        assert!(!s.contains("--array"));
        assert!(s.contains("#SBATCH --output=/w/it's/slurm/task-3.log\n"));
        assert!(s.contains("task '/w/it'\\''s/slurm' 3\n"));
    }
}
