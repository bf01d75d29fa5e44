//! Static solid obstacles as signed distance functions, and the open (fluid) fraction of
//! each MAC face they leave (Batty et al. 2007 style face weights for the projection).

use crate::layout::Layout;
use glam::DVec3;
use polyphase_grid::GridSpec;
use rayon::prelude::*;
use std::fmt;
use std::sync::Arc;

/// Any shape given by a signed distance: negative inside the solid, positive in the fluid.
pub trait SignedDistance: Send + Sync {
    /// Signed distance (m) from `x` to the solid's surface.
    fn signed_distance(&self, x: DVec3) -> f64;
}

/// A static obstacle.
#[derive(Clone)]
pub enum Solid {
    /// Axis-aligned box between two corners.
    Box {
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
    },
    /// Ball.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
    },
    /// Anything else (meshes, CSG) by its signed distance.
    Sdf(Arc<dyn SignedDistance>),
}

impl fmt::Debug for Solid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Solid::Box { min, max } => write!(f, "Box {{ min: {min}, max: {max} }}"),
            Solid::Sphere { center, radius } => {
                write!(f, "Sphere {{ center: {center}, radius: {radius} }}")
            }
            Solid::Sdf(_) => write!(f, "Sdf(..)"),
        }
    }
}

impl SignedDistance for Solid {
    fn signed_distance(&self, x: DVec3) -> f64 {
        match self {
            Solid::Box { min, max } => {
                let c = (*min + *max) * 0.5;
                let half = (*max - *min) * 0.5;
                let q = (x - c).abs() - half;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
            Solid::Sphere { center, radius } => (x - *center).length() - radius,
            Solid::Sdf(s) => s.signed_distance(x),
        }
    }
}

/// Sub-samples per face side used to estimate a face's open fraction.
const FACE_SAMPLES: usize = 4;

/// Open fraction of every face of component `a`: 0 on domain walls, otherwise the share of the
/// face area outside all solids, estimated on a 4×4 midpoint rule (exact for faces the
/// surface does not cross; ±1/16 where it does).
pub(crate) fn open_fractions(
    spec: &GridSpec,
    layout: &Layout,
    solids: &[Solid],
    a: usize,
) -> Vec<f64> {
    let dims = layout.face_dims(a);
    let count = dims[0] * dims[1] * dims[2];
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    (0..count)
        .into_par_iter()
        .map(|f| {
            let p = crate::layout::unidx(dims, f);
            if layout.on_wall(a, p[a]) {
                return 0.0;
            }
            if solids.is_empty() {
                return 1.0;
            }
            let mut base = DVec3::ZERO;
            base[a] = p[a] as f64;
            base[b] = p[b] as f64;
            base[c] = p[c] as f64;
            let mut open = 0usize;
            for s in 0..FACE_SAMPLES {
                for t in 0..FACE_SAMPLES {
                    let mut q = base;
                    q[b] += (s as f64 + 0.5) / FACE_SAMPLES as f64;
                    q[c] += (t as f64 + 0.5) / FACE_SAMPLES as f64;
                    let x = spec.origin + q * spec.h;
                    if solids.iter().all(|so| so.signed_distance(x) > 0.0) {
                        open += 1;
                    }
                }
            }
            open as f64 / (FACE_SAMPLES * FACE_SAMPLES) as f64
        })
        .collect()
}
