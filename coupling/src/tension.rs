//! Surface tension in a coupled step (ARCHITECTURE.md "Surface tension"): the Laplace jump
//! σ_ab·κ at every solver face an a–b interface crosses, κ measured on the tracker's labelled
//! mesh, and the capillary time-step limit.
//!
//! The jump is applied sharply in the projection (ghost-fluid jump condition, `solver/src/
//! jump.rs`), so a drop whose measured κ is uniform is balanced exactly: no force is smeared
//! over cells, and the spurious currents are those of κ's own error. Each face gets the σ of the
//! two phases on its sides; where three phases meet, the triple curve is pulled by the three
//! tensions together (`line_tension.rs`), which sets the angles between the interfaces.

use glam::DVec3;
use polyphase_scenes::Tension;
use polyphase_solver::{InterfaceFace, PhaseProps, PointForces, PressureJumps};
use polyphase_tracker::curvature::CurvatureSampler;
use polyphase_tracker::LabeledMesh;
use rayon::prelude::*;

use crate::line_tension::triple_curve_forces;

/// The tension of a scene and the curvature of the tracker's current mesh.
pub struct SurfaceTension {
    tension: Tension,
    /// Fitting neighbourhood of the curvature (m).
    fit_radius: f64,
    /// The axis a slab (2D) scene is extruded along: κ is then the section's curvature.
    extrusion: Option<usize>,
    sampler: Option<CurvatureSampler>,
    /// The pull on the current mesh's triple curves.
    lines: PointForces,
}

/// What [`SurfaceTension::jumps`] did at one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JumpStats {
    /// Interface faces with a tension.
    pub faces: usize,
    /// Of those, faces where no interface of their pair lay within reach of the crossing
    /// (no jump applied there).
    pub missed: usize,
}

impl SurfaceTension {
    /// The scene's tensions, with curvature fitted over `fit_radius` metres of the mesh; for
    /// a 2D scene run as a slab, `extrusion` is the slab's thin axis
    /// ([`CurvatureSampler::extruded_along`]).
    pub fn new(tension: Tension, fit_radius: f64, extrusion: Option<usize>) -> SurfaceTension {
        SurfaceTension {
            tension,
            fit_radius,
            extrusion,
            sampler: None,
            lines: PointForces::default(),
        }
    }

    /// Measures the curvature and the triple curves of a new mesh (after every tracker step).
    pub fn refresh(&mut self, mesh: &LabeledMesh) {
        let tension = &self.tension;
        // Directions fitted over 1.5 curvature radii (6 tracker cells in the coupled scenes):
        // over 4, the noise of the sheets next to a triple point pulled one end of an oil lens
        // in (`validation/lens2`: width −9 % at 0.2 s); over 6 the lens holds Neumann's shape
        // to 7 %.
        self.lines = PointForces::new(triple_curve_forces(mesh, 1.5 * self.fit_radius, |a, b| {
            tension.sigma(a, b)
        }));
        let sampler = CurvatureSampler::new(mesh, self.fit_radius);
        self.sampler = Some(match self.extrusion {
            Some(axis) => sampler.extruded_along(axis),
            None => sampler,
        });
    }

    /// The Laplace jump at each of `faces`: J = p_above − p_below = −σ_ab·κ_below, where
    /// κ_below is the curvature of the interface seen from the phase below (a convex drop of
    /// it: κ > 0, its pressure higher by σκ). The mesh is read at `locate(crossing)`, the
    /// crossing traced back to the mesh's time (as φ and χ are), within `reach` metres.
    pub fn jumps(
        &self,
        faces: &[InterfaceFace],
        locate: impl Fn(DVec3) -> DVec3 + Sync,
        reach: f64,
    ) -> (PressureJumps, JumpStats) {
        let Some(sampler) = &self.sampler else {
            return (PressureJumps::default(), JumpStats::default());
        };
        // One fit per face, in parallel; collected in face order, so any thread count gives
        // the same jumps.
        let fitted: Vec<(InterfaceFace, Option<f64>)> = faces
            .par_iter()
            .filter_map(|face| {
                let sigma = self.tension.sigma(face.below, face.above);
                (sigma != 0.0).then(|| {
                    let kappa = sampler.at(locate(face.crossing), face.below, face.above, reach);
                    (*face, kappa.map(|k| -sigma * k))
                })
            })
            .collect();
        let stats = JumpStats {
            faces: fitted.len(),
            missed: fitted.iter().filter(|(_, j)| j.is_none()).count(),
        };
        let jumps = fitted.into_iter().filter_map(|(f, j)| Some((f, j?)));
        (PressureJumps::new(jumps), stats)
    }

    /// The pull of the tensions on the current mesh's triple curves
    /// ([`triple_curve_forces`]), none without any.
    pub fn line_forces(&self) -> &PointForces {
        &self.lines
    }

    /// Half the capillary time-step limit of Brackbill, Kothe & Zemach (1992), Eq. (61),
    /// √(ρ̄·h³ / (2π·σ)) with ρ̄ the mean density of the pair, over every pair with a tension
    /// (∞ without any): the step must resolve the fastest capillary wave the grid carries.
    /// At the full limit a static water drop in air (32 cells across) grew spurious currents
    /// from 1e-5 to 2e-3 m/s in 100 steps; at half it stays 25 times lower.
    pub fn capillary_dt(&self, phases: &[PhaseProps], h: f64) -> f64 {
        self.tension
            .pairs()
            .into_iter()
            .map(|(a, b, sigma)| {
                let mean = 0.5 * (phases[usize::from(a)].density + phases[usize::from(b)].density);
                0.5 * (mean * h.powi(3) / (2.0 * std::f64::consts::PI * sigma)).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }
}
