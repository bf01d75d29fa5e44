//! The solver steps a tracker step has not applied yet, each with the interface velocity of
//! its own interval. The tracker and the solver's samples follow trajectories through the
//! velocity as it changed step by step: a single time-averaged field moves an accelerating
//! interface along the wrong path (the `rayleigh_taylor_re256` spike at 32 cells per
//! wavelength ended 0.015 W higher with the tracker stepping every 8 of its cells than every
//! cell).

use glam::DVec3;
use polyphase_grid::VelocityField;
use polyphase_solver::MacGrid;

/// Solver steps since the last tracker step, in time order, starting at `start`.
pub struct PendingSteps {
    start: f64,
    /// (dt, the interface velocity over that step).
    steps: Vec<(f64, MacGrid)>,
    travel: f64,
}

impl PendingSteps {
    /// No steps yet, starting at time `start`.
    pub fn new(start: f64) -> Self {
        Self {
            start,
            steps: Vec::new(),
            travel: 0.0,
        }
    }

    /// Appends a step of `dt` with `velocity` (its largest component bounds its travel).
    pub fn push(&mut self, dt: f64, velocity: MacGrid) {
        self.travel += dt * velocity.max_abs();
        self.steps.push((dt, velocity));
    }

    /// Time at the first step's start.
    pub fn start(&self) -> f64 {
        self.start
    }

    /// Summed dt of the steps.
    pub fn duration(&self) -> f64 {
        self.steps.iter().map(|(dt, _)| dt).sum()
    }

    /// An upper bound of how far the fluid has moved over the steps (m).
    pub fn travel(&self) -> f64 {
        self.travel
    }
}

impl VelocityField for PendingSteps {
    /// The velocity of the step whose interval holds `t` (the first or last before or after
    /// them).
    fn velocity(&self, x: DVec3, t: f64) -> DVec3 {
        let mut end = self.start;
        for (dt, v) in &self.steps {
            end += dt;
            if t <= end {
                return v.sample(x);
            }
        }
        self.steps.last().map_or(DVec3::ZERO, |(_, v)| v.sample(x))
    }

    /// Traces back through the steps overlapping [t, t + dt], latest first, each with RK4 in
    /// its own (stationary) velocity over its part of the interval.
    fn departure(&self, mut x: DVec3, t: f64, dt: f64) -> DVec3 {
        let mut ends = Vec::with_capacity(self.steps.len());
        let mut end = self.start;
        for (step, _) in &self.steps {
            end += step;
            ends.push(end);
        }
        for ((step, v), &b) in self.steps.iter().zip(&ends).rev() {
            let (lo, hi) = ((b - step).max(t), b.min(t + dt));
            if hi > lo {
                x = v.departure(x, lo, hi - lo);
            }
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use polyphase_grid::GridSpec;
    use polyphase_solver::{Solver, SolverConfig};

    /// A uniform field of `u` on the unit cube, 4³ cells.
    fn uniform(u: DVec3) -> MacGrid {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 0.25,
            dims: [4, 4, 4],
        };
        let mut m = Solver::new(SolverConfig::closed_box(grid))
            .unwrap()
            .velocity()
            .clone();
        for a in 0..3 {
            m.component_mut(a).fill(u[a]);
        }
        m
    }

    #[test]
    fn departure_follows_each_step_in_turn() {
        // 0.1 s at +x then 0.2 s at +y: the point reached at 0.3 s left from 0.1 back in y
        // and 0.05 back in x, whatever the order of the average would say.
        let mut p = PendingSteps::new(1.0);
        p.push(0.1, uniform(DVec3::new(0.5, 0.0, 0.0)));
        p.push(0.2, uniform(DVec3::new(0.0, 0.5, 0.0)));
        let x = DVec3::new(0.5, 0.5, 0.5);
        let d = p.departure(x, 1.0, 0.3);
        assert!(d.distance(DVec3::new(0.45, 0.4, 0.5)) < 1e-12, "{d}");
        // Over the second step alone only the y motion counts.
        let d = p.departure(x, 1.1, 0.2);
        assert!(d.distance(DVec3::new(0.5, 0.4, 0.5)) < 1e-12, "{d}");
        assert!((p.duration() - 0.3).abs() < 1e-15);
        assert!((p.travel() - 0.15).abs() < 1e-15);
        assert_eq!(p.velocity(x, 1.05), DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(p.velocity(x, 1.25), DVec3::new(0.0, 0.5, 0.0));
    }
}
