//! The end-of-run summary: one table on the terminal and the same figures in `stats.jsonl`.

use std::fmt::Write;

use polyphase_tracker::{LabeledMesh, StepStats};
use serde_json::{json, Value};

/// Totals gathered over a run.
pub struct Summary {
    names: Vec<String>,
    stages: Vec<(String, f64)>,
    frames: usize,
    steps: usize,
    wall: f64,
    drift: Vec<f64>,
    vertices: usize,
    triangles: usize,
    /// Pressure and viscosity CG iterations of a coupled run.
    solver_iterations: Option<(usize, usize)>,
}

impl Summary {
    pub fn new(names: &[String]) -> Summary {
        Summary {
            names: names.to_vec(),
            stages: Vec::new(),
            frames: 0,
            steps: 0,
            wall: 0.0,
            drift: Vec::new(),
            vertices: 0,
            triangles: 0,
            solver_iterations: None,
        }
    }

    /// Adds one step's stage timings.
    pub fn add_step(&mut self, step: &StepStats) {
        for &(name, secs) in &step.stages {
            self.add_stage(name, secs);
        }
    }

    /// Adds `secs` to stage `name` (a new stage goes last).
    pub fn add_stage(&mut self, name: &str, secs: f64) {
        match self.stages.iter_mut().find(|(n, _)| n == name) {
            Some(entry) => entry.1 += secs,
            None => self.stages.push((name.to_string(), secs)),
        }
    }

    /// Seconds per stage so far, in the order the stages first ran (kept by checkpoints).
    pub fn stages(&self) -> &[(String, f64)] {
        &self.stages
    }

    /// Records the solver's total CG iterations (pressure, viscosity) of a coupled run.
    pub fn set_solver_iterations(&mut self, pressure: usize, viscosity: usize) {
        self.solver_iterations = Some((pressure, viscosity));
    }

    /// Records the final state: relative volume drift against the reference volumes.
    pub fn finish(
        &mut self,
        frames: usize,
        steps: usize,
        wall: f64,
        reference: &[f64],
        volumes: &[f64],
        mesh: &LabeledMesh,
    ) {
        self.frames = frames;
        self.steps = steps;
        self.wall = wall;
        self.drift = volumes
            .iter()
            .zip(reference)
            .map(|(v, r)| if *r > 0.0 { (v - r) / r } else { 0.0 })
            .collect();
        self.vertices = mesh.vertices.len();
        self.triangles = mesh.triangles.len();
    }

    /// The terminal table.
    pub fn table(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "frames {}  steps {}  wall {:.2} s  final mesh {} vertices, {} triangles",
            self.frames, self.steps, self.wall, self.vertices, self.triangles
        );
        if let Some((p, v)) = self.solver_iterations {
            let _ = writeln!(s, "solver CG iterations: pressure {p}, viscosity {v}");
        }
        let _ = writeln!(s, "{:<16} {:>10}", "stage", "seconds");
        for (name, secs) in &self.stages {
            let _ = writeln!(s, "{name:<16} {secs:>10.3}");
        }
        let _ = writeln!(s, "{:<16} {:>10}", "phase", "vol drift");
        for (name, d) in self.names.iter().zip(&self.drift) {
            let _ = writeln!(s, "{name:<16} {:>9.4}%", d * 100.0);
        }
        s
    }

    /// The same figures as one JSON line.
    pub fn json(&self) -> Value {
        let stages: serde_json::Map<String, Value> = self
            .stages
            .iter()
            .map(|(n, t)| (n.clone(), json!(t)))
            .collect();
        let drift: serde_json::Map<String, Value> = self
            .names
            .iter()
            .zip(&self.drift)
            .map(|(n, d)| (n.clone(), json!(d)))
            .collect();
        let iterations = self
            .solver_iterations
            .map(|(p, v)| json!({ "pressure": p, "viscosity": v }));
        json!({
            "summary": {
                "solver_iterations": iterations,
                "frames": self.frames,
                "steps": self.steps,
                "wall_s": self.wall,
                "stage_s": stages,
                "volume_drift": drift,
                "mesh": { "vertices": self.vertices, "triangles": self.triangles },
                "process": {
                    "peak_rss_mb": crate::resources::peak_rss_bytes().map(|b| b as f64 / 1e6),
                    "cpu_s": crate::resources::cpu_seconds(),
                },
            }
        })
    }
}
