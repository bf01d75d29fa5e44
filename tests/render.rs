//! End-to-end tests of `polyphase render` (issue 5): a tiny frame of a small run is rendered
//! with Mitsuba (`scalar_rgb`, 64×48, 4 spp), and a run folder with a corrupt frame renders the
//! good frames and names the bad one. The first test to run creates `render/.venv` (pip
//! install from PyPI, about a minute); later runs reuse it.

mod common;

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use common::{polyphase, run_small, scratch};

/// The run folder every test starts from: zalesak at 16 cells, frames 0–2. Made once.
fn small_run() -> &'static PathBuf {
    static RUN: OnceLock<PathBuf> = OnceLock::new();
    RUN.get_or_init(|| {
        let out = scratch("render_run").join("zalesak");
        let o = run_small("zalesak", 16, 2, &out, &[]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    })
}

/// Copies the run folder's scene, stats and the listed frames into a fresh folder.
fn copy_run(name: &str, frames: &[usize]) -> PathBuf {
    let src = small_run();
    let dst = scratch(name);
    fs::create_dir_all(dst.join("frames")).unwrap();
    for f in ["scene.toml", "stats.jsonl"] {
        fs::copy(src.join(f), dst.join(f)).unwrap();
    }
    for n in frames {
        let name = format!("frames/{n:04}.ply");
        fs::copy(src.join(&name), dst.join(&name)).unwrap();
    }
    dst
}

fn render(dir: &Path, frames: &str) -> Output {
    polyphase(&[
        "render",
        dir.to_str().unwrap(),
        "--frames",
        frames,
        "--width",
        "64",
        "--height",
        "48",
        "--spp",
        "4",
        "--variant",
        "scalar_rgb",
        "--no-movie",
    ])
}

/// Pixel statistics of two EXR renders, computed by the render environment's own Python
/// (the test has no EXR reader): finiteness, means, and where the two differ.
fn compare_exr(a: &Path, b: &Path) -> serde_json::Value {
    let python = Path::new(env!("CARGO_MANIFEST_DIR")).join("render/.venv/bin/python");
    let script = r#"
import json, sys
import numpy as np
import mitsuba as mi
mi.set_variant("scalar_rgb")
a = np.array(mi.Bitmap(sys.argv[1]), dtype=np.float64)[..., :3]
b = np.array(mi.Bitmap(sys.argv[2]), dtype=np.float64)[..., :3]
diff = np.abs(a - b).max(axis=2)
h, w = diff.shape
center = diff[h // 2 - h // 6 : h // 2 + h // 6, w // 2 - w // 6 : w // 2 + w // 6]
print(json.dumps({
    "shape": list(a.shape),
    "finite": bool(np.isfinite(a).all() and np.isfinite(b).all()),
    "mean_a": float(a.mean()), "mean_b": float(b.mean()),
    "frac_differ": float((diff > 0.02).mean()),
    "center_differ": float((center > 0.02).mean()),
}))
"#;
    let o = Command::new(python)
        .args(["-c", script])
        .arg(a)
        .arg(b)
        .output()
        .expect("the render environment's python runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A valid labeled PLY with no vertices and no faces: the scene with nothing but air.
fn write_empty_ply(path: &Path) {
    let header = "ply\nformat binary_little_endian 1.0\ncomment polyphase labeled mesh\n\
        element vertex 0\nproperty double x\nproperty double y\nproperty double z\n\
        element face 0\nproperty list uchar uint vertex_indices\nproperty ushort front\n\
        property ushort back\nend_header\n";
    fs::write(path, header).unwrap();
}

#[test]
fn tiny_frame_shows_the_liquids() {
    // Frame 0 of the run, and frame 1 emptied: both rendered in one call share the camera
    // (framed on every frame of the run), so their difference is where the liquids project.
    let dir = copy_run("render_tiny", &[0]);
    write_empty_ply(&dir.join("frames/0001.ply"));
    let o = render(&dir, "0-1");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["0000.png", "0000.exr", "0001.png", "0001.exr"] {
        assert!(dir.join("render").join(f).is_file(), "render/{f} missing");
    }
    assert!(
        dir.join("plots/volumes.png").is_file(),
        "volume plot missing"
    );
    let s = compare_exr(&dir.join("render/0000.exr"), &dir.join("render/0001.exr"));
    assert_eq!(s["shape"], serde_json::json!([48, 64, 3]));
    assert_eq!(s["finite"], true, "{s}");
    // Not black: ambient radiance 0.5 on a grey ground gives a mean far above 0.05.
    assert!(s["mean_a"].as_f64().unwrap() > 0.05, "{s}");
    // The camera aims at the liquids: most of the central third of the image shows them
    // (4 spp noise is identical where the mesh plays no part: same per-pixel sample seeds).
    assert!(s["center_differ"].as_f64().unwrap() > 0.5, "{s}");
    // The liquids do not cover the whole frame: ground and sky remain around them.
    let frac = s["frac_differ"].as_f64().unwrap();
    assert!(frac > 0.05 && frac < 0.9, "{s}");
}

#[test]
fn corrupt_frame_is_named_and_the_others_render() {
    let dir = copy_run("render_corrupt", &[0, 1, 2]);
    let bad = dir.join("frames/0001.ply");
    let bytes = fs::read(&bad).unwrap();
    fs::write(&bad, &bytes[..bytes.len() / 2]).unwrap();
    let o = render(&dir, "all");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "a corrupt frame must fail the command: {stderr}"
    );
    assert!(
        stderr.contains("frames/0001.ply"),
        "bad frame not named: {stderr}"
    );
    assert!(stderr.contains("truncated"), "reason not given: {stderr}");
    assert!(dir.join("render/0000.png").is_file(), "{stderr}");
    assert!(dir.join("render/0002.png").is_file(), "{stderr}");
    assert!(!dir.join("render/0001.png").exists());
}

#[test]
fn missing_run_folder_is_one_clear_error() {
    let dir = scratch("render_missing").join("nope");
    let o = polyphase(&["render", dir.to_str().unwrap()]);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("does not exist"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

#[test]
fn python_unit_tests_pass() {
    // Needs the virtual environment: render once (cheaply) so that it exists.
    let dir = copy_run("render_unit", &[0]);
    let o = render(&dir, "0");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("render");
    let o = Command::new(root.join(".venv/bin/python"))
        .args(["-m", "unittest", "discover", "-s", "tests", "-t", "."])
        .current_dir(&root)
        .output()
        .expect("the render environment's python runs");
    assert!(
        o.status.success(),
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}
