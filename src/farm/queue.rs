//! What Slurm says about a job's tasks: `squeue` for the queued and running ones, `sacct` for
//! the ended ones where the cluster keeps accounting (many small clusters do not).

use std::collections::BTreeMap;
use std::process::Command;

/// Slurm's state of each task still known to it, by array index (`PENDING`, `RUNNING`,
/// `COMPLETED`, `FAILED`, `TIMEOUT`, `NODE_FAIL`, …). Tasks Slurm no longer knows are absent.
pub fn task_states(job_id: &str) -> BTreeMap<usize, String> {
    let mut states = BTreeMap::new();
    // sacct first: squeue's view of the queued and running tasks is the fresher one.
    if let Some(text) = run(
        "sacct",
        &["-n", "-P", "-X", "-j", job_id, "-o", "JobID,State"],
    ) {
        states.extend(parse(&text, job_id));
    }
    if let Some(text) = run("squeue", &["-h", "-r", "-j", job_id, "-o", "%i|%T"]) {
        states.extend(parse(&text, job_id));
    }
    states
}

/// Slurm's state of a job that is not an array, while Slurm knows it.
pub fn job_state(job_id: &str) -> Option<String> {
    let mut state = None;
    let queries = [
        (
            "sacct",
            vec!["-n", "-P", "-X", "-j", job_id, "-o", "JobID,State"],
        ),
        ("squeue", vec!["-h", "-j", job_id, "-o", "%i|%T"]),
    ];
    for (program, args) in queries {
        let found = run(program, &args).and_then(|text| {
            text.lines().find_map(|l| {
                let (id, s) = l.split_once('|')?;
                (id.trim() == job_id).then(|| s.split_whitespace().next().unwrap_or("").to_string())
            })
        });
        state = found.or(state);
    }
    state
}

/// Stdout of a command that succeeded, else `None` (not installed, accounting disabled,
/// or the job has left the queue).
fn run(program: &str, args: &[&str]) -> Option<String> {
    let out = Command::new(program).args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Lines `JOBID_K|STATE` of this job (a pending array's `JOBID_[0-4]` line names a range).
fn parse(text: &str, job_id: &str) -> BTreeMap<usize, String> {
    let mut states = BTreeMap::new();
    for line in text.lines() {
        let Some((id, state)) = line.split_once('|') else {
            continue;
        };
        let Some(index) = id
            .trim()
            .strip_prefix(job_id)
            .and_then(|r| r.strip_prefix('_'))
        else {
            continue;
        };
        // sacct writes "CANCELLED by 0"; the first word is the state.
        let state = state.split_whitespace().next().unwrap_or("").to_string();
        for k in indices(index) {
            states.insert(k, state.clone());
        }
    }
    states
}

/// `3` → [3]; `[0-4,7]` or `[0-4%2]` → 0..=4, 7.
fn indices(spec: &str) -> Vec<usize> {
    let spec = spec.trim_start_matches('[').trim_end_matches(']');
    let spec = spec.split('%').next().unwrap_or("");
    let mut out = Vec::new();
    for part in spec.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                if let (Ok(a), Ok(b)) = (a.parse::<usize>(), b.parse::<usize>()) {
                    out.extend(a..=b);
                }
            }
            None => out.extend(part.parse::<usize>().ok()),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_lines_and_ranges() {
        let text = "12_[3-5%2]|PENDING\n12_1|RUNNING\n12_0|CANCELLED by 0\n120_1|RUNNING\n";
        let s = parse(text, "12");
        assert_eq!(s.get(&0).map(String::as_str), Some("CANCELLED"));
        assert_eq!(s.get(&1).map(String::as_str), Some("RUNNING"));
        assert_eq!(
            (3..=5).map(|k| s.get(&k).cloned()).collect::<Vec<_>>(),
            vec![Some("PENDING".to_string()); 3]
        );
        assert_eq!(s.len(), 5, "job 120 is another job");
    }
}
