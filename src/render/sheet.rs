//! `polyphase render WEDGE_DIR`: a contact sheet of a wedge, one rendered frame per variant
//! (from the variants' runs, `DIR/<variant>/run`, as `polyphase submit wedge` writes them),
//! labeled with its settings, into `DIR/sheet.png`.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};

use super::{frames_on_disk, prepare, RenderArgs};
use crate::wedge::WedgeIndex;

/// Renders the chosen frame (`--frames N`, default each run's last) of every variant with the
/// options of `args`, then composes the labeled sheet.
pub fn render_sheet(args: &RenderArgs) -> Result<()> {
    let dir = &args.dir;
    let index = WedgeIndex::read(dir)?;
    let chosen = match args.frames.as_str() {
        "all" => None,
        n => Some(n.parse::<usize>().with_context(|| {
            format!("--frames {n}: a contact sheet shows one frame; give its number")
        })?),
    };
    let mut tiles = Vec::new();
    let mut rendered = 0;
    for v in &index.variants {
        let run = v.run_dir(dir);
        let label = format!("{}\n{}", v.name, v.label("\n"));
        let frame = match (chosen, frames_on_disk(&run)) {
            (Some(n), Ok(_)) => n,
            (None, Ok(frames)) => frames[frames.len() - 1],
            (_, Err(e)) => {
                eprintln!("{}: not run yet ({e:#})", v.name);
                tiles.push((run.join("render/none.png"), label));
                continue;
            }
        };
        let mut one = args.clone();
        one.dir = run.clone();
        one.frames = frame.to_string();
        one.no_movie = true;
        one.no_plots = true;
        match super::render(&one) {
            Ok(()) => rendered += 1,
            Err(e) => eprintln!("{}: frame {frame} not rendered ({e:#})", v.name),
        }
        tiles.push((run.join(format!("render/{frame:04}.png")), label));
    }
    if rendered == 0 {
        bail!(
            "no variant of {} has a rendered frame (run them first: `polyphase submit wedge {}`)",
            dir.display(),
            dir.display()
        );
    }
    let (render_dir, python) = prepare(args)?;
    let out = dir.join("sheet.png");
    let title = match chosen {
        Some(n) => format!("{} wedge, frame {n}", index.scene),
        None => format!("{} wedge, last frame", index.scene),
    };
    let mut cmd = Command::new(&python);
    cmd.args(["-m", "polyphase_render.sheet"])
        .arg(&out)
        .args(["--title", &title])
        .env("PYTHONPATH", &render_dir);
    for (image, label) in &tiles {
        cmd.arg(image).arg(label);
    }
    let status = cmd
        .status()
        .with_context(|| format!("cannot run {}", python.display()))?;
    anyhow::ensure!(status.success(), "the contact sheet was not written");
    println!("contact sheet: {}", out.display());
    Ok(())
}

/// True when `dir` is a wedge folder rather than a run folder.
pub fn is_wedge(dir: &Path) -> bool {
    dir.join(crate::wedge::INDEX_FILE).is_file()
}
