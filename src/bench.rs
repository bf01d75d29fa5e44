//! `polyphase bench`: stage timings and accuracy in tables shaped like the papers'.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Subcommand;
use polyphase_tracker::{metrics, ContourTracker, InterfaceTracker};
use serde::Serialize;

/// What to benchmark.
#[derive(Subcommand)]
pub enum BenchCommand {
    /// First step of the contouring tracker (paper 004 Tables 1 and 2).
    Contour {
        /// Built-in scene name or scene file.
        #[arg(long, default_value = "zalesak")]
        scene: String,
        /// Resolutions, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "32,64,128")]
        res: Vec<i64>,
        /// Random points for the indicator accuracy (paper: 10⁷; default 10⁶).
        #[arg(long, default_value_t = 1_000_000)]
        samples: usize,
        /// Also write the rows as a JSON array to this file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// The front tracker next to the contouring tracker over one period of a scene: volume
    /// error, Hausdorff distance to the start, triangles, time per step, collision vs
    /// remeshing share (paper 000 §7).
    Front {
        /// Built-in scene name or scene file (a periodic one).
        #[arg(long, default_value = "enright")]
        scene: String,
        /// Resolutions (the front's target edge length is the grid spacing), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "128")]
        res: Vec<i64>,
        /// Stop after this many steps of each tracker (default: the whole period).
        #[arg(long)]
        steps: Option<usize>,
        /// Run only this tracker (`contour` or `front`; default: both).
        #[arg(long)]
        only: Option<polyphase_scenes::TrackerKind>,
    },
    /// A coupled scene at several resolutions, each run in its own process: seconds per frame
    /// per stage, start-up, peak memory and CPU use.
    Coupled {
        /// Built-in scene name or scene file (a coupled one).
        #[arg(long, default_value = "dambreak")]
        scene: String,
        /// Tracker resolutions (the solver keeps the scene's ratio), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "64,128")]
        res: Vec<i64>,
        /// Frames to run (default: the scene's).
        #[arg(long)]
        frames: Option<i64>,
        /// Worker threads of each run (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Folder for the runs (default: out/bench-coupled).
        #[arg(long, default_value = "out/bench-coupled")]
        out: PathBuf,
    },
    /// Mean-curvature flow of a random Voronoi foam (paper 000 Fig. 24): regions left,
    /// triangles, T1/T2 events and seconds per substep, one row per frame.
    Foam {
        /// Cells of the foam (the paper's run: 2000).
        #[arg(long, default_value_t = 2000)]
        regions: i64,
        /// Seed of the cells' random placement.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Tracker resolution (default: 3.3 cells per mean cell diameter, the paper's sizing).
        #[arg(long)]
        res: Option<i64>,
        /// Simulated end time (default: the built-in `foam` scene's).
        #[arg(long)]
        end: Option<f64>,
        /// Rows over the run (default: the built-in scene's frames).
        #[arg(long)]
        frames: Option<i64>,
    },
    /// Pressure and viscosity solves of a two-phase 1000:1 sphere, MIC(0)-PCG vs multigrid-PCG.
    Solver {
        /// Resolutions, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "32,64")]
        res: Vec<usize>,
    },
}

/// One row of the contour benchmark.
#[derive(Serialize)]
pub(crate) struct ContourRow {
    res: i64,
    cells: usize,
    interface_cells: usize,
    vertices: usize,
    build_s: f64,
    contour_s: f64,
    query_s: f64,
    total_s: f64,
    pub(crate) indicator_accuracy: f64,
    pub(crate) max_mismatch_over_h: f64,
}

pub fn bench(cmd: BenchCommand) -> Result<()> {
    match cmd {
        BenchCommand::Contour {
            scene,
            res,
            samples,
            json,
        } => {
            let base = polyphase_scenes::load(&scene)?;
            let mut rows = Vec::new();
            for r in res {
                let s = base.with_overrides(Some(r), None)?;
                rows.push(contour_row(&s, samples));
                eprintln!("{}", contour_table(&rows));
            }
            println!("{}", contour_table(&rows));
            if let Some(path) = json {
                std::fs::write(&path, serde_json::to_string_pretty(&rows)?)
                    .with_context(|| format!("cannot write {}", path.display()))?;
            }
            Ok(())
        }
        BenchCommand::Front {
            scene,
            res,
            steps,
            only,
        } => crate::bench_front::run(&scene, &res, steps, only),
        BenchCommand::Coupled {
            scene,
            res,
            frames,
            threads,
            out,
        } => crate::bench_coupled::run(&scene, &res, frames, threads, &out),
        BenchCommand::Foam {
            regions,
            seed,
            res,
            end,
            frames,
        } => crate::bench_foam::run(&crate::bench_foam::FoamBench {
            regions,
            seed,
            res,
            end,
            frames,
        }),
        BenchCommand::Solver { res } => {
            let rows = polyphase_solver::bench::run(&res)?;
            println!("{}", polyphase_solver::bench::format_table(&rows));
            Ok(())
        }
    }
}

/// The first step of the contouring tracker from the scene's exact shapes: its stage timings,
/// and its indicator against the exact one at `samples` random points (paper 004 Table 2).
pub(crate) fn contour_row(scene: &polyphase_scenes::Scene, samples: usize) -> ContourRow {
    let n_phases = scene.file.phases.len();
    let exact = |x| scene.initial.sample(x);
    let (tracker, stats) =
        ContourTracker::new(scene.grid, &exact, n_phases, scene.initial.background);
    let stage = |name: &str| {
        stats
            .stages
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(0.0, |s| s.1)
    };
    let h = scene.grid.h;
    let acc = metrics::indicator_accuracy(
        scene.grid.origin,
        scene.grid.upper(),
        samples,
        1,
        |x| tracker.phi_chi(x).1,
        |x| scene.initial.phase(x),
        |x| tracker.query().distance(x),
    );
    // Table 1's third stage, redistancing, is the new mesh's exact query structure here: φ is
    // read off it (`ContourTracker::phi_chi`).
    let (b, c, d) = (stage("build"), stage("contour"), stage("query"));
    ContourRow {
        res: scene.file.resolution,
        cells: stats.cells,
        interface_cells: stats.interface_cells,
        vertices: tracker.mesh().vertices.len(),
        build_s: b,
        contour_s: c,
        query_s: d,
        total_s: b + c + d,
        indicator_accuracy: acc.accuracy(),
        max_mismatch_over_h: acc.max_mismatch_distance / h,
    }
}

fn contour_table(rows: &[ContourRow]) -> String {
    let mut s = String::new();
    let line = |s: &mut String, label: &str, f: &dyn Fn(&ContourRow) -> String| {
        let _ = write!(s, "{label:<22}");
        for r in rows {
            let _ = write!(s, "{:>12}", f(r));
        }
        s.push('\n');
    };
    line(&mut s, "Res (n^3)", &|r| format!("{}^3", r.res));
    line(&mut s, "Cells", &|r| r.cells.to_string());
    line(&mut s, "Intersect cells", &|r| {
        r.interface_cells.to_string()
    });
    line(&mut s, "N / N_T", &|r| {
        format!("{:.3}", r.interface_cells as f64 / r.cells.max(1) as f64)
    });
    line(&mut s, "Vertices", &|r| r.vertices.to_string());
    line(&mut s, "Building tree (s)", &|r| {
        format!("{:.4}", r.build_s)
    });
    line(&mut s, "Contouring (s)", &|r| format!("{:.4}", r.contour_s));
    line(&mut s, "Query (s)", &|r| format!("{:.4}", r.query_s));
    line(&mut s, "Total (s)", &|r| format!("{:.4}", r.total_s));
    line(&mut s, "Indicator accuracy", &|r| {
        format!("{:.4}%", r.indicator_accuracy * 100.0)
    });
    line(&mut s, "max |phi_e / h|", &|r| {
        format!("{:.2}", r.max_mismatch_over_h)
    });
    s
}
