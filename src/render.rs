//! `polyphase render DIR`: renders a run folder with the Mitsuba 3 pipeline in `render/`
//! (issue 5). Creates and reuses the virtual environment `render/.venv`, installs
//! `render/requirements.txt` into it on first use, then runs `python -m polyphase_render`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use anyhow::{bail, Context, Result};

mod sheet;

/// Options of `polyphase render`; passed through to the Python pipeline.
#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    /// Run folder written by `polyphase run` (with scene.toml and frames/), or a wedge folder
    /// (`polyphase wedge`): then a contact sheet of one frame per variant, `DIR/sheet.png`.
    pub dir: PathBuf,
    /// Frames to render: `all`, `N`, `A-B` or a comma list such as `0-10,12`.
    #[arg(long, default_value = "all")]
    pub frames: String,
    /// Image width in pixels.
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 480)]
    pub height: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Mitsuba variant: `auto` (llvm_ad_rgb if it works here, else scalar_rgb), `scalar_rgb`,
    /// `llvm_ad_rgb`.
    #[arg(long, default_value = "auto")]
    pub variant: String,
    /// Do not assemble `render/movie.mp4`.
    #[arg(long)]
    pub no_movie: bool,
    /// Do not plot `stats.jsonl`.
    #[arg(long)]
    pub no_plots: bool,
    /// Render only the frames whose EXR or PNG is missing and keep the others, e.g. to make
    /// the movie and plots of a farmed render, or to finish a killed one.
    #[arg(long)]
    pub only_missing: bool,
    /// Also export per-phase occupancy grids as Mitsuba `.vol` files, N voxels along the
    /// longest domain axis.
    #[arg(long, value_name = "N")]
    pub vol: Option<u32>,
    /// Render the phases voxelised (`--vol` voxels, default 64) as coloured smoke into
    /// `render/volume/`, a debug view of the `.vol` grids.
    #[arg(long)]
    pub volume: bool,
    /// Draw the domain walls as a glass tank (default: the scene's render hints).
    #[arg(long, conflicts_with = "no_tank")]
    pub tank: bool,
    /// Do not draw the domain walls, whatever the scene's render hints say.
    #[arg(long)]
    pub no_tank: bool,
    /// Python 3.11+ used to create the virtual environment (default: `$POLYPHASE_PYTHON`,
    /// else `python3`).
    #[arg(long)]
    pub python: Option<PathBuf>,
}

impl RenderArgs {
    /// Quick preview settings for `polyphase run --render`: every frame at 320×240 with 16
    /// samples per pixel, plots and movie, the scene's own tank setting.
    pub fn preview(dir: PathBuf) -> RenderArgs {
        RenderArgs {
            dir,
            frames: "all".into(),
            width: 320,
            height: 240,
            spp: 16,
            variant: "auto".into(),
            no_movie: false,
            no_plots: false,
            only_missing: false,
            vol: None,
            volume: false,
            tank: false,
            no_tank: false,
            python: None,
        }
    }

    /// The `polyphase render …` command line (without the program name) for these options.
    pub fn to_cli(&self) -> Vec<String> {
        let mut args = vec![
            "render".to_string(),
            self.dir.display().to_string(),
            "--frames".into(),
            self.frames.clone(),
            "--width".into(),
            self.width.to_string(),
            "--height".into(),
            self.height.to_string(),
            "--spp".into(),
            self.spp.to_string(),
            "--variant".into(),
            self.variant.clone(),
        ];
        let flags = [
            (self.no_movie, "--no-movie"),
            (self.no_plots, "--no-plots"),
            (self.only_missing, "--only-missing"),
            (self.volume, "--volume"),
            (self.tank, "--tank"),
            (self.no_tank, "--no-tank"),
        ];
        args.extend(flags.iter().filter(|f| f.0).map(|f| f.1.to_string()));
        if let Some(n) = self.vol {
            args.extend(["--vol".to_string(), n.to_string()]);
        }
        if let Some(p) = &self.python {
            args.extend(["--python".to_string(), p.display().to_string()]);
        }
        args
    }
}

/// Exit status of the pipeline when some frames were bad or missing (the rest rendered).
const SOME_FRAMES_BAD: i32 = 1;

/// Renders the run folder `args.dir`.
pub fn render(args: &RenderArgs) -> Result<()> {
    if sheet::is_wedge(&args.dir) {
        return sheet::render_sheet(args);
    }
    check_run_folder(&args.dir)?;
    let (render_dir, python) = prepare(args)?;
    let dir = fs::canonicalize(&args.dir)
        .with_context(|| format!("cannot resolve {}", args.dir.display()))?;
    let mut cmd = Command::new(&python);
    cmd.arg("-m")
        .arg("polyphase_render")
        .arg(&dir)
        .args(["--frames", &args.frames])
        .args(["--width", &args.width.to_string()])
        .args(["--height", &args.height.to_string()])
        .args(["--spp", &args.spp.to_string()])
        .args(["--variant", &args.variant])
        .env("PYTHONPATH", &render_dir);
    if args.no_movie {
        cmd.arg("--no-movie");
    }
    if args.no_plots {
        cmd.arg("--no-plots");
    }
    if args.only_missing {
        cmd.arg("--only-missing");
    }
    if let Some(n) = args.vol {
        cmd.args(["--vol", &n.to_string()]);
    }
    if args.volume {
        cmd.arg("--volume");
    }
    if args.tank {
        cmd.arg("--tank");
    }
    if args.no_tank {
        cmd.arg("--no-tank");
    }
    let status = cmd
        .status()
        .with_context(|| format!("cannot run {}", python.display()))?;
    match status.code() {
        Some(0) => Ok(()),
        Some(SOME_FRAMES_BAD) => bail!("some frames were not rendered (named above)"),
        Some(code) => bail!("render failed (exit status {code}, see the message above)"),
        None => bail!("render was killed by a signal"),
    }
}

/// Makes the render environment ready (creating `render/.venv` on first use); returns the
/// scripts' folder and the environment's interpreter.
pub fn prepare(args: &RenderArgs) -> Result<(PathBuf, PathBuf)> {
    let render_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("render");
    anyhow::ensure!(
        render_dir.join("polyphase_render").is_dir(),
        "render scripts not found at {} (polyphase render runs from a source checkout)",
        render_dir.display()
    );
    let base_python = args
        .python
        .clone()
        .or_else(|| std::env::var_os("POLYPHASE_PYTHON").map(PathBuf::from))
        .unwrap_or_else(|| PathBuf::from("python3"));
    let python = ensure_venv(&render_dir, &base_python)?;
    Ok((render_dir, python))
}

/// The frame numbers of a run folder's `frames/NNNN.ply`, ascending.
pub fn frames_on_disk(dir: &Path) -> Result<Vec<usize>> {
    check_run_folder(dir)?;
    let frames = dir.join("frames");
    let mut found: Vec<usize> = fs::read_dir(&frames)
        .with_context(|| format!("cannot read {}", frames.display()))?
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            let stem = name.strip_suffix(".ply")?;
            stem.bytes()
                .all(|b| b.is_ascii_digit())
                .then(|| stem.parse().ok())
                .flatten()
        })
        .collect();
    found.sort_unstable();
    anyhow::ensure!(
        !found.is_empty(),
        "{} has no NNNN.ply frames",
        frames.display()
    );
    Ok(found)
}

/// Fails with one line unless `dir` looks like a run folder.
fn check_run_folder(dir: &Path) -> Result<()> {
    anyhow::ensure!(dir.is_dir(), "run folder {} does not exist", dir.display());
    anyhow::ensure!(
        dir.join("scene.toml").is_file(),
        "{} has no scene.toml (not a polyphase run folder?)",
        dir.display()
    );
    Ok(())
}

/// The virtual environment's interpreter, creating the environment and installing the
/// requirements when they are missing or changed. A file lock serialises concurrent first uses.
fn ensure_venv(render_dir: &Path, base_python: &Path) -> Result<PathBuf> {
    let venv = render_dir.join(".venv");
    let python = venv.join("bin").join("python");
    let requirements = render_dir.join("requirements.txt");
    let wanted = fs::read_to_string(&requirements)
        .with_context(|| format!("cannot read {}", requirements.display()))?;
    let stamp = venv.join("polyphase-requirements.txt");
    let up_to_date = |stamp: &Path| fs::read_to_string(stamp).is_ok_and(|s| s == wanted);
    if python.is_file() && up_to_date(&stamp) {
        return Ok(python);
    }
    fs::create_dir_all(&venv).with_context(|| format!("cannot create {}", venv.display()))?;
    let lock_path = venv.join("polyphase-install.lock");
    let lock = fs::File::create(&lock_path)
        .with_context(|| format!("cannot create {}", lock_path.display()))?;
    lock.lock()
        .with_context(|| format!("cannot lock {}", lock_path.display()))?;
    // Another process may have finished the install while this one waited for the lock.
    if python.is_file() && up_to_date(&stamp) {
        return Ok(python);
    }
    if !python.is_file() {
        check_python(base_python)?;
        run_quiet(
            Command::new(base_python).arg("-m").arg("venv").arg(&venv),
            "creating the virtual environment render/.venv failed (on Debian: apt-get install python3-venv)",
        )?;
    }
    eprintln!(
        "polyphase render: first use, installing Mitsuba 3, numpy, matplotlib, ffmpeg (imageio-ffmpeg) and OpenEXR into {} (about a minute)",
        venv.display()
    );
    run_quiet(
        Command::new(&python)
            .args([
                "-m",
                "pip",
                "install",
                "--quiet",
                "--disable-pip-version-check",
                "-r",
            ])
            .arg(&requirements),
        "pip install of render/requirements.txt failed",
    )?;
    fs::write(&stamp, &wanted).with_context(|| format!("cannot write {}", stamp.display()))?;
    Ok(python)
}

/// Fails with one line unless `python` runs and is at least 3.11 (the pipeline uses tomllib).
fn check_python(python: &Path) -> Result<()> {
    let out = Command::new(python)
        .args(["-c", "import sys; print(sys.version_info >= (3, 11))"])
        .output()
        .with_context(|| {
            format!(
                "{} not found: polyphase render needs Python 3.11 or newer (set --python or POLYPHASE_PYTHON)",
                python.display()
            )
        })?;
    anyhow::ensure!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "True",
        "{} is not Python 3.11 or newer (set --python or POLYPHASE_PYTHON)",
        python.display()
    );
    Ok(())
}

/// Runs `cmd` with its output captured; on failure the error carries `what` and the last line
/// the command printed.
fn run_quiet(cmd: &mut Command, what: &str) -> Result<()> {
    let out = cmd
        .stdin(Stdio::null())
        .output()
        .with_context(|| what.to_string())?;
    if out.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let nonblank = |l: &&str| !l.trim().is_empty();
    let last = stderr
        .lines()
        .rfind(nonblank)
        .or_else(|| stdout.lines().rfind(nonblank))
        .unwrap_or("no output");
    bail!("{what}: {}", last.trim())
}
