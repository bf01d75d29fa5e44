//! Metrics of the contouring tracker's first step that need no run (paper 004 §7.2, Table 2):
//! the tree is built from the scene's exact shapes, and its indicator is compared with the
//! exact one at random points.
//!
//! `indicator_accuracy`: the share of points whose phase is right, judged by the share that is
//! wrong: the error is how many more mismatches we make than the paper (relative).
//! `indicator_mismatch_distance`: the largest distance of a wrong point from the interface in
//! cells (the paper's e_i), against the paper's.

use anyhow::{bail, Context, Result};
use polyphase_scenes::Scene;

use super::case::MetricSpec;
use super::metrics::Outcome;
use crate::bench::ContourRow;

/// The paper's sample count (Table 2: 10 000 000 points per test).
const PAPER_SAMPLES: usize = 10_000_000;

/// Whether a metric kind is evaluated without running the scene.
pub fn is_static(kind: &str) -> bool {
    matches!(kind, "indicator_accuracy" | "indicator_mismatch_distance")
}

/// The first step's measurements, made once for all static metrics of a case.
pub struct FirstStep {
    row: ContourRow,
    resolution: i64,
}

impl FirstStep {
    /// Builds the tracker of `scene` from its exact shapes and samples `samples` points.
    pub fn measure(scene: &Scene, samples: Option<usize>) -> FirstStep {
        FirstStep {
            row: crate::bench::contour_row(scene, samples.unwrap_or(PAPER_SAMPLES)),
            resolution: scene.file.resolution,
        }
    }

    /// Evaluates one static metric against the row of its `table` at this resolution.
    pub fn evaluate(&self, spec: &MetricSpec, quick: bool) -> Result<Outcome> {
        let table = spec.table.as_deref().with_context(|| {
            format!(
                "metric '{}' ({}) needs `table` ([resolution, accuracy %, e_i] rows)",
                spec.name, spec.kind
            )
        })?;
        let &[_, percent, e_i] = table
            .iter()
            .find(|r| r[0] == self.resolution as f64)
            .with_context(|| {
                format!(
                    "metric '{}': `table` has no row for resolution {}",
                    spec.name, self.resolution
                )
            })?;
        let tolerance = spec.tolerance_for(quick);
        let (ours, reference, error) = match spec.kind.as_str() {
            "indicator_accuracy" => {
                let ours = 100.0 * self.row.indicator_accuracy;
                (ours, percent, (100.0 - ours) / (100.0 - percent) - 1.0)
            }
            "indicator_mismatch_distance" => {
                let ours = self.row.max_mismatch_over_h;
                (ours, e_i, ours / e_i - 1.0)
            }
            other => bail!("metric '{}': '{other}' is not a first-step kind", spec.name),
        };
        Ok(Outcome {
            metric: spec.name.clone(),
            ours,
            reference,
            error,
            tolerance,
            pass: error.is_finite() && error <= tolerance,
            plot: None,
            note: Some(format!(
                "{}³, first step from the exact shapes",
                self.resolution
            )),
            known_gap: spec.gap(quick),
        })
    }
}
