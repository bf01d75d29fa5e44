//! Interface metrics comparing meshes (ARCHITECTURE.md "The parts", `tracker/`: Hausdorff
//! distance).

use crate::mesh::LabeledMesh;
use crate::query::MeshQuery;
use crate::sampling::SplitMix64;
use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};
use rayon::prelude::*;

/// Symmetric Hausdorff distance between the interface parts of `a` and `b` (faces with an
/// `OUTSIDE` label excluded), approximated by sampling: each mesh's interface vertices, edge
/// midpoints and triangle centroids are measured exactly against the other mesh
/// ([`MeshQuery`]). Since the distance to a set is 1-Lipschitz, the result is a lower bound of
/// the true value and falls short by at most half the longest interface edge (every point of a
/// triangle lies in one of its four midpoint sub-triangles, whose corners are samples).
/// Both empty: 0; one empty: infinity. Parallel; the maximum is exact, so the result does not
/// depend on the thread count.
pub fn hausdorff(a: &LabeledMesh, b: &LabeledMesh) -> f64 {
    let (qa, qb) = rayon::join(|| MeshQuery::new(a, 0), || MeshQuery::new(b, 0));
    match (qa.interface_triangle_count(), qb.interface_triangle_count()) {
        (0, 0) => return 0.0,
        (0, _) | (_, 0) => return f64::INFINITY,
        _ => {}
    }
    let (ab, ba) = rayon::join(|| directed(a, &qb), || directed(b, &qa));
    ab.max(ba)
}

/// Outcome of comparing a tracked indicator with the exact one at random points (paper 004
/// §7.2, Table 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndicatorAccuracy {
    pub samples: usize,
    pub mismatches: usize,
    /// Largest distance to the tracked interface of a point whose indicator is wrong.
    pub max_mismatch_distance: f64,
}

impl IndicatorAccuracy {
    /// Share of points whose indicator matches.
    pub fn accuracy(&self) -> f64 {
        1.0 - self.mismatches as f64 / self.samples.max(1) as f64
    }
}

/// Compares `tracked` with `exact` at `samples` uniform random points of the box `lo..hi`
/// (point i comes from its own SplitMix64 stream seeded by `seed` and i, so the answer does
/// not depend on the thread count); `distance` measures how far a mismatch is from the
/// tracked interface.
pub fn indicator_accuracy(
    lo: DVec3,
    hi: DVec3,
    samples: usize,
    seed: u64,
    tracked: impl Fn(DVec3) -> PhaseId + Sync,
    exact: impl Fn(DVec3) -> PhaseId + Sync,
    distance: impl Fn(DVec3) -> f64 + Sync,
) -> IndicatorAccuracy {
    let (mismatches, max_mismatch_distance) = (0..samples as u64)
        .into_par_iter()
        .filter_map(|i| {
            let x = SplitMix64(seed ^ i.wrapping_mul(0xD1B5_4A32_D192_ED03)).point(lo, hi);
            (tracked(x) != exact(x)).then(|| distance(x))
        })
        .map(|d| (1usize, d))
        .reduce(|| (0, 0.0), |a, b| (a.0 + b.0, a.1.max(b.1)));
    IndicatorAccuracy {
        samples,
        mismatches,
        max_mismatch_distance,
    }
}

/// Largest distance from the samples of `from`'s interface to the surface behind `to`.
fn directed(from: &LabeledMesh, to: &MeshQuery) -> f64 {
    samples(from)
        .par_iter()
        .map(|&p| to.distance(p))
        .reduce(|| 0.0, f64::max)
}

/// Vertices (each once), edge midpoints (each edge once) and centroids of the interface
/// triangles, in a deterministic order.
fn samples(mesh: &LabeledMesh) -> Vec<DVec3> {
    let interface: Vec<usize> = (0..mesh.triangle_count())
        .filter(|&t| !mesh.labels[t].contains(&OUTSIDE))
        .collect();
    let mut verts: Vec<u32> = interface.iter().flat_map(|&t| mesh.triangles[t]).collect();
    verts.sort_unstable();
    verts.dedup();
    let mut edges: Vec<(u32, u32)> = interface
        .iter()
        .flat_map(|&t| {
            let [a, b, c] = mesh.triangles[t];
            [(a, b), (b, c), (c, a)].map(|(u, v)| (u.min(v), u.max(v)))
        })
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let pos = |i: u32| mesh.vertices[i as usize];
    let mut out = Vec::with_capacity(verts.len() + edges.len() + interface.len());
    out.extend(verts.iter().map(|&v| pos(v)));
    out.extend(edges.iter().map(|&(u, v)| 0.5 * (pos(u) + pos(v))));
    out.extend(interface.iter().map(|&t| {
        let [p, q, r] = mesh.corners(t);
        (p + q + r) / 3.0
    }));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::icosphere;

    /// Longest edge of the mesh.
    fn longest_edge(m: &LabeledMesh) -> f64 {
        (0..m.triangle_count())
            .flat_map(|t| {
                let [a, b, c] = m.corners(t);
                [a.distance(b), b.distance(c), c.distance(a)]
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn concentric_spheres() {
        let (r, d) = (1.0, 0.1);
        let inner = icosphere(DVec3::ZERO, r, 3, 1, 0);
        let outer = icosphere(DVec3::ZERO, r + d, 3, 1, 0);
        let h = hausdorff(&inner, &outer);
        assert_eq!(h, hausdorff(&outer, &inner));
        // Each polyhedron lies within its sagitta s = R − (distance from the centre to the
        // polyhedron) of its sphere, and the spheres are d apart: the true polyhedral Hausdorff
        // distance lies in [d − s_i − s_o, d + s_i + s_o]; sampling can only lower it, by at
        // most half the longest edge.
        let s_in = r - MeshQuery::new(&inner, 0).distance(DVec3::ZERO);
        let s_out = r + d - MeshQuery::new(&outer, 0).distance(DVec3::ZERO);
        let upper = d + s_in + s_out;
        let lower = d - s_in - s_out - 0.5 * longest_edge(&outer);
        assert!(h <= upper && h >= lower, "{h} not in [{lower}, {upper}]");
        // The outer mesh's vertices (samples) are at radius r + d and the inner polyhedron lies
        // inside the ball of radius r: the sampled value is at least d (up to rounding).
        assert!(h >= d * (1.0 - 1e-12), "{h}");
    }

    #[test]
    fn identical_and_empty_meshes() {
        let m = icosphere(DVec3::ZERO, 1.0, 2, 1, 0);
        // The samples lie on the other mesh: only rounding of midpoints/centroids remains.
        assert!(hausdorff(&m, &m) < 1e-14);
        assert_eq!(
            hausdorff(&LabeledMesh::default(), &LabeledMesh::default()),
            0.0
        );
        assert_eq!(hausdorff(&m, &LabeledMesh::default()), f64::INFINITY);
    }
}
