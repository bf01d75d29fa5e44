//! Farming on a real Slurm cluster: a single-node cluster (munged, slurmctld, slurmd) started
//! on this machine runs a 3-variant wedge and a 4-frame render as job arrays, and every output
//! must be byte-identical to the same commands run locally. `.ci/run` installs Debian's
//! `slurm-wlm` and `munge`; the test is skipped, with the reason, only where the daemons
//! cannot start (not root, packages missing).

mod common;

use std::fs;
use std::io::Read;
use std::net::TcpListener;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};

use common::scratch;

/// A single-node Slurm cluster whose files all live in one folder; stopped on drop.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
}

/// Daemons in start order; stopped in reverse.
const DAEMONS: [&str; 3] = ["munged", "slurmctld", "slurmd"];

impl Cluster {
    /// Starts munged, slurmctld and slurmd with a private key, state and ports, and waits
    /// until the node is idle; `Err` says why it could not.
    fn start(dir: &Path) -> Result<Cluster, String> {
        if !Command::new("id")
            .arg("-u")
            .output()
            .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        {
            return Err("slurmd needs root to launch jobs, and this test is not root".into());
        }
        for program in ["munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo"] {
            if !Command::new("sh")
                .args(["-c", &format!("command -v {program}")])
                .output()
                .is_ok_and(|o| o.status.success())
            {
                return Err(format!(
                    "{program} not found (Debian: apt-get install slurm-wlm munge; .ci/run does)"
                ));
            }
        }
        let host = Command::new("hostname")
            .arg("-s")
            .output()
            .map_err(|e| format!("hostname: {e}"))?;
        let host = String::from_utf8_lossy(&host.stdout).trim().to_string();
        for sub in ["state", "spool", "log"] {
            fs::create_dir_all(dir.join(sub)).map_err(|e| e.to_string())?;
        }
        let key = dir.join("munge.key");
        let mut bytes = vec![0u8; 1024];
        fs::File::open("/dev/urandom")
            .and_then(|mut f| f.read_exact(&mut bytes))
            .map_err(|e| e.to_string())?;
        fs::write(&key, &bytes).map_err(|e| e.to_string())?;
        fs::set_permissions(&key, fs::Permissions::from_mode(0o600)).map_err(|e| e.to_string())?;
        let d = dir.display();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let (ctld_port, slurmd_port) = (free_port()?, free_port()?);
        let conf = dir.join("slurm.conf");
        let text = format!(
            "ClusterName=polyphasetest\nSlurmctldHost={host}\nSlurmUser=root\nSlurmdUser=root\n\
             AuthType=auth/munge\nAuthInfo=socket={d}/munge.sock\nCredType=cred/munge\n\
             StateSaveLocation={d}/state\nSlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\nSlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldPort={ctld_port}\nSlurmdPort={slurmd_port}\n\
             SlurmctldLogFile={d}/log/slurmctld.log\nSlurmdLogFile={d}/log/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n\
             JobAcctGatherType=jobacct_gather/none\nAccountingStorageType=accounting_storage/none\n\
             SwitchType=switch/none\nMpiDefault=none\nSchedulerType=sched/backfill\n\
             SelectType=select/cons_tres\nSelectTypeParameters=CR_Core\nReturnToService=2\n\
             NodeName={host} CPUs={cpus} State=UNKNOWN\n\
             PartitionName=local Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n"
        );
        fs::write(&conf, text).map_err(|e| e.to_string())?;
        let cluster = Cluster {
            dir: dir.to_path_buf(),
            conf,
        };
        let c = cluster.conf.display().to_string();
        let starts: [Vec<String>; 3] = [
            vec![
                "--force".into(),
                format!("--key-file={}", key.display()),
                format!("--socket={d}/munge.sock"),
                format!("--pid-file={d}/munged.pid"),
                format!("--log-file={d}/log/munged.log"),
                format!("--seed-file={d}/munge.seed"),
            ],
            vec!["-c".into(), "-f".into(), c.clone()],
            vec!["-f".into(), c],
        ];
        for (daemon, args) in DAEMONS.iter().zip(starts) {
            let status = Command::new(daemon)
                .args(&args)
                .env("SLURM_CONF", &cluster.conf)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .map_err(|e| format!("{daemon}: {e}"))?;
            if !status.success() {
                return Err(format!("{daemon} did not start: {}", cluster.logs()));
            }
        }
        let deadline = Instant::now() + Duration::from_secs(60);
        while Instant::now() < deadline {
            let o = cluster.command("sinfo", &["-h", "-o", "%T"]);
            if String::from_utf8_lossy(&o.stdout).trim() == "idle" {
                return Ok(cluster);
            }
            sleep(Duration::from_millis(250));
        }
        Err(format!("the node never became idle: {}", cluster.logs()))
    }

    /// A command with this cluster's configuration.
    fn command(&self, program: &str, args: &[&str]) -> Output {
        Command::new(program)
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .output()
            .expect("the command runs")
    }

    /// `polyphase` with this cluster's configuration, from `cwd`; must succeed.
    fn polyphase(&self, cwd: &Path, args: &[&str]) -> String {
        let o = Command::new(env!("CARGO_BIN_EXE_polyphase"))
            .args(args)
            .current_dir(cwd)
            .env("SLURM_CONF", &self.conf)
            .output()
            .expect("polyphase runs");
        assert!(
            o.status.success(),
            "polyphase {args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    }

    /// `polyphase` with this cluster's configuration, whatever its exit status.
    fn command_polyphase(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_polyphase"))
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .output()
            .expect("polyphase runs")
    }

    /// `polyphase status DIR --wait`, killed (and the test failed) after `limit`.
    fn wait(&self, dir: &Path, limit: Duration) -> Output {
        let mut child = Command::new(env!("CARGO_BIN_EXE_polyphase"))
            .args(["status", dir.to_str().expect("UTF-8"), "--wait"])
            .env("SLURM_CONF", &self.conf)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("polyphase status runs");
        let start = Instant::now();
        while child.try_wait().expect("status").is_none() {
            if start.elapsed() > limit {
                child.kill().ok();
                let q = self.command("squeue", &[]);
                panic!(
                    "the job did not end within {limit:?}; squeue:\n{}\n{}",
                    String::from_utf8_lossy(&q.stdout),
                    self.logs()
                );
            }
            sleep(Duration::from_millis(200));
        }
        child.wait_with_output().expect("status output")
    }

    /// The daemons' log tails, for failure messages.
    fn logs(&self) -> String {
        DAEMONS
            .iter()
            .map(|d| {
                let text =
                    fs::read_to_string(self.dir.join(format!("log/{d}.log"))).unwrap_or_default();
                let tail: Vec<&str> = text.lines().rev().take(5).collect();
                format!(
                    "{d}: {}",
                    tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for d in DAEMONS.iter().rev() {
            if let Ok(pid) = fs::read_to_string(self.dir.join(format!("{d}.pid"))) {
                let _ = Command::new("kill").arg(pid.trim()).status();
            }
        }
    }
}

/// A TCP port nothing listens on now.
fn free_port() -> Result<u16, String> {
    let l = TcpListener::bind("127.0.0.1:0").map_err(|e| e.to_string())?;
    l.local_addr().map(|a| a.port()).map_err(|e| e.to_string())
}

/// Every file under `dir/sub` with the given extension, as (name, bytes), sorted.
fn files(dir: &Path, sub: &str, ext: &str) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = fs::read_dir(dir.join(sub))
        .map(|entries| {
            entries
                .flatten()
                .filter(|e| e.path().extension().is_some_and(|x| x == ext))
                .map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    (name, fs::read(e.path()).expect("readable"))
                })
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

/// Asserts `a/sub/*.ext` and `b/sub/*.ext` are the same non-empty set of identical files.
fn assert_same_files(a: &Path, b: &Path, sub: &str, ext: &str, count: usize) {
    let (x, y) = (files(a, sub, ext), files(b, sub, ext));
    assert_eq!(x.len(), count, "{}/{sub}: *.{ext}", a.display());
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&x), names(&y), "{} vs {}", a.display(), b.display());
    for (f, g) in x.iter().zip(&y) {
        assert!(
            f.1 == g.1,
            "{}/{sub}/{} differs from the local run's",
            a.display(),
            f.0
        );
    }
}

/// The `n` EXR frames of two render folders, read with Mitsuba's own reader: equal to float32
/// summation order. Mitsuba adds the filter's overlap between image blocks in the order its
/// threads finish them, so two renders of one frame differ in the last bits, locally too
/// (measured: 1 of these 4 frames differed between two local renders, while every PNG was
/// identical). Float32 sums of a handful of terms differ by a few 1e-7 relative; 1e-5 of the
/// brightest pixel leaves margin and still catches any real change of the image.
fn assert_close_exr(a: &Path, b: &Path, n: usize) {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("render/.venv/bin/python");
    let script = "import sys, numpy as np, mitsuba as mi\n\
                  mi.set_variant('scalar_rgb')\n\
                  a, b = (np.array(mi.Bitmap(p), dtype=np.float64) for p in sys.argv[1:3])\n\
                  print(a.shape == b.shape, np.abs(a - b).max() / max(np.abs(a).max(), 1e-30))\n";
    for k in 0..n {
        let (x, y) = (a.join(format!("{k:04}.exr")), b.join(format!("{k:04}.exr")));
        let o = Command::new(&python)
            .args(["-c", script])
            .args([&x, &y])
            .output()
            .expect("the render environment's python runs");
        let text = String::from_utf8_lossy(&o.stdout);
        let mut words = text.split_whitespace();
        assert_eq!(words.next(), Some("True"), "{}: {text}", x.display());
        let rel: f64 = words
            .next()
            .and_then(|w| w.parse().ok())
            .expect("a difference");
        assert!(rel <= 1e-5, "{}: relative difference {rel}", x.display());
    }
}

#[test]
fn wedge_and_render_farmed_on_slurm_match_local_runs() {
    let root = scratch("slurm");
    let cluster = match Cluster::start(&root.join("cluster")) {
        Ok(c) => c,
        Err(why) => {
            eprintln!("SKIPPED wedge_and_render_farmed_on_slurm_match_local_runs: {why}");
            return;
        }
    };
    // Three viscosities of the heavy fluid, at a resolution where a run takes seconds.
    let wedge = root.join("wedge");
    cluster.polyphase(
        &root,
        &[
            "wedge",
            "rayleigh_taylor",
            "--set",
            "phases.heavy.viscosity=0.001,0.01,0.1",
            "--set",
            "resolution=32",
            "--set",
            "time.frames=3",
            "--out",
            wedge.to_str().expect("UTF-8"),
        ],
    );
    let out = cluster.polyphase(&root, &["submit", "wedge", "wedge", "--cpus", "1"]);
    assert!(out.contains("3 wedge task(s)"), "{out}");
    let status = cluster.wait(&wedge, Duration::from_secs(900));
    let table = String::from_utf8_lossy(&status.stdout);
    assert!(
        status.status.success(),
        "{table}\n{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert!(table.contains("3 done, 0 failed"), "{table}");

    // The same variants run locally, on two threads where the tasks had one.
    let local = root.join("local");
    for k in 0..3 {
        let name = format!("rayleigh_taylor-{k}");
        let scene = wedge.join(&name).join("scene.toml");
        let mine = local.join(&name);
        cluster.polyphase(
            &root,
            &[
                "run",
                scene.to_str().expect("UTF-8"),
                "--out",
                mine.to_str().expect("UTF-8"),
                "--threads",
                "2",
            ],
        );
        let farmed = wedge.join(&name).join("run");
        assert_same_files(&farmed, &mine, "frames", "ply", 4);
        assert_same_files(&farmed, &mine, "grids", "vdb", 4);
    }

    // Four frames, one per task, against the same frames rendered locally in one go.
    let run0 = wedge.join("rayleigh_taylor-0/run");
    let small = [
        "--width",
        "48",
        "--height",
        "36",
        "--spp",
        "2",
        "--variant",
        "scalar_rgb",
    ];
    let mut args = vec![
        "submit",
        "render",
        run0.to_str().expect("UTF-8"),
        "--per-task",
        "1",
    ];
    args.extend(small);
    let out = cluster.polyphase(&root, &args);
    assert!(out.contains("4 render task(s)"), "{out}");
    assert!(out.contains("the movie and plots, once job"), "{out}");
    let status = cluster.wait(&run0, Duration::from_secs(900));
    let table = String::from_utf8_lossy(&status.stdout);
    assert!(status.status.success(), "{table}");
    // The finishing job ran after the four frames and plotted the run's stats.
    assert!(table.contains("5 done, 0 failed"), "{table}");
    assert!(run0.join("plots/volumes.png").is_file(), "{table}");
    let mine = local.join("rayleigh_taylor-0");
    let mut args = vec![
        "render",
        mine.to_str().expect("UTF-8"),
        "--no-movie",
        "--no-plots",
    ];
    args.extend(small);
    cluster.polyphase(&root, &args);
    assert_same_files(&run0, &mine, "render", "png", 4);
    assert_close_exr(&run0.join("render"), &mine.join("render"), 4);

    // A task that fails is reported with its error line, and status exits non-zero.
    fs::remove_file(wedge.join("rayleigh_taylor-1/scene.toml")).expect("remove");
    fs::remove_dir_all(wedge.join("rayleigh_taylor-1/run")).expect("remove");
    cluster.polyphase(&root, &["submit", "wedge", "wedge"]);
    let status = cluster.wait(&wedge, Duration::from_secs(900));
    let table = String::from_utf8_lossy(&status.stdout);
    assert!(!status.status.success(), "{table}");
    assert!(table.contains("2 done, 1 failed"), "{table}");
    let failed = table
        .lines()
        .find(|l| l.starts_with("1 "))
        .expect("task 1's row");
    assert!(
        failed.contains("failed") && failed.contains("scene.toml"),
        "{failed}"
    );

    // A job whose partition is down never starts: `--wait --timeout` gives up, shows it
    // pending and fails.
    let down = cluster.command("scontrol", &["update", "PartitionName=local", "State=DOWN"]);
    assert!(
        down.status.success(),
        "{}",
        String::from_utf8_lossy(&down.stderr)
    );
    cluster.polyphase(&root, &["submit", "wedge", "wedge"]);
    let id = job_id(&wedge);
    let o = cluster.command_polyphase(&[
        "status",
        wedge.to_str().unwrap(),
        "--wait",
        "--timeout",
        "3",
    ]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(!o.status.success() && table.contains("pending"), "{table}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--timeout"));
    cluster.command("scancel", &[&id]);
}

/// The job id `polyphase submit` recorded for a farmed folder.
fn job_id(dir: &Path) -> String {
    let job: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("slurm/job.json")).expect("job.json"))
            .expect("JSON");
    job["job_id"].as_str().expect("a job id").to_string()
}
