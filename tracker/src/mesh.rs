//! The labeled non-manifold triangle mesh shared by every tracker (ARCHITECTURE.md
//! "LabeledMesh").

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

#[cfg(test)]
pub(crate) mod fixtures;

/// Triangles with two phase labels each. `labels[t] = [front, back]`: `front` is the phase on
/// the side the normal `(b - a) × (c - a)` of triangle `[a, b, c]` points to, `back` the phase
/// behind it (paper 000 §3). Faces on the domain boundary carry `OUTSIDE` on their outer side.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LabeledMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    pub labels: Vec<[PhaseId; 2]>,
}

impl LabeledMesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`. Panics if `t` or its indices are out of
    /// range; run [`crate::invariants::check`] first on untrusted meshes.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// Area-weighted normal `(b - a) × (c - a)` of triangle `t` (length = twice the area); it
    /// points into the front phase.
    pub fn area_normal(&self, t: usize) -> DVec3 {
        let [a, b, c] = self.corners(t);
        (b - a).cross(c - a)
    }

    /// Unit normal of triangle `t`, pointing into its front phase; zero for a degenerate triangle.
    pub fn normal(&self, t: usize) -> DVec3 {
        self.area_normal(t).normalize_or_zero()
    }

    /// Area of triangle `t`.
    pub fn area(&self, t: usize) -> f64 {
        0.5 * self.area_normal(t).length()
    }

    /// Axis-aligned bounding box `(min, max)` of the vertices; `None` for a mesh without vertices.
    pub fn bbox(&self) -> Option<(DVec3, DVec3)> {
        let first = *self.vertices.first()?;
        Some(
            self.vertices
                .iter()
                .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v))),
        )
    }

    /// Mean length of the triangles' edges (each triangle's three; on a closed mesh every edge
    /// counts equally often, so this is the mean over edges); 0 for an empty mesh.
    pub fn mean_edge_length(&self) -> f64 {
        let sum: f64 = (0..self.triangle_count())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                (a - b).length() + (b - c).length() + (c - a).length()
            })
            .sum();
        sum / (3 * self.triangle_count()).max(1) as f64
    }

    /// Appends `other`'s vertices and triangles (indices shifted), keeping its labels; the
    /// result is the disjoint union of both surfaces.
    pub fn append(&mut self, other: &LabeledMesh) {
        let offset = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
        self.labels.extend_from_slice(&other.labels);
    }

    /// Exact volume of each phase `0..n_phases` by the divergence theorem: every triangle adds
    /// the signed volume of the tetrahedron it spans with a reference point (the bounding-box
    /// centre, which keeps the products small and the sum accurate) to its back phase and
    /// subtracts it from its front phase. `OUTSIDE` and labels `>= n_phases` are ignored. The
    /// sum runs in triangle order, so the result is reproducible bit for bit. Requires a closed,
    /// label-consistent mesh ([`crate::invariants::check`]) to be meaningful.
    pub fn phase_volumes(&self, n_phases: usize) -> Vec<f64> {
        let mut volumes = vec![0.0; n_phases];
        let Some((lo, hi)) = self.bbox() else {
            return volumes;
        };
        let centre = 0.5 * (lo + hi);
        for (t, &[front, back]) in self.labels.iter().enumerate() {
            let [a, b, c] = self.corners(t);
            let (a, b, c) = (a - centre, b - centre, c - centre);
            // Tetra (centre, a, b, c): positive when the normal points away from the centre,
            // i.e. the triangle bounds its back phase from outside.
            let vol = a.dot(b.cross(c)) / 6.0;
            if back != OUTSIDE {
                if let Some(v) = volumes.get_mut(back as usize) {
                    *v += vol;
                }
            }
            if front != OUTSIDE {
                if let Some(v) = volumes.get_mut(front as usize) {
                    *v -= vol;
                }
            }
        }
        volumes
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{icosphere, lattice_mesh};
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn split_cube_volumes_are_exact() {
        let mesh = lattice_mesh(2, |i, _, _| i as PhaseId);
        let v = mesh.phase_volumes(2);
        // Polyhedron with dyadic coordinates: the tetra sums are exact up to rounding of a few
        // dozen terms of size <= 1/6, far below 1e-12.
        assert!((v[0] - 0.5).abs() < 1e-12, "{v:?}");
        assert!((v[1] - 0.5).abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn three_slabs_volumes_are_exact() {
        let mesh = lattice_mesh(3, |i, _, _| i as PhaseId);
        let v = mesh.phase_volumes(3);
        for vol in v {
            // Exact polyhedron; rounding only (see above).
            assert!((vol - 1.0 / 3.0).abs() < 1e-12, "{vol}");
        }
    }

    #[test]
    fn icosphere_volume_converges_within_inscribed_bounds() {
        let r = 1.3;
        let exact = 4.0 / 3.0 * PI * r * r * r;
        let mut last_err = f64::INFINITY;
        for level in 0..5 {
            let mesh = icosphere(DVec3::ZERO, r, level, 1, 0);
            let v = mesh.phase_volumes(2);
            // The inner phase is the polyhedron inscribed in the sphere: it contains the ball of
            // its smallest face-plane distance `rho` and lies inside the ball of radius r.
            let rho = (0..mesh.triangle_count())
                .map(|t| mesh.normal(t).dot(mesh.corners(t)[0]).abs())
                .fold(f64::INFINITY, f64::min);
            let lower = 4.0 / 3.0 * PI * rho.powi(3);
            assert!(
                v[1] <= exact && v[1] >= lower,
                "level {level}: {} not in [{lower}, {exact}]",
                v[1]
            );
            // Outer phase (0) is closed only by the sphere itself: it gets the negative volume.
            assert!((v[0] + v[1]).abs() < 1e-12 * exact, "{v:?}");
            let err = exact - v[1];
            // Each subdivision roughly quarters the sagitta, so the error must shrink.
            assert!(
                err < last_err,
                "level {level}: error {err} did not decrease"
            );
            last_err = err;
        }
        // Level 4 (5120 faces): the polyhedral volume error is ~ 3 * sagitta / r ~ 0.2 %.
        assert!(last_err / exact < 3e-3, "{last_err}");
    }

    #[test]
    fn append_shifts_indices() {
        let a = icosphere(DVec3::ZERO, 1.0, 0, 1, 0);
        let b = icosphere(DVec3::new(5.0, 0.0, 0.0), 1.0, 0, 2, 0);
        let mut m = a.clone();
        m.append(&b);
        assert_eq!(m.triangle_count(), 40);
        let v = m.phase_volumes(3);
        let va = a.phase_volumes(2)[1];
        // Same polyhedron translated: volumes agree to rounding of the tetra sums.
        assert!(
            (v[1] - va).abs() < 1e-12 && (v[2] - va).abs() < 1e-12,
            "{v:?}"
        );
    }
}
