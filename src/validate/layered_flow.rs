//! The exact steady velocity of plane layers sheared between two walls: the reference of the
//! `profile` metric (two-layer Couette and Poiseuille flow).
//!
//! Layers k between coordinates s_k and s_{k+1} across the channel (s from the low wall, width
//! H) have viscosity μ_k and feel the body force f_k = ρ_k·g along the walls; the walls move
//! at u_low and u_high. Steady momentum along the walls, dτ/ds + f = 0, with the shear stress
//! τ = μ du/ds continuous across each interface (Batchelor 1967, §4.2, for one layer), gives
//! τ(s) = τ₀ − F(s), F(s) = ∫₀^s f, and
//!   u(s) = u_low + τ₀·A(s) − B(s),  A(s) = ∫₀^s dσ/μ,  B(s) = ∫₀^s F(σ)/μ dσ,
//! both piecewise in closed form (F is linear in each layer, so B is quadratic there);
//! u(H) = u_high fixes τ₀ = (u_high − u_low + B(H))/A(H).

use anyhow::{ensure, Result};

/// One layer: where it ends (coordinate from the low wall), its viscosity and body force per
/// unit volume along the walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layer {
    pub top: f64,
    pub viscosity: f64,
    pub force: f64,
}

/// The exact profile of [`Layer`]s (lowest first, the last one's top is the channel width)
/// between walls moving at `walls` = (u_low, u_high).
#[derive(Clone, Debug)]
pub struct LayeredFlow {
    layers: Vec<Layer>,
    low: f64,
    tau0: f64,
}

impl LayeredFlow {
    /// Checks the layers (increasing tops, positive viscosities, finite forces) and solves for
    /// the wall stress.
    pub fn new(layers: Vec<Layer>, walls: (f64, f64)) -> Result<Self> {
        ensure!(
            !layers.is_empty(),
            "a layered flow needs at least one layer"
        );
        let mut bottom = 0.0;
        for (k, l) in layers.iter().enumerate() {
            ensure!(
                l.top > bottom && l.top.is_finite(),
                "layer {k}: its top {} must lie above its bottom {bottom}",
                l.top
            );
            ensure!(
                l.viscosity > 0.0 && l.viscosity.is_finite(),
                "layer {k}: viscosity {} must be positive (an inviscid layer has no steady \
                 shear profile)",
                l.viscosity
            );
            ensure!(l.force.is_finite(), "layer {k}: body force is not finite");
            bottom = l.top;
        }
        let mut flow = Self {
            layers,
            low: walls.0,
            tau0: 0.0,
        };
        let width = bottom;
        let (a, b) = flow.integrals(width);
        flow.tau0 = (walls.1 - walls.0 + b) / a;
        Ok(flow)
    }

    /// (A(s), B(s)) of the module doc.
    fn integrals(&self, s: f64) -> (f64, f64) {
        let (mut a, mut b, mut f, mut bottom) = (0.0, 0.0, 0.0, 0.0);
        for l in &self.layers {
            let d = (s.min(l.top) - bottom).max(0.0);
            a += d / l.viscosity;
            b += (f * d + 0.5 * l.force * d * d) / l.viscosity;
            f += l.force * d;
            bottom = l.top;
            if s <= l.top {
                break;
            }
        }
        (a, b)
    }

    /// The velocity at coordinate `s` from the low wall.
    pub fn velocity(&self, s: f64) -> f64 {
        let (a, b) = self.integrals(s);
        self.low + self.tau0 * a - b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_layer_gives_plane_couette_and_poiseuille_flow() {
        let couette = one_layer(0.5, 0.0, (0.0, 2.0));
        assert!((couette.velocity(0.25) - 0.5).abs() < 1e-15);
        // Poiseuille: u = f s (H − s)/(2μ), H = 1, μ = 0.5, f = 1: u(0.5) = 0.25.
        let poiseuille = one_layer(0.5, 1.0, (0.0, 0.0));
        assert!((poiseuille.velocity(0.5) - 0.25).abs() < 1e-15);
        assert!(poiseuille.velocity(1.0).abs() < 1e-15);
    }

    #[test]
    fn two_layers_share_the_stress_at_the_interface() {
        // Couette with μ 1 below 0.4 and 10 above: τ = U/(0.4/1 + 0.6/10) = 1/0.46, so the
        // interface moves at 0.4 τ.
        let flow = LayeredFlow::new(
            vec![
                Layer {
                    top: 0.4,
                    viscosity: 1.0,
                    force: 0.0,
                },
                Layer {
                    top: 1.0,
                    viscosity: 10.0,
                    force: 0.0,
                },
            ],
            (0.0, 1.0),
        )
        .unwrap();
        assert!((flow.velocity(0.4) - 0.4 / 0.46).abs() < 1e-14);
        assert!((flow.velocity(1.0) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn bad_layers_are_refused_with_the_reason() {
        let layer = |top, viscosity| Layer {
            top,
            viscosity,
            force: 0.0,
        };
        let err = LayeredFlow::new(vec![layer(0.5, 1.0), layer(0.4, 1.0)], (0.0, 1.0))
            .unwrap_err()
            .to_string();
        assert!(err.contains("layer 1: its top 0.4 must lie above"), "{err}");
        let err = LayeredFlow::new(vec![layer(1.0, 0.0)], (0.0, 1.0))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("layer 0: viscosity 0 must be positive"),
            "{err}"
        );
    }

    /// One layer of width 1.
    fn one_layer(viscosity: f64, force: f64, walls: (f64, f64)) -> LayeredFlow {
        let layer = Layer {
            top: 1.0,
            viscosity,
            force,
        };
        LayeredFlow::new(vec![layer], walls).unwrap()
    }
}
