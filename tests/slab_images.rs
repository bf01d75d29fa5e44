//! Slab scenes' `frames/NNNN.exr` and `frames/NNNN.png` (issue 18), read back by readers
//! independent of the Rust writers: OpenEXR's own Python bindings and matplotlib's PNG reader,
//! both in `render/.venv` (installed from `render/requirements.txt`; the first test here to
//! need them creates it through `polyphase render`, about a minute on a fresh clone).

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::{builtin_at, polyphase, run_small, scratch};
use serde_json::Value;

/// Tracker cells across vortex4: 32 keeps the run near 10 s in the dev profile.
const RESOLUTION: u32 = 32;
/// Frames after the initial one; vortex4 keeps its period T = 4 s, so frame f is at t = f s.
const FRAMES: u32 = 4;

/// Reads every frame's EXR and PNG with OpenEXR and matplotlib and reports, per frame: the
/// channel names, the header's domain, cells per phase, differing neighbour pairs per phase,
/// how far φ exceeds the distance to the nearest midpoint between differing neighbours, the
/// velocity's largest gap to the analytic vortex, the cells (i, j) whose phase is not their
/// quadrant's, and the PNG's size and colours.
const READER: &str = r#"
import json, math, sys
import numpy as np
import OpenEXR
import matplotlib.image as mpimg

root, frames, period, phases = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
out = []
for f in range(frames + 1):
    exr = OpenEXR.File(f"{root}/frames/{f:04d}.exr")
    header, channels = exr.header(), exr.channels()
    chi = channels["chi"].pixels.astype(np.int64)
    rows, cols = chi.shape
    origin = np.asarray(header["origin"], dtype=np.float64)
    h = float(np.asarray(header["cellSize"]).item())
    # Row r holds cell row ny - 1 - r: flip so that index [j, i] is cell (i, j).
    chi = chi[::-1]
    phi = channels["phi"].pixels[::-1].astype(np.float64)
    u = channels["velocity.u"].pixels[::-1].astype(np.float64)
    v = channels["velocity.v"].pixels[::-1].astype(np.float64)
    x = origin[0] + h * (np.arange(cols) + 0.5)[None, :]
    y = origin[1] + h * (np.arange(rows) + 0.5)[:, None]
    c = math.cos(math.pi * f / period)
    u_exact = -np.sin(np.pi * x) ** 2 * np.sin(2 * np.pi * y) * c
    v_exact = np.sin(np.pi * y) ** 2 * np.sin(2 * np.pi * x) * c
    across_x = chi[:, 1:] != chi[:, :-1]
    across_y = chi[1:, :] != chi[:-1, :]
    pairs = [int((across_x & ((chi[:, 1:] == p) | (chi[:, :-1] == p))).sum()
                 + (across_y & ((chi[1:, :] == p) | (chi[:-1, :] == p))).sum())
             for p in range(phases)]
    # Midpoints between the centres of neighbours in different phases: the interface crosses
    # each such segment, within h/2 of its midpoint.
    jx, ix = np.nonzero(across_x)
    jy, iy = np.nonzero(across_y)
    mids = np.concatenate([np.stack([origin[0] + h * (ix + 1), origin[1] + h * (jx + 0.5)], 1),
                           np.stack([origin[0] + h * (iy + 0.5), origin[1] + h * (jy + 1)], 1)])
    centres = np.stack(np.broadcast_arrays(x, y), -1).reshape(-1, 1, 2)
    to_mid = np.sqrt(((centres - mids[None]) ** 2).sum(-1)).min(1).reshape(chi.shape)
    quadrant = (x > 0.5).astype(np.int64) + 2 * (y > 0.5).astype(np.int64)
    png = mpimg.imread(f"{root}/frames/{f:04d}.png")
    colours = {tuple(int(round(255 * ch)) for ch in px) for px in png.reshape(-1, png.shape[2])}
    out.append({
        "channels": sorted(channels),
        "origin": origin.tolist(),
        "cell_size": h,
        "shape": [rows, cols],
        "cells": [int((chi == p).sum()) for p in range(phases)],
        "pairs": pairs,
        "phi_excess": float((phi - to_mid).max()),
        "phi_min": float(phi.min()),
        "velocity_error": float(max(np.abs(u - u_exact).max(), np.abs(v - v_exact).max())),
        "quadrant_mismatch": np.argwhere(chi != quadrant)[:, ::-1].tolist(),
        "png_shape": list(png.shape),
        "png_colours": sorted(colours),
    })
print(json.dumps(out))
"#;

/// The render environment's Python, created (with OpenEXR) by a tiny `polyphase render` of
/// frame 0 of `run`.
fn render_python(run: &Path) -> PathBuf {
    let o = polyphase(&[
        "render",
        run.to_str().unwrap(),
        "--frames",
        "0",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--variant",
        "scalar_rgb",
        "--no-movie",
        "--no-plots",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    Path::new(env!("CARGO_MANIFEST_DIR")).join("render/.venv/bin/python")
}

/// The JSON lines of the run's `stats.jsonl`, frame lines only.
fn frame_stats(run: &Path) -> Vec<Value> {
    fs::read_to_string(run.join("stats.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .filter(|v| v.get("frame").is_some())
        .collect()
}

#[test]
fn vortex4_exr_frames_match_the_stats() {
    let run = scratch("slab_vortex4").join("vortex4");
    let o = run_small("vortex4", RESOLUTION, FRAMES, &run, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let python = render_python(&run);
    let names = ["q00", "q10", "q01", "q11"];
    let o = Command::new(python)
        .args(["-c", READER])
        .arg(&run)
        .args([FRAMES.to_string(), "4".into(), names.len().to_string()])
        .output()
        .expect("the render environment's python runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frames: Vec<Value> = serde_json::from_slice(&o.stdout).unwrap();
    let stats = frame_stats(&run);
    assert_eq!(frames.len(), FRAMES as usize + 1);
    assert_eq!(stats.len(), frames.len());
    let n = RESOLUTION as usize;
    let h = 1.0 / RESOLUTION as f64;
    // The scene's colours (linear RGB) through the sRGB transfer curve, as 8-bit values.
    let srgb = |c: f64| {
        let e = if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        (e * 255.0).round() as i64
    };
    let mut colours: Vec<Vec<i64>> = builtin_at("vortex4", RESOLUTION as i64)
        .file
        .phases
        .iter()
        .map(|p| p.color.iter().map(|&c| srgb(c)).collect())
        .collect();
    colours.sort();
    for (f, (img, line)) in frames.iter().zip(&stats).enumerate() {
        let ctx = format!("frame {f}: {img}");
        // Passive run: no solver, so no pressure channel.
        assert_eq!(
            img["channels"],
            serde_json::json!(["chi", "phi", "velocity.u", "velocity.v"]),
            "{ctx}"
        );
        assert_eq!(img["shape"], serde_json::json!([n, n]), "{ctx}");
        assert_eq!(img["cell_size"].as_f64(), Some(h), "{ctx}");
        // The slab is two cells thick: the layer's cells are centred on its mid-plane z = h.
        assert_eq!(
            img["origin"],
            serde_json::json!([0.0, 0.0, 0.5 * h]),
            "{ctx}"
        );
        // The prescribed vortex at the frame's time, evaluated in f64 and stored as f32
        // (|v| ≤ 1, so rounding is below 1e-7).
        assert!(img["velocity_error"].as_f64().unwrap() < 1e-6, "{ctx}");
        // φ: the interface crosses each segment between neighbours in different phases within
        // h/2 of its midpoint, so φ ≤ (distance to the nearest such midpoint) + h/2; 0.1 h more
        // for the tracker's trilinear interpolation of φ away from interface cells (it adds
        // 0.015 h at most in this run). Rows read in the wrong order, or φ in other units,
        // break this by many cells.
        assert!(img["phi_excess"].as_f64().unwrap() <= 0.6 * h, "{ctx}");
        assert!(img["phi_min"].as_f64().unwrap() >= 0.0, "{ctx}");
        // Area per phase against the mesh volumes of stats.jsonl (the slab's volume over its
        // area is its constant thickness, so fractions compare). A cell counts wholly for the
        // phase at its centre; where the interface crosses a cell about straight, the centre's
        // side holds at least half of it, so each crossed cell is off by at most half a cell,
        // and a phase's boundary crosses about as many cells as it has differing neighbour
        // pairs (its staircase perimeter over h): the issue's perimeter × h / 2.
        let volumes = &line["phase_volumes"];
        let total: f64 = names.iter().map(|p| volumes[p].as_f64().unwrap()).sum();
        for (id, phase) in names.iter().enumerate() {
            let expected = volumes[phase].as_f64().unwrap() / total * (n * n) as f64;
            let cells = img["cells"][id].as_f64().unwrap();
            let tolerance = img["pairs"][id].as_f64().unwrap() / 2.0;
            assert!(
                (cells - expected).abs() <= tolerance,
                "{phase}: {cells} cells, stats say {expected:.1} ± {tolerance}; {ctx}"
            );
        }
        assert_eq!(img["png_shape"], serde_json::json!([n, n, 3]), "{ctx}");
        // Every phase is present in every frame (vortex4 conserves their areas).
        assert_eq!(img["png_colours"], serde_json::json!(colours), "{ctx}");
    }
    // Frame 0 is the quadrants: cell (i, j) holds phase (x > ½) + 2 (y > ½), which pins the
    // ids and the rows' top-down order; no centre lies on x = ½ or y = ½, but the contoured
    // mesh cannot hold the four-phase point (½, ½) exactly (marching tetrahedra put junctions
    // inside cells), so only the four cells around it may differ.
    let centre = [n / 2 - 1, n / 2];
    for cell in frames[0]["quadrant_mismatch"].as_array().unwrap() {
        let (i, j) = (cell[0].as_u64().unwrap(), cell[1].as_u64().unwrap());
        assert!(
            centre.contains(&(i as usize)) && centre.contains(&(j as usize)),
            "cell ({i}, {j}) is not its quadrant's phase: {}",
            frames[0]
        );
    }
}

#[test]
fn coupled_images_are_identical_with_one_and_two_threads() {
    // dambreak_column at 32: tracker 32 × 16 × 2 cells, solver 16 × 8 × 1 (a coupled slab).
    let dir = scratch("slab_threads");
    let run = |threads: &str| {
        let out = dir.join(format!("t{threads}"));
        let o = run_small("dambreak_column", 32, 2, &out, &["--threads", threads]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        ["exr", "png"]
            .iter()
            .flat_map(|ext| (0..=2).map(move |f| format!("frames/{f:04}.{ext}")))
            .map(|name| fs::read(out.join(name)).unwrap())
            .collect::<Vec<_>>()
    };
    let one = run("1");
    assert!(
        one == run("2"),
        "slab images differ between 1 and 2 threads"
    );
    // A coupled run's EXR has the solver's pressure: its name is in the header's channel list.
    let exr = &one[1];
    assert!(
        exr.windows(9).any(|w| w == b"pressure\0"),
        "no pressure channel"
    );
    // The PNG paints the finer tracker grid: its IHDR chunk gives 32 × 16 pixels.
    let png = &one[4];
    assert_eq!(&png[16..24], &[0, 0, 0, 32, 0, 0, 0, 16]);
}

#[test]
fn blocked_image_path_is_one_clear_error() {
    // A folder where frame 0's image belongs, with a file inside so that nothing replaces it.
    let out = scratch("slab_blocked").join("vortex4");
    let blocked = out.join("frames/0000.png");
    fs::create_dir_all(&blocked).unwrap();
    fs::write(blocked.join("keep"), "x").unwrap();
    let o = run_small("vortex4", 8, 1, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    let last = err.lines().last().unwrap_or("");
    assert!(
        last.starts_with("error: ") && last.contains("frames/0000.png"),
        "{err}"
    );
    assert_eq!(
        err.lines().filter(|l| l.starts_with("error")).count(),
        1,
        "{err}"
    );
}
