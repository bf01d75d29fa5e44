//! Unfolding a contoured starting mesh: multiphase contouring can fold a few triangles over
//! each other next to triple lines (measured on enright at 24³–128³: 6–48 intersecting pairs
//! of ~10⁴–10⁵ triangles), and the front tracker must start intersection-free.

use std::collections::BTreeSet;

use glam::DVec3;

use crate::front::intersection::self_intersections;
use crate::mesh::LabeledMesh;

/// Rounds of smoothing before giving up.
const ROUNDS: usize = 20;

/// Moves every vertex of an intersecting triangle to the mean of its edge neighbours (all at
/// once, from the previous round's positions), round after round, until the exact checker
/// finds no intersection. A fold is a few sliver triangles around a misplaced junction point,
/// so averaging the few vertices involved removes it and moves the surface by well under an
/// edge length. Returns the number of intersecting pairs left when it fails.
pub(super) fn untangle(mesh: &mut LabeledMesh) -> Result<(), usize> {
    let mut neighbours: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); mesh.vertices.len()];
    for &[a, b, c] in &mesh.triangles {
        for (p, q) in [(a, b), (b, c), (c, a)] {
            neighbours[p as usize].insert(q);
            neighbours[q as usize].insert(p);
        }
    }
    for _ in 0..ROUNDS {
        let hits = self_intersections(mesh);
        if hits.is_empty() {
            return Ok(());
        }
        let involved: BTreeSet<u32> = hits
            .iter()
            .flat_map(|&(s, t)| [s, t])
            .flat_map(|t| mesh.triangles[t as usize])
            .collect();
        let moved: Vec<(u32, DVec3)> = involved
            .iter()
            .map(|&v| {
                let ring = &neighbours[v as usize];
                let sum: DVec3 = ring.iter().map(|&u| mesh.vertices[u as usize]).sum();
                (v, sum / ring.len().max(1) as f64)
            })
            .collect();
        for (v, x) in moved {
            mesh.vertices[v as usize] = x;
        }
    }
    match self_intersections(mesh).len() {
        0 => Ok(()),
        n => Err(n),
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::invariants::check;
    use crate::mesh::fixtures;

    #[test]
    fn a_vertex_pushed_through_the_opposite_side_is_pulled_back() {
        let mut mesh = fixtures::icosphere(DVec3::ZERO, 1.0, 1, 1, 0);
        // Push a vertex through the ball and out of the far side: its faces cross others.
        mesh.vertices[0] *= -1.3;
        assert!(!self_intersections(&mesh).is_empty());
        untangle(&mut mesh).expect("one vertex to average");
        assert!(self_intersections(&mesh).is_empty());
        check(&mesh, 0.0).expect("still closed and consistent");
    }
}
