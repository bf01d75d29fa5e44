//! `polyphase`: run multiphase interface-tracking scenes, list them, benchmark the stages.
#![deny(unsafe_code)]

mod bench;
mod bench_coupled;
mod bench_foam;
mod bench_front;
mod checkpoint;
mod farm;
mod measurements;
mod output;
mod render;
mod resources;
mod run;
mod run_coupled;
mod run_passive;
mod slab;
mod slab_exr;
mod slab_png;
mod summary;
mod validate;
mod wedge;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "polyphase",
    version,
    about = "Multiphase interface tracking and fluid simulation"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write frames, stats and the resolved scene into an output folder.
    Run {
        /// Built-in scene name or path to a scene TOML file.
        #[arg(default_value = polyphase_scenes::DEFAULT_SCENE)]
        scene: String,
        /// Output folder (default: out/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Tracker cells along the longest domain axis (overrides the scene).
        #[arg(long)]
        resolution: Option<i64>,
        /// Number of frames after the initial one (overrides the scene).
        #[arg(long)]
        frames: Option<i64>,
        /// Interface tracker, `contour` or `front` (overrides the scene).
        #[arg(long)]
        tracker: Option<polyphase_scenes::TrackerKind>,
        /// Worker threads (default: all cores). Output is identical for any value.
        #[arg(long)]
        threads: Option<usize>,
        /// Then render every frame (a quick preview: 320×240, 16 samples per pixel) with
        /// `polyphase render`, plus the plots and the movie; render again with
        /// `polyphase render DIR` for other settings.
        #[arg(long)]
        render: bool,
        /// Continue the output folder's killed run of the same scene from its checkpoint (or
        /// leave a finished one alone) instead of starting over.
        #[arg(long)]
        resume: bool,
    },
    /// Continue a killed run from its last checkpoint; the frames come out byte-identical to
    /// an uninterrupted run's.
    Resume {
        /// The run's output folder.
        dir: PathBuf,
        /// Worker threads (default: all cores). Output is identical for any value.
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Render a run folder with Mitsuba 3: images, movie and plots into DIR/render and DIR/plots.
    Render(render::RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Run the physics validation cases (validation/<case>/) and compare with their
    /// references; exits non-zero if any metric fails.
    Validate(validate::ValidateArgs),
    /// Write a parameter wedge: one validated scene per combination of `--set` values, and an
    /// index, into a new folder.
    Wedge(wedge::WedgeArgs),
    /// Farm out a wedge's variants, validation cases or a run's frames as a Slurm job array.
    Submit(farm::SubmitArgs),
    /// Show which tasks of a farmed folder's Slurm job finished, failed, run or wait.
    Status(farm::StatusArgs),
    /// One task of a farmed job (what each Slurm array task runs).
    #[command(hide = true)]
    Task {
        /// The job's `slurm/` folder.
        dir: PathBuf,
        /// The task's index in the array.
        index: usize,
    },
    /// Measure the stages and print tables shaped like the papers'.
    Bench {
        #[command(subcommand)]
        what: bench::BenchCommand,
    },
}

fn main() -> ExitCode {
    let result = dispatch(Cli::parse().command);
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", chain.join(": "));
            ExitCode::FAILURE
        }
    }
}

/// Runs one command.
fn dispatch(command: Command) -> anyhow::Result<()> {
    match command {
        Command::Run {
            scene,
            out,
            resolution,
            frames,
            tracker,
            threads,
            render,
            resume,
        } => with_threads(threads, || {
            run::run(&run::RunOptions {
                scene,
                out,
                resolution,
                frames,
                tracker,
                resume,
            })
        })
        .and_then(|root| match render {
            true => render::render(&render::RenderArgs::preview(root)),
            false => Ok(()),
        }),
        Command::Resume { dir, threads } => with_threads(threads, || run::resume(&dir)),
        Command::Render(args) => render::render(&args),
        Command::Scenes => {
            list_scenes();
            Ok(())
        }
        Command::Bench { what } => bench::bench(what),
        Command::Validate(args) => validate::validate(&args),
        Command::Wedge(args) => wedge::wedge(&args),
        Command::Submit(args) => farm::submit(&args),
        Command::Status(args) => farm::status(&args),
        Command::Task { dir, index } => farm::task(&dir, index, |args| {
            let cli = Cli::try_parse_from(
                std::iter::once("polyphase".to_string()).chain(args.iter().cloned()),
            )?;
            dispatch(cli.command)
        }),
    }
}

/// Runs `f` on a rayon pool of `threads` workers (all cores when `None`).
fn with_threads<T: Send>(
    threads: Option<usize>,
    f: impl FnOnce() -> anyhow::Result<T> + Send,
) -> anyhow::Result<T> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        anyhow::ensure!(n >= 1, "--threads must be at least 1");
        builder = builder.num_threads(n);
    }
    builder.build()?.install(f)
}

fn list_scenes() {
    for (name, _) in polyphase_scenes::BUILTIN {
        match polyphase_scenes::builtin(name) {
            Some(Ok(s)) => println!("{name:<16} {}", s.file.description),
            Some(Err(e)) => println!("{name:<16} (invalid: {e})"),
            None => {}
        }
    }
}
