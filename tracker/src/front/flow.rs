//! Mesh-driven motion (paper 000 §8): velocities computed from the labeled mesh itself rather
//! than read from a field — constant-speed normal flow per pair of phases (§8.2, with
//! area-weighted vertex normals or face offsetting), mean-curvature flow (§8.4) and normal
//! flow alternating with curl noise (§8.1, Fig. 21). Only the front tracker can follow them:
//! an implicit tracker has no mesh to differentiate.

mod curl_noise;
mod curvature;
mod normal;
mod offset;

use glam::DVec3;
use polyphase_grid::PhaseId;

pub use self::curl_noise::CurlNoise;
use super::connectivity::Connectivity;

/// The interface between `from` and `into` moves along its normal, from `from` into `into`, at
/// `speed` (negative: the other way). Interfaces of pairs not listed stand still, as do those
/// that collisions create (paper 000 §8.2: new interfaces get speed 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairSpeed {
    pub from: PhaseId,
    pub into: PhaseId,
    pub speed: f64,
}

/// A motion of the mesh computed from the mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum MeshFlow {
    /// Constant-speed normal flow with area-weighted vertex normals (§8.1, §8.3).
    Normal(Vec<PairSpeed>),
    /// Constant-speed normal flow by face offsetting (Jiao 2007), as paper 000 §8.2 uses for
    /// the cyclic case: each vertex moves so that its faces move by their own offsets.
    NormalOffset(Vec<PairSpeed>),
    /// Mean-curvature flow, the gradient flow of the total interface area (§8.4, Meyer et
    /// al. 2002 over all incident triangles), scaled by `rate` (m²/s; 1 gives r² = r0² − 4t
    /// for a sphere).
    MeanCurvature { rate: f64 },
    /// Steps of curl noise alternating with steps of area-weighted normal flow (§8.1).
    NoiseAndNormal {
        noise: CurlNoise,
        speeds: Vec<PairSpeed>,
    },
}

/// What one substep of a flow does.
pub enum FlowStep<'a> {
    /// Every vertex moves at its own velocity, held over the substep (explicit Euler).
    Vertices(Vec<DVec3>),
    /// The vertices follow a velocity field (integrated like a passive run's).
    Field(&'a CurlNoise),
}

impl MeshFlow {
    /// The motion of substep number `step` of the mesh in `c`.
    pub fn step(&self, c: &Connectivity, step: u64) -> FlowStep<'_> {
        match self {
            MeshFlow::Normal(speeds) => FlowStep::Vertices(normal::velocities(c, speeds)),
            MeshFlow::NormalOffset(speeds) => FlowStep::Vertices(offset::velocities(c, speeds)),
            MeshFlow::MeanCurvature { rate } => FlowStep::Vertices(curvature::velocities(c, *rate)),
            MeshFlow::NoiseAndNormal { noise, speeds } => {
                if step % 2 == 0 {
                    FlowStep::Field(noise)
                } else {
                    FlowStep::Vertices(normal::velocities(c, speeds))
                }
            }
        }
    }

    /// Largest substep that keeps the explicit update stable with the shortest live edge
    /// `shortest`: mean-curvature flow is a diffusion of the positions, stable for
    /// dt ≤ ℓ²/(rate·λ) with λ ≈ 8 for the cotangent Laplacian of equilateral triangles
    /// (the largest eigenvalue of the one-ring stencil, 2·6·cot 60°/(√3/2)); we take a
    /// fifth of ℓ²/rate, a safety factor of 1.6 below that. Normal flows need none beyond
    /// the travel limit.
    pub fn stable_dt(&self, shortest: f64) -> f64 {
        match self {
            MeshFlow::MeanCurvature { rate } => 0.2 * shortest * shortest / rate.abs().max(1e-300),
            _ => f64::INFINITY,
        }
    }

    /// Whether T1 processes follow this flow, and how their strength is measured: mean
    /// curvature minimises area (§5.1.6); the paper gives normal flows no separation rule.
    pub fn separates_by_area(&self) -> bool {
        matches!(self, MeshFlow::MeanCurvature { .. })
    }
}

/// Speed of the interface of triangle labels `[front, back]` along the triangle's normal
/// (which points into `front`): positive when it moves toward `front`.
fn normal_speed(speeds: &[PairSpeed], [front, back]: [PhaseId; 2]) -> f64 {
    speeds
        .iter()
        .find_map(|p| {
            if p.from == back && p.into == front {
                Some(p.speed)
            } else if p.from == front && p.into == back {
                Some(-p.speed)
            } else {
                None
            }
        })
        .unwrap_or(0.0)
}

#[cfg(test)]
mod tests;
