//! `polyphase bench foam`: mean-curvature flow of a random Voronoi foam (paper 000 §8.4,
//! Fig. 24: 2000 regions in a cube), one row per frame: regions left, triangles, topology
//! events and seconds per flow substep, so the coarsening and its cost read off one table.

use std::fmt::Write as _;
use std::time::Instant;

use anyhow::{Context, Result};
use polyphase_coupling::build_tracker;
use polyphase_scenes::format::FoamSpec;
use polyphase_scenes::Scene;
use polyphase_tracker::InterfaceTracker;

/// Tracker cells per cell diameter of the default resolution: the paper's 2000-region run
/// carried up to 220 K triangles, an edge of about 3.3 per (1/2000)^⅓ cell diameter.
const CELLS_ACROSS: f64 = 3.3;

/// The options of one benchmark run.
pub struct FoamBench {
    pub regions: i64,
    pub seed: u64,
    /// Tracker resolution (default: [`CELLS_ACROSS`] per mean cell diameter).
    pub res: Option<i64>,
    /// Simulated end time (default: the built-in scene's).
    pub end: Option<f64>,
    /// Rows (frames) over the run (default: the built-in scene's).
    pub frames: Option<i64>,
}

/// Stages timed per row (summed over the row's steps), in table order, with their column
/// titles; "remesh" includes the implicit flow's solves, which run between the stages.
const STAGES: [(&str, &str); 3] = [
    ("collide", "collide s"),
    ("remesh", "remesh s"),
    ("topology", "T1/T2 s"),
];

/// Events counted per row, in table order, with their column titles.
const EVENTS: [(&str, &str); 4] = [
    ("t1_separations", "T1 sep"),
    ("t1_collapses", "T1 coll"),
    ("t2_regions", "T2"),
    ("flow_substeps", "substeps"),
];

pub fn run(opts: &FoamBench) -> Result<()> {
    let scene = scene(opts)?;
    eprintln!(
        "foam of {} regions at {}³ (edge {:.4}), t = 0 → {}",
        opts.regions, scene.file.resolution, scene.grid.h, scene.file.time.end
    );
    let started = Instant::now();
    let (mut tracker, _) = build_tracker(&scene, None)?;
    let start_s = started.elapsed().as_secs_f64();
    let per_frame = scene.steps_per_frame(tracker.max_travel());
    let dt = scene.frame_dt() / per_frame as f64;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Foam: {} regions, {}³ tracker cells (target edge {:.4}), start {:.1} s, {} triangles",
        opts.regions,
        scene.file.resolution,
        scene.grid.h,
        start_s,
        tracker.mesh().triangle_count()
    );
    let _ = write!(out, "{:>10}{:>9}{:>11}", "t", "regions", "triangles");
    for (_, title) in EVENTS {
        let _ = write!(out, "{title:>10}");
    }
    let _ = write!(out, "{:>12}", "s/substep");
    for (_, title) in STAGES {
        let _ = write!(out, "{title:>11}");
    }
    let _ = writeln!(out, "{:>10}", "wall s");
    eprint!("{out}");
    let mut step = 0;
    for frame in 1..=scene.file.time.frames as usize {
        let mut counts = [0usize; EVENTS.len()];
        let mut seconds_in = [0.0; STAGES.len()];
        let frame_start = Instant::now();
        for _ in 0..per_frame {
            let stats = tracker
                .advance(&scene.velocity, step as f64 * dt, dt)
                .with_context(|| format!("foam step {step}"))?;
            step += 1;
            for (name, n) in &stats.events {
                if let Some(k) = EVENTS.iter().position(|(e, _)| e == name) {
                    counts[k] += n;
                }
            }
            for (name, s) in &stats.stages {
                if let Some(k) = STAGES.iter().position(|(e, _)| e == name) {
                    seconds_in[k] += s;
                }
            }
        }
        let seconds = frame_start.elapsed().as_secs_f64();
        let mut row = format!(
            "{:>10.6}{:>9}{:>11}",
            frame as f64 * scene.frame_dt(),
            tracker.region_count().unwrap_or(0),
            tracker.mesh().triangle_count()
        );
        for c in counts {
            let _ = write!(row, "{c:>10}");
        }
        let substeps = counts[EVENTS.len() - 1].max(1);
        let _ = write!(row, "{:>12.3}", seconds / substeps as f64);
        for s in seconds_in {
            let _ = write!(row, "{s:>11.1}");
        }
        let _ = writeln!(row, "{:>10.1}", started.elapsed().as_secs_f64());
        eprint!("{row}");
        out.push_str(&row);
    }
    print!("{out}");
    Ok(())
}

/// The built-in `foam` scene with the benchmark's regions, seed, resolution and time.
fn scene(opts: &FoamBench) -> Result<Scene> {
    let base = polyphase_scenes::load("foam")?;
    let mut file = base.file.clone();
    file.foam = Some(FoamSpec {
        regions: opts.regions,
        seed: opts.seed,
    });
    file.phases.clear();
    file.background = "cell0".into();
    file.resolution = opts
        .res
        .unwrap_or_else(|| (CELLS_ACROSS * (opts.regions.max(1) as f64).cbrt()).round() as i64);
    if let Some(end) = opts.end {
        file.time.end = end;
    }
    if let Some(frames) = opts.frames {
        file.time.frames = frames;
    }
    Ok(Scene::from_file(file, "bench foam")?)
}
