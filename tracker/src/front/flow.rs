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
    /// Constant-speed normal flow with area-weighted vertex normals (§8.1, §8.3); from
    /// `reverse_at` on (if given) every speed changes sign, as in paper 000 §8.2's reversed
    /// Fig. 15, where the merged spheres shrink until they vanish.
    Normal {
        speeds: Vec<PairSpeed>,
        reverse_at: Option<f64>,
    },
    /// Constant-speed normal flow by face offsetting (Jiao 2007), as paper 000 §8.2 uses:
    /// each vertex moves so that its faces move by their own offsets; reversed from
    /// `reverse_at` on as [`MeshFlow::Normal`].
    NormalOffset {
        speeds: Vec<PairSpeed>,
        reverse_at: Option<f64>,
    },
    /// Mean-curvature flow, the gradient flow of the total interface area (§8.4, Meyer et
    /// al. 2002 over all incident triangles), scaled by `rate` (m²/s; 1 gives r² = r0² − 4t
    /// for a sphere).
    MeanCurvature { rate: f64 },
    /// Steps of curl noise alternating with steps of area-weighted normal flow (§8.1).
    NoiseAndNormal {
        noise: Box<CurlNoise>,
        speeds: Vec<PairSpeed>,
    },
}

/// What one substep of a flow does.
pub enum FlowStep<'a> {
    /// Every vertex moves at its own velocity, held over the substep (for the implicit
    /// mean-curvature flow, its displacement over the substep divided by the substep).
    Vertices(Vec<DVec3>),
    /// The vertices follow a velocity field (integrated like a passive run's).
    Field(&'a CurlNoise),
}

impl MeshFlow {
    /// The motion of substep number `step`, from time `t` for `h`, of the mesh in `c`;
    /// `fixed[v][k]` marks coordinates held by a domain wall (the implicit flow needs them in
    /// its solve), and `earlier` the velocities of an earlier try of the same substep with
    /// another `h`, where the implicit flow's solve starts.
    pub fn step(
        &self,
        c: &Connectivity,
        step: u64,
        t: f64,
        h: f64,
        fixed: &[[bool; 3]],
        earlier: Option<&[DVec3]>,
    ) -> FlowStep<'_> {
        match self {
            MeshFlow::Normal { speeds, reverse_at } => {
                FlowStep::Vertices(normal::velocities(c, speeds, sign(*reverse_at, t)))
            }
            MeshFlow::NormalOffset { speeds, reverse_at } => {
                FlowStep::Vertices(offset::velocities(c, speeds, sign(*reverse_at, t)))
            }
            MeshFlow::MeanCurvature { rate } => {
                FlowStep::Vertices(curvature::implicit_velocities(c, *rate, h, fixed, earlier))
            }
            MeshFlow::NoiseAndNormal { noise, speeds } => {
                if step.is_multiple_of(2) {
                    FlowStep::Field(noise)
                } else {
                    FlowStep::Vertices(normal::velocities(c, speeds, 1.0))
                }
            }
        }
    }

    /// The time after `t` at which the flow changes (a reversal), so that no substep spans it.
    pub fn change_after(&self, t: f64) -> Option<f64> {
        match self {
            MeshFlow::Normal {
                reverse_at: Some(at),
                ..
            }
            | MeshFlow::NormalOffset {
                reverse_at: Some(at),
                ..
            } if !reached(*at, t) => Some(*at),
            _ => None,
        }
    }

    /// Whether a substep's velocities depend on its length (the backward-Euler mean-curvature
    /// flow), so that the substep fitting the travel limit is found by tries.
    pub fn is_implicit(&self) -> bool {
        matches!(self, MeshFlow::MeanCurvature { .. })
    }

    /// The fraction of the travel limit a substep may use. Backward Euler is stable at any
    /// step but only first-order accurate: measured on a sphere of radius 7.5 L at 60 % of
    /// its extinction time, the radius is 3.2 % off r² = r0² − 4t with substeps of a quarter
    /// of an edge length, 1.8 % at 0.15, 1.0 % at 0.1 and 0.2 % at 0.05 (error ∝ substep);
    /// at 0.1 its extinction came 2.0 % late, at 0.05 within 1 %.
    pub fn travel_fraction(&self) -> f64 {
        match self {
            MeshFlow::MeanCurvature { .. } => 0.05,
            _ => 1.0,
        }
    }

    /// Whether surfaces can come together under this flow, so merging runs (§6). Mean-curvature
    /// flow is a gradient flow of area that only pulls surfaces apart; its topology changes are
    /// T1 and T2 (§8.4). Measured on `mcf_t2` with merging on: films were snapped to the
    /// walls they meet and across junction wedges, and the 4 regions became 41.
    pub fn merges(&self) -> bool {
        !matches!(self, MeshFlow::MeanCurvature { .. })
    }

    /// The instantaneous velocities of a mean-curvature flow (the area gradient), by which
    /// collapses that start a T1 are judged (§5.1.7); `None` for the other flows, which the
    /// paper gives no separation rule (§5.1.6).
    pub fn area_gradient_velocities(&self, c: &Connectivity) -> Option<Vec<DVec3>> {
        match self {
            MeshFlow::MeanCurvature { rate } => Some(curvature::velocities(c, *rate)),
            _ => None,
        }
    }
}

/// The factor of every speed at time `t` of a flow reversed at `reverse_at`.
fn sign(reverse_at: Option<f64>, t: f64) -> f64 {
    match reverse_at {
        Some(at) if reached(at, t) => -1.0,
        _ => 1.0,
    }
}

/// Whether time `t` has reached `at`, up to the rounding of summed substeps (a billionth of
/// `at`), so that a substep ending at `at` is not followed by a vanishing one before it.
fn reached(at: f64, t: f64) -> bool {
    t >= at - 1e-9 * at.abs().max(1.0)
}

/// The interface triangles around vertex `v` (domain walls, `OUTSIDE` faces, left out) as
/// (labels, area normal): what every flow reads of a vertex's neighbourhood.
fn interface_faces(c: &Connectivity, v: u32) -> impl Iterator<Item = ([PhaseId; 2], DVec3)> + '_ {
    c.vertex_triangles(v)
        .iter()
        .map(|&t| (c.labels(t), c.triangle(t).map(|i| c.position(i))))
        .filter(|(labels, _)| !labels.contains(&polyphase_grid::OUTSIDE))
        .map(|(labels, [a, b, d])| (labels, (b - a).cross(d - a)))
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
