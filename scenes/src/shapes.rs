//! Initial shapes: primitives with signed distances, clipped by half-spaces, painted in order
//! of priority. Their union gives the initial phase χ exactly and a lower bound on the distance
//! φ to the interface, which is all the contouring tracker needs to build its first mesh.

use std::sync::Arc;

use glam::DVec3;
use polyphase_grid::PhaseId;

use crate::mesh_sdf::MeshSdf;
use crate::voronoi::Voronoi;

/// A solid primitive; `sdf` is negative inside.
#[derive(Clone, Debug, PartialEq)]
pub enum Primitive {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Infinite circular cylinder with axis parallel to z through `center`.
    Cylinder {
        center: DVec3,
        radius: f64,
    },
    Box {
        lo: DVec3,
        hi: DVec3,
    },
    /// Axis-aligned ellipsoid; a very long z radius makes an ellipse of a slab scene.
    Ellipsoid {
        center: DVec3,
        radii: DVec3,
    },
    /// Keeps the side `normal` (unit) points away from.
    HalfSpace {
        point: DVec3,
        normal: DVec3,
    },
    /// A half-space whose plane is displaced along `normal` by amplitude·cos(2π (x − point.x) /
    /// wavelength): the single-mode perturbed interface of Rayleigh–Taylor (paper 004 Fig. 21).
    Wave {
        point: DVec3,
        normal: DVec3,
        amplitude: f64,
        wavelength: f64,
    },
    /// The inside of a closed triangle mesh (from an OBJ file); shared, as it can be large.
    Mesh(Arc<MeshSdf>),
}

impl Primitive {
    /// Signed distance to the primitive's surface: exact, or for `Ellipsoid` and `Wave` a bound
    /// whose magnitude never exceeds the distance.
    pub fn sdf(&self, x: DVec3) -> f64 {
        match *self {
            Primitive::Sphere { center, radius } => (x - center).length() - radius,
            Primitive::Cylinder { center, radius } => {
                (x.x - center.x).hypot(x.y - center.y) - radius
            }
            Primitive::Box { lo, hi } => {
                let c = (lo + hi) * 0.5;
                let q = (x - c).abs() - (hi - lo) * 0.5;
                q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
            }
            // g = ‖(x − c)/r‖ changes by at most 1/r_min per metre, and g = 1 on the surface,
            // so (g − 1)·r_min never exceeds the distance (a bound, as the CSG of `Shape`), with
            // the exact sign.
            Primitive::Ellipsoid { center, radii } => {
                (((x - center) / radii).length() - 1.0) * radii.min_element()
            }
            Primitive::HalfSpace { point, normal } => (x - point).dot(normal),
            // Divided by √(1 + max slope²) so |sdf| never exceeds the true distance.
            Primitive::Wave {
                point,
                normal,
                amplitude,
                wavelength,
            } => {
                let k = std::f64::consts::TAU / wavelength;
                let d = (x - point).dot(normal) - amplitude * (k * (x.x - point.x)).cos();
                d / (1.0 + (k * amplitude).powi(2)).sqrt()
            }
            Primitive::Mesh(ref mesh) => mesh.sdf(x),
        }
    }
}

/// A primitive intersected with half-spaces, filled with one phase.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    pub phase: PhaseId,
    /// Wins over shapes of lower priority where they overlap (scene file `priority`).
    pub priority: i64,
    pub primitive: Primitive,
    /// (point, unit normal): keep the side the normal points away from.
    pub clip: Vec<(DVec3, DVec3)>,
}

impl Shape {
    /// Signed distance bound of the intersection: `max` of the parts. Its magnitude never
    /// exceeds the true distance to the shape's boundary (CSG bound), its sign is exact.
    pub fn sdf(&self, x: DVec3) -> f64 {
        self.clip
            .iter()
            .fold(self.primitive.sdf(x), |d, &(p, n)| d.max((x - p).dot(n)))
    }
}

/// All initial shapes over a background phase, or a foam filling the domain.
#[derive(Clone, Debug, PartialEq)]
pub struct InitialPhases {
    pub background: PhaseId,
    /// In painting order (a later shape wins where shapes overlap): ascending priority, file
    /// order among equals ([`crate::Scene`] sorts them so).
    pub shapes: Vec<Shape>,
    /// A Voronoi foam (scene `[foam]`, which has no shapes): cell `k` is phase `k`.
    pub foam: Option<Arc<Voronoi>>,
}

impl InitialPhases {
    /// χ(x): the last shape containing x, else the background; the foam's cell.
    pub fn phase(&self, x: DVec3) -> PhaseId {
        if let Some(foam) = &self.foam {
            return foam.cell(x) as PhaseId;
        }
        self.shapes
            .iter()
            .rev()
            .find(|s| s.sdf(x) < 0.0)
            .map_or(self.background, |s| s.phase)
    }

    /// The boundary nearest to x among all shapes: its |sdf| and unit gradient (the direction
    /// in which that shape's signed distance grows), by central differences.
    pub fn nearest_boundary(&self, x: DVec3) -> Option<(f64, DVec3)> {
        if let Some(foam) = &self.foam {
            let (_, d, n) = foam.boundary(x);
            return n.map(|n| (-d, n));
        }
        let (_, shape) = self
            .shapes
            .iter()
            .map(|s| (s.sdf(x).abs(), s))
            .min_by(|a, b| a.0.total_cmp(&b.0))?;
        let e = 1e-7;
        let d = |a: DVec3| (shape.sdf(x + a * e) - shape.sdf(x - a * e)) / (2.0 * e);
        let g = DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z));
        Some((shape.sdf(x), g.normalize_or_zero()))
    }

    /// (φ, χ): φ is a lower bound on the distance to the interface (the interface lies on the
    /// union of shape boundaries, and each |sdf| bounds the distance to its boundary).
    pub fn sample(&self, x: DVec3) -> (f64, PhaseId) {
        if let Some(foam) = &self.foam {
            return foam.sample(x);
        }
        let mut phi = f64::INFINITY;
        let mut chi = self.background;
        for s in &self.shapes {
            let d = s.sdf(x);
            phi = phi.min(d.abs());
            if d < 0.0 {
                chi = s.phase;
            }
        }
        (phi, chi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_sdf_is_exact_distance() {
        let b = Primitive::Box {
            lo: DVec3::ZERO,
            hi: DVec3::ONE,
        };
        // Outside a corner: Euclidean distance to the corner; inside: distance to nearest face.
        assert!((b.sdf(DVec3::new(2.0, 2.0, 2.0)) - 3f64.sqrt()).abs() < 1e-15);
        assert!((b.sdf(DVec3::new(0.5, 0.5, 0.2)) + 0.2).abs() < 1e-15);
        assert!((b.sdf(DVec3::new(0.5, 1.5, 0.5)) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn painter_order_and_distance_bound() {
        let sphere = Shape {
            phase: 1,
            priority: 0,
            primitive: Primitive::Sphere {
                center: DVec3::splat(0.5),
                radius: 0.25,
            },
            clip: vec![],
        };
        let half = Shape {
            clip: vec![(DVec3::splat(0.5), DVec3::X)],
            phase: 2,
            ..sphere.clone()
        };
        let p = InitialPhases {
            background: 0,
            shapes: vec![sphere, half],
            foam: None,
        };
        assert_eq!(p.phase(DVec3::new(0.4, 0.5, 0.5)), 2);
        assert_eq!(p.phase(DVec3::new(0.6, 0.5, 0.5)), 1);
        assert_eq!(p.phase(DVec3::new(0.9, 0.5, 0.5)), 0);
        // At (0.6, 0.5, 0.5) the nearest interface is the cut plane x = 0.5, 0.1 away.
        let (phi, _) = p.sample(DVec3::new(0.6, 0.5, 0.5));
        assert!((phi - 0.1).abs() < 1e-12);
    }
}
