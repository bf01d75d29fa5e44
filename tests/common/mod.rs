//! Helpers shared by the end-to-end tests: run the binary, make scratch folders.
// Each test file compiles this module on its own and uses only some of the helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Built-in scene `name` at tracker `resolution`.
pub fn builtin_at(name: &str, resolution: i64) -> polyphase_scenes::Scene {
    polyphase_scenes::builtin(name)
        .expect("built-in")
        .expect("valid")
        .with_overrides(Some(resolution), None)
        .expect("valid override")
}

/// Runs the `polyphase` binary with `args`.
pub fn polyphase(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_polyphase"))
        .args(args)
        .output()
        .expect("the polyphase binary runs")
}

/// A fresh, empty scratch folder under the target directory, unique per test name.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    dir
}

/// `polyphase run SCENE --resolution R --frames F --out OUT` plus `extra` arguments.
pub fn run_small(scene: &str, resolution: u32, frames: u32, out: &Path, extra: &[&str]) -> Output {
    let (r, f) = (resolution.to_string(), frames.to_string());
    let mut args = vec!["run", scene, "--resolution", &r, "--frames", &f];
    let out = out.to_str().expect("UTF-8 path");
    args.extend(["--out", out]);
    args.extend(extra);
    polyphase(&args)
}

/// `polyphase run FILE --out OUT`.
pub fn run_file(file: &Path, out: &Path) -> Output {
    polyphase(&[
        "run",
        file.to_str().expect("UTF-8 path"),
        "--out",
        out.to_str().expect("UTF-8 path"),
    ])
}
