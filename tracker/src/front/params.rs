//! User bounds of the front tracker's remeshing and time integration (paper 000 Appendix A:
//! "we expose the angle bounds, edge length bounds, minimum area bound, and volume change
//! bound as user parameters"), readable from a scene's `[tracker.front]` table.

use serde::{Deserialize, Serialize};

/// Time integrator of the vertex trajectories (paper 000 §4.1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Midpoint rule, second order.
    Rk2,
    /// Classical Runge–Kutta, fourth order.
    #[default]
    Rk4,
}

/// Remeshing and integration parameters. Lengths are relative to the target edge length `L`
/// ([`FrontParams::edge_length`], or the mean interface edge length of the initial mesh), so
/// one set of defaults serves every resolution.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrontParams {
    /// Target edge length `L` in domain units; `None`: the mean interface edge length of the
    /// mesh the tracker starts from (a scene's grid spacing `h`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_length: Option<f64>,
    /// Largest step, as a multiple of `L / (max speed)`: vertices move at most `cfl` target
    /// edge lengths per step, which keeps collision resolution local. Unset: 1, which scenes
    /// fill in for coupled runs and mesh-driven flows, and [`PASSIVE_CFL`] for velocity fields.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cfl: Option<f64>,
    /// Edges shorter than `min_edge * L` are collapsed (default 0.5, Brochu & Bridson 2009).
    pub min_edge: f64,
    /// Edges longer than `max_edge * L` are split; no operation may create a longer edge
    /// (default 1.5, Brochu & Bridson 2009).
    pub max_edge: f64,
    /// Smallest triangle angle (degrees) an operation may create unless it improves on the
    /// worst angle it removes (default 3°).
    pub min_angle: f64,
    /// Largest triangle angle (degrees) an operation may create unless it improves on the
    /// worst angle it removes (default 170°).
    pub max_angle: f64,
    /// Smallest triangle area an operation may create, relative to `L²`, unless it improves on
    /// the smallest area around it (default 1e-4; without the exception a cluster of tiny
    /// triangles could never be collapsed away, each collapse leaving tiny ones behind). The
    /// exception raised `laplace2_front`'s spurious currents from 5.7e-5 to 6.7e-5 m/s; kept
    /// for tiny-edge collapses only, it failed three tests (`enright` 24³ came back 2.25 h off,
    /// `merge2_reverse` kept 2.5 % of a liquid, the midpoint-flux test lost 1.5× more).
    pub min_area: f64,
    /// Largest change of any phase volume one operation may cause, relative to `L³`
    /// (default 0.02: a collapse on a smooth surface moves far less, a collapse across a
    /// sharp feature more).
    pub max_volume_change: f64,
    /// Dihedral angle (degrees) above which a manifold edge is a feature edge (default 30°,
    /// paper 000 Appendix A).
    pub feature_angle: f64,
    /// Angles (degrees) outside `[poor_angle, 180 - poor_angle]` trigger the fail-safe pass
    /// of Appendix A.4 that ignores every bound except collision safety (default 2°).
    pub poor_angle: f64,
    /// Splits place the new vertex at the butterfly subdivision point of a smooth regular
    /// neighbourhood instead of the edge midpoint (default off: measured on `enright` at 32³,
    /// the shape came back 3.5 h off instead of 1.1 h, for no volume gained).
    pub butterfly: bool,
    /// Null-space smoothing passes per step (default 1; 0 disables smoothing).
    pub smoothing_passes: u32,
    /// Vertex trajectory integrator (default RK4).
    pub integrator: Integrator,
    /// In a velocity field, vertices also move by the normal part of their triangles' flux
    /// defect, so that each triangle sweeps the edge-midpoint rule's flux, exact for quadratic
    /// velocities, instead of its corners' (default on; `front_tracker/flux.rs`).
    pub midpoint_flux: bool,
    /// Greatest number of times a step's motion is halved when collision resolution fails
    /// before the unresolvable part of the motion is dropped (default 4).
    pub max_substep_depth: u32,
    /// Puts the start on the initial shapes' exact interface: its remeshing collapses edges a
    /// little past the steps' bound, so the first steps find none at the bound, and its
    /// vertices then move along their normals onto the interface (`front_tracker/
    /// onto_initial.rs`). Unset: on in scenes with surface tension, whose forces read the
    /// mesh's curvature (`laplace2_front`'s spurious currents 6.7e-5 → 4.1e-6 m/s), off
    /// elsewhere: on everywhere, `enright` at 24³ came back 2.63 h off instead of 0.63 h, its
    /// worst liquid −2.2 % from its first mesh instead of +0.42 % (`tests/front.rs` allows 2 h).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exact_start: Option<bool>,
    /// Surfaces closer than `merge_distance * L` are snapped together (paper 000 §6.2, whose
    /// threshold is the user's): liquids that meet merge, different ones get an interface; 0
    /// turns merging off. Default: 0.3 for mesh-driven flows that bring surfaces together
    /// (normal flows, curl noise), off in velocity fields, passive and coupled: passive tests
    /// measure the tracker without it (merging took 0.4 s of 0.55 s per frame of `enright`
    /// at 24³), and in coupled runs the T2 removal of the air pockets merging traps took
    /// minutes per frame (`balls` at 64). Set it to merge there too; in a velocity field only
    /// films of the background phase close.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub merge_distance: Option<f64>,
    /// Regions smaller than `min_region_volume * L³` are removed, their space given to their
    /// neighbours (a T2 process, §5.2; default 0.125, a cube of half the edge length).
    pub min_region_volume: f64,
}

impl Default for FrontParams {
    fn default() -> Self {
        FrontParams {
            edge_length: None,
            cfl: None,
            min_edge: 0.5,
            max_edge: 1.5,
            min_angle: 3.0,
            max_angle: 170.0,
            min_area: 1e-4,
            max_volume_change: 0.02,
            feature_angle: 30.0,
            poor_angle: 2.0,
            butterfly: false,
            smoothing_passes: 1,
            integrator: Integrator::Rk4,
            midpoint_flux: true,
            max_substep_depth: 4,
            exact_start: None,
            merge_distance: None,
            min_region_volume: 0.125,
        }
    }
}

/// `cfl` of passive runs in a velocity field, as the paper's code moves about 3 L a step
/// (`enright` at edge 0.005 to t = 0.8: 136 steps against 392 at 1, the same volume within
/// 0.0023 % of the first mesh). Coupled runs keep 1: the mesh follows the fluid once per `cfl`
/// L of travel, and at 3 the `dambreak_column` surge of `tests/front_coupled.rs` fell 2.1
/// tracker cells behind.
pub const PASSIVE_CFL: f64 = 3.0;

impl FrontParams {
    /// The step bound `cfl` in L (1 when unset).
    pub fn cfl(&self) -> f64 {
        self.cfl.unwrap_or(1.0)
    }

    /// Rejects contradictory or out-of-range parameters, saying which.
    pub fn validate(&self) -> Result<(), String> {
        let p = self;
        let bad = |what: &str| Err(what.to_string());
        if let Some(l) = p.edge_length {
            if !(l > 0.0 && l.is_finite()) {
                return bad("edge_length must be positive");
            }
        }
        if !p.cfl.is_none_or(|c| c > 0.0 && c.is_finite()) {
            return bad("cfl must be positive");
        }
        if !(p.min_edge > 0.0 && p.min_edge * 2.0 < p.max_edge) {
            return bad("need 0 < min_edge and 2 min_edge < max_edge (splits must not create edges to collapse)");
        }
        if !(0.0 <= p.min_angle && p.min_angle < 60.0 && 60.0 < p.max_angle && p.max_angle <= 180.0)
        {
            return bad("need 0 <= min_angle < 60 < max_angle <= 180");
        }
        if !(p.min_area >= 0.0 && p.max_volume_change >= 0.0) {
            return bad("min_area and max_volume_change must not be negative");
        }
        if !(0.0 < p.feature_angle && p.feature_angle < 180.0 && 0.0 <= p.poor_angle) {
            return bad("need 0 < feature_angle < 180 and poor_angle >= 0");
        }
        // A merge distance near L would let a surface snap onto its own neighbouring faces
        // beyond the adjacent-triangle fold rule of §6.2.
        if !p.merge_distance.is_none_or(|d| (0.0..=0.5).contains(&d)) {
            return bad("need 0 <= merge_distance <= 0.5");
        }
        if !(p.min_region_volume >= 0.0 && p.min_region_volume.is_finite()) {
            return bad("min_region_volume must not be negative");
        }
        Ok(())
    }
}

/// The bounds in absolute units for a target edge length, as the remeshing operations use them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    pub min_edge: f64,
    pub max_edge: f64,
    /// Cosine of the smallest allowed angle.
    pub cos_min_angle: f64,
    /// Cosine of the largest allowed angle.
    pub cos_max_angle: f64,
    pub min_area: f64,
    pub max_volume_change: f64,
    /// Cosine of the feature dihedral angle.
    pub cos_feature: f64,
    /// Cosine of the fail-safe poor angle.
    pub cos_poor: f64,
}

impl Bounds {
    /// Absolute bounds for target edge length `l`.
    pub fn new(p: &FrontParams, l: f64) -> Bounds {
        Bounds {
            min_edge: p.min_edge * l,
            max_edge: p.max_edge * l,
            cos_min_angle: p.min_angle.to_radians().cos(),
            cos_max_angle: p.max_angle.to_radians().cos(),
            min_area: p.min_area * l * l,
            max_volume_change: p.max_volume_change * l * l * l,
            cos_feature: p.feature_angle.to_radians().cos(),
            cos_poor: p.poor_angle.to_radians().cos(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partial_tables_keep_the_other_defaults() {
        let p: FrontParams = toml::from_str("min_edge = 0.4\nintegrator = \"rk2\"").expect("valid");
        assert_eq!(p.min_edge, 0.4);
        assert_eq!(p.integrator, Integrator::Rk2);
        assert_eq!(p.max_edge, FrontParams::default().max_edge);
        assert_eq!(p.edge_length, None);
    }

    #[test]
    fn unknown_keys_are_refused() {
        let err = toml::from_str::<FrontParams>("max_edges = 2.0").unwrap_err();
        assert!(err.to_string().contains("max_edges"), "{err}");
    }
}
