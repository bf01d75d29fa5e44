//! The function the contouring tracker samples: φ (distance) and χ (phase) at a point.

use glam::DVec3;
use polyphase_grid::PhaseId;

/// Exact (or lower-bound) unsigned distance φ to the interface and phase χ at a point.
///
/// In the semi-Lagrangian tracker this is "backtrace, then query the previous mesh"
/// (paper 004 §3–4); in tests an analytic shape. A lower bound on the distance is enough:
/// the tree's split rule and the bisection brackets (§5.2, §6.2) only rely on
/// "no interface lies closer to `x` than φ(x)".
pub trait PhaseSampler: Sync {
    /// φ(x) ≥ 0 and χ(x) at the point `x`.
    fn sample(&self, x: DVec3) -> (f64, PhaseId);

    /// [`PhaseSampler::sample`] where φ(x) < `reach`; elsewhere χ as exactly, but φ may be any
    /// lower bound of at least `reach`. The tree's build asks no more of its far nodes (§6.2:
    /// a centre only decides whether φ < 2·h_cell), so a sampler may skip the far search.
    fn sample_near(&self, x: DVec3, reach: f64) -> (f64, PhaseId) {
        let _ = reach;
        self.sample(x)
    }
}

impl<F: Fn(DVec3) -> (f64, PhaseId) + Sync> PhaseSampler for F {
    fn sample(&self, x: DVec3) -> (f64, PhaseId) {
        self(x)
    }
}
