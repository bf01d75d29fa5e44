//! Vertex separation, the T1 process of paper 000 §5.1.4–§5.1.8 (Algorithm 2, Figs. 9–12):
//! an irregular vertex `v` whose region graph misses the arc {A, B} is duplicated into `va`
//! (carrying the triangles of region A) and `vb` (all others), pulled apart along the
//! separation direction, and the gap is filled by triangles `va vb w` where the two regions
//! beside the opened edge `vw` differ. Repeated in order of separation strength until no
//! candidate with positive strength remains; each separation is collision-checked (§5.1.8) and
//! cancelled when unsafe, so the mesh stays closed, label-consistent and intersection-free.

mod junction;
mod plan;
mod safety;

use polyphase_grid::{PhaseId, VelocityField};

use super::region_graph::missing_arcs;
use crate::front::connectivity::Connectivity;
use crate::front::params::{Bounds, FrontParams};
use crate::front::remesh::Remesher;
use plan::Plan;

pub use junction::collapse_junction_edges;

/// The two new vertices lie `SEPARATION_FRACTION * target` on either side of the old one, so
/// the new edge `va vb` is a fifth of the target length: short enough to be a small local edit
/// (the gap triangles are slivers of height ~`target`, smallest angle ~11°, inside the default
/// angle bounds), long enough to be well resolved by the exact predicates. The paper leaves ε
/// unspecified (§5.1.4, Algorithm 2). Such an edge joins two non-manifold curves, so the
/// ordinary collapse pass does not undo it (only [`collapse_junction_edges`] could, where the
/// flow shortens it, §5.1.7).
pub const SEPARATION_FRACTION: f64 = 0.1;

/// Rounds of Algorithm 2's outer loop at most. Every separation removes a node from the
/// region graphs of both new vertices (§5.1.5), so the loop ends by itself; the bound only
/// guards against a flow that keeps asking for separations the collision checks cancel.
const MAX_ROUNDS: usize = 16;

/// How strongly the flow asks for a proposed separation (§5.1.6); only positive strengths are
/// performed.
pub enum SeparationStrength<'a> {
    /// Mean-curvature-like flows that decrease area (§5.1.6, last paragraph): the decrease of
    /// the total area of the triangles around the vertex when it is separated (gap triangles
    /// included). Positive when separating lowers the surface energy.
    AreaDecrease,
    /// A prescribed velocity field at a time: `d · (∂u/∂d)`, the rate of stretching of the
    /// flow along the unit separation direction `d` (from region B's one-ring centroid toward
    /// region A's), by central differences over ±ε. Positive when the flow carries A's side
    /// away from B's, i.e. when A and B are being pulled apart (and the two regions beside
    /// them pushed together, which the gap triangles then join: Fig. 2 middle, Fig. 4). The
    /// paper's wording, "how strongly the velocity field is converging along that
    /// direction", does not fix the sign; this is the one under which a T1 follows the flow
    /// (the regions the flow brings together get the new interface).
    Velocity(&'a dyn VelocityField, f64),
}

/// Performs vertex separations on `c` (Algorithm 2): in every round, every missing arc of
/// every irregular vertex is a candidate (both assignments of its two regions to `va`),
/// candidates are sorted by decreasing strength (ties by vertex, then regions), and each is
/// re-planned and re-scored on the mesh as it is at its turn and performed if its strength is
/// still positive and it is collision-safe. Rounds repeat until one performs nothing. `target`
/// is the target edge length (the separation offset ε = [`SEPARATION_FRACTION`] × `target`,
/// the broad-phase cell). Compacts `c` at the end (indices change). Returns the number of
/// separations performed.
pub fn separate_vertices(
    c: &mut Connectivity,
    params: &FrontParams,
    target: f64,
    strength: &SeparationStrength,
) -> usize {
    let eps = SEPARATION_FRACTION * target;
    let mut r = Remesher::new(c, Bounds::new(params, target));
    let mut done = 0;
    for _ in 0..MAX_ROUNDS {
        let mut candidates: Vec<(f64, u32, PhaseId, PhaseId)> = Vec::new();
        for v in 0..r.c.mesh.vertices.len() as u32 {
            for [a, b] in missing_arcs(r.c, v) {
                for (a, b) in [(a, b), (b, a)] {
                    if let Some(plan) = Plan::new(r.c, v, a, b, eps) {
                        let s = plan.strength(r.c, strength);
                        if s > 0.0 {
                            candidates.push((s, v, a, b));
                        }
                    }
                }
            }
        }
        candidates.sort_by(|x, y| {
            y.0.total_cmp(&x.0)
                .then(x.1.cmp(&y.1))
                .then(x.2.cmp(&y.2))
                .then(x.3.cmp(&y.3))
        });
        let mut round = 0;
        for (_, v, a, b) in candidates {
            let pair = [a.min(b), a.max(b)];
            if missing_arcs(r.c, v).binary_search(&pair).is_err() {
                continue;
            }
            let Some(plan) = Plan::new(r.c, v, a, b, eps) else {
                continue;
            };
            if plan.strength(r.c, strength) > 0.0 && plan.perform(&mut r) {
                round += 1;
                verify(&r);
            }
        }
        done += round;
        if round == 0 {
            break;
        }
    }
    drop(r);
    c.compact();
    done
}

/// In tests, after every separation: the live mesh is closed, label-consistent and free of
/// intersections.
#[cfg(test)]
fn verify(r: &Remesher) {
    let mesh = r.live_mesh();
    if let Err(e) = crate::invariants::check(&mesh, 0.0) {
        panic!("after a separation: {e}");
    }
    let hits = crate::front::intersection::self_intersections(&mesh);
    assert!(hits.is_empty(), "after a separation: {hits:?}");
}

#[cfg(not(test))]
fn verify(_r: &Remesher) {}

#[cfg(test)]
mod tests;
