//! Structural invariants of a [`LabeledMesh`] (ARCHITECTURE.md "LabeledMesh"): valid indices,
//! finite coordinates, two different labels per triangle, no degenerate triangle, and every
//! phase region bounded by a closed, consistently oriented surface.

use crate::mesh::LabeledMesh;
use glam::DVec3;
use polyphase_grid::PhaseId;
use thiserror::Error;

/// The first invariant violation found, naming the offending element and where it is.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum InvariantError {
    /// `labels` and `triangles` have different lengths.
    #[error("mesh has {triangles} triangles but {labels} label pairs")]
    LabelCount { triangles: usize, labels: usize },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },
    /// A vertex has a NaN or infinite coordinate.
    #[error("vertex {vertex} has a non-finite position {position}")]
    NonFiniteVertex { vertex: usize, position: DVec3 },
    /// Both sides of a triangle carry the same phase.
    #[error("triangle {triangle} at {centroid} has phase {phase} on both sides")]
    EqualLabels {
        triangle: usize,
        phase: PhaseId,
        centroid: DVec3,
    },
    /// A triangle uses the same vertex twice.
    #[error("triangle {triangle} repeats a vertex: {vertices:?}")]
    RepeatedVertex { triangle: usize, vertices: [u32; 3] },
    /// A triangle's area is not above the threshold.
    #[error("triangle {triangle} at {centroid} has area {area:e} <= minimum {min_area:e}")]
    Degenerate {
        triangle: usize,
        area: f64,
        min_area: f64,
        centroid: DVec3,
    },
    /// An edge belongs to a single triangle: the surface has a hole there.
    #[error("edge ({a}, {b}) from {pa} to {pb} is used only by triangle {triangle}")]
    OpenEdge {
        a: u32,
        b: u32,
        pa: DVec3,
        pb: DVec3,
        triangle: usize,
    },
    /// The boundary of phase `phase` is not closed and consistently oriented along an edge:
    /// the half-faces of that phase traverse it `imbalance` more times from `a` to `b` than back.
    #[error(
        "phase {phase} boundary is open or inconsistently oriented at edge ({a}, {b}) from {pa} to {pb} (imbalance {imbalance})"
    )]
    Inconsistent {
        a: u32,
        b: u32,
        pa: DVec3,
        pb: DVec3,
        phase: PhaseId,
        imbalance: i64,
    },
}

/// Checks every invariant of `mesh` and returns the first violation (in a deterministic order:
/// per-triangle checks by triangle index, then edges by vertex indices). A triangle is
/// degenerate when its area is `<= min_area` or it repeats a vertex.
///
/// Closure and label consistency are one condition (paper 000 §3): for every undirected edge
/// and every phase `p` (`OUTSIDE` included), summing over the triangles incident to the edge
/// that carry `p` the edge's direction as traversed by the triangle oriented with `p` behind
/// it (+1 for `a → b`, −1 for `b → a`; the traversal is reversed when `p` is the front label)
/// must give zero. Then the half-faces of each phase form closed, outward-oriented surfaces.
pub fn check(mesh: &LabeledMesh, min_area: f64) -> Result<(), InvariantError> {
    if mesh.labels.len() != mesh.triangles.len() {
        return Err(InvariantError::LabelCount {
            triangles: mesh.triangles.len(),
            labels: mesh.labels.len(),
        });
    }
    let nv = mesh.vertices.len();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= nv) {
            return Err(InvariantError::IndexOutOfRange {
                triangle: t,
                index,
                vertex_count: nv,
            });
        }
    }
    if let Some((vertex, &position)) = mesh
        .vertices
        .iter()
        .enumerate()
        .find(|(_, p)| !p.is_finite())
    {
        return Err(InvariantError::NonFiniteVertex { vertex, position });
    }
    for (t, (tri, &[front, back])) in mesh.triangles.iter().zip(&mesh.labels).enumerate() {
        let [a, b, c] = mesh.corners(t);
        let centroid = (a + b + c) / 3.0;
        if front == back {
            return Err(InvariantError::EqualLabels {
                triangle: t,
                phase: front,
                centroid,
            });
        }
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0] {
            return Err(InvariantError::RepeatedVertex {
                triangle: t,
                vertices: *tri,
            });
        }
        let area = mesh.area(t);
        if area.is_nan() || area <= min_area {
            return Err(InvariantError::Degenerate {
                triangle: t,
                area,
                min_area,
                centroid,
            });
        }
    }
    check_edges(mesh)
}

/// One triangle's view of one of its edges: `(a, b)` with `a < b`, the phase, the direction.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
struct HalfEdge {
    a: u32,
    b: u32,
    phase: PhaseId,
    triangle: u32,
    dir: i8,
}

/// Closure and label consistency by sorting all (edge, phase) half-edge records.
fn check_edges(mesh: &LabeledMesh) -> Result<(), InvariantError> {
    let mut records = Vec::with_capacity(mesh.triangles.len() * 6);
    for (t, (tri, labels)) in mesh.triangles.iter().zip(&mesh.labels).enumerate() {
        for k in 0..3 {
            let (u, v) = (tri[k], tri[(k + 1) % 3]);
            let (a, b, forward) = if u < v { (u, v, 1) } else { (v, u, -1) };
            // Oriented with `p` behind, the triangle keeps its order for the back label and
            // reverses it for the front label.
            for (phase, dir) in [(labels[0], -forward), (labels[1], forward)] {
                records.push(HalfEdge {
                    a,
                    b,
                    phase,
                    triangle: t as u32,
                    dir,
                });
            }
        }
    }
    records.sort_unstable();
    let position = |i: u32| mesh.vertices[i as usize];
    for edge in records.chunk_by(|x, y| (x.a, x.b) == (y.a, y.b)) {
        let (a, b) = (edge[0].a, edge[0].b);
        // Each triangle contributes two records (its two labels) per edge.
        if edge.len() == 2 {
            return Err(InvariantError::OpenEdge {
                a,
                b,
                pa: position(a),
                pb: position(b),
                triangle: edge[0].triangle as usize,
            });
        }
        for run in edge.chunk_by(|x, y| x.phase == y.phase) {
            let imbalance: i64 = run.iter().map(|r| i64::from(r.dir)).sum();
            if imbalance != 0 {
                return Err(InvariantError::Inconsistent {
                    a,
                    b,
                    pa: position(a),
                    pb: position(b),
                    phase: run[0].phase,
                    imbalance,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh};
    use polyphase_grid::OUTSIDE;

    fn cube() -> LabeledMesh {
        lattice_mesh(2, |i, _, _| i as PhaseId)
    }

    #[test]
    fn valid_meshes_pass() {
        assert_eq!(check(&cube(), 1e-12), Ok(()));
        // Four phases meeting along a line (edges with 4 interface triangles) and a corner cell.
        let quad = lattice_mesh(2, |i, j, _| (i + 2 * j) as PhaseId);
        assert_eq!(check(&quad, 1e-12), Ok(()));
        let corner = lattice_mesh(3, |i, j, k| PhaseId::from(i == 1 && j == 1 && k == 1));
        assert_eq!(check(&corner, 1e-12), Ok(()));
        assert_eq!(check(&icosphere(DVec3::ZERO, 1.0, 2, 1, 0), 1e-12), Ok(()));
    }

    #[test]
    fn flipped_labels_fail() {
        let mut m = cube();
        let t = m
            .labels
            .iter()
            .position(|l| l[0] != OUTSIDE && l[1] != OUTSIDE)
            .unwrap();
        m.labels[t].swap(0, 1);
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::Inconsistent { .. })
        ));
    }

    #[test]
    fn relabelled_triangle_fails() {
        let mut m = cube();
        let t = m
            .labels
            .iter()
            .position(|l| l[0] != OUTSIDE && l[1] != OUTSIDE)
            .unwrap();
        m.labels[t] = [2, 0];
        // Phase 1 loses a half-face and phase 2 gains an unmatched one; phases are checked in
        // ascending order.
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::Inconsistent { phase: 1, .. })
        ));
    }

    #[test]
    fn dropped_triangle_fails() {
        let mut m = cube();
        m.triangles.remove(5);
        m.labels.remove(5);
        // The quad's other triangle keeps the diagonal to itself: an open edge.
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::OpenEdge { .. })
        ));
    }

    #[test]
    fn degenerate_triangles_fail() {
        let mut m = cube();
        let [a, b, _] = m.triangles[3];
        m.triangles[3] = [a, b, a];
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::RepeatedVertex { triangle: 3, .. })
        ));
        // Zero area without repeated index: collapse a vertex onto another position.
        let mut m = cube();
        let [a, b, c] = m.triangles[0];
        m.vertices[c as usize] = 0.5 * (m.vertices[a as usize] + m.vertices[b as usize]);
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::Degenerate { triangle: 0, .. })
        ));
    }

    #[test]
    fn equal_labels_fail() {
        let mut m = cube();
        m.labels[7] = [1, 1];
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::EqualLabels {
                triangle: 7,
                phase: 1,
                ..
            })
        ));
    }

    #[test]
    fn bad_indices_and_coordinates_fail() {
        let mut m = cube();
        m.triangles[2][1] = 10_000;
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::IndexOutOfRange {
                triangle: 2,
                index: 10_000,
                ..
            })
        ));
        let mut m = cube();
        m.vertices[4].y = f64::NAN;
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::NonFiniteVertex { vertex: 4, .. })
        ));
        let mut m = cube();
        m.labels.pop();
        assert!(matches!(
            check(&m, 1e-12),
            Err(InvariantError::LabelCount { .. })
        ));
    }
}
