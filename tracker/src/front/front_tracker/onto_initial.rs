//! Putting the remeshed start back onto the exact initial interface.
//!
//! The start is contoured at half the spacing (vertices on the exact interface) and then
//! coarsened to the target edge length, and every collapse to an edge's midpoint leaves its
//! vertex inside a convex surface by the chord's sagitta, L²/8R. That noise in the vertices'
//! places is noise in the curvature surface tension reads off the mesh: a static drop with the
//! front tracker started with its vertices 6.8e-7 m inside its circle on average (up to
//! 3.6e-6 m, 16 solver cells across), against 1.2e-7 m r.m.s. on the contoured mesh, and its
//! first steps' jumps were three times as uneven. Moving each two-phase vertex along its normal
//! onto the initial indicator's interface removes it.

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use super::super::connectivity::Connectivity;
use crate::contour::PhaseSampler;

/// How far along its normal a vertex looks for the interface, in target edge lengths: a
/// midpoint collapse leaves it a sagitta (L²/8R, an eighth of L at R = L) inside.
const REACH: f64 = 0.25;

/// Bisection steps: 2⁻⁴⁰ of the reach is far below rounding of a vertex's place.
const BISECTIONS: usize = 40;

/// The position each vertex of `c` should take on the interface of `initial` (its own where it
/// is not a two-phase vertex whose normal line crosses that interface within `REACH · edge`).
/// `fixed` holds each vertex's wall coordinates, which do not move.
pub(super) fn onto_initial(
    c: &Connectivity,
    initial: &dyn PhaseSampler,
    edge: f64,
    fixed: &[[bool; 3]],
) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .map(|v| {
            let p = c.position(v);
            normal_line(c, v, fixed[v as usize])
                .and_then(|(n, into, from)| crossing(initial, p, n, REACH * edge, into, from))
                .unwrap_or(p)
        })
        .collect()
}

/// The unit area-weighted normal of `v`'s interface triangles, pointing from one phase
/// (`from`) into the other (`into`), with the wall coordinates zeroed; `None` where `v` is on
/// no interface or on more than one phase pair, or where that line does not cross every one of
/// its triangles from behind (a fold). Sharp features need no exception: a vertex on the exact
/// crease or corner finds the phase change where it is and stays.
fn normal_line(c: &Connectivity, v: u32, fixed: [bool; 3]) -> Option<(DVec3, PhaseId, PhaseId)> {
    let mut pair: Option<[PhaseId; 2]> = None;
    let mut normals = Vec::new();
    for &t in c.vertex_triangles(v) {
        let labels = c.labels(t);
        if labels.contains(&OUTSIDE) {
            continue;
        }
        let [into, from] = *pair.get_or_insert(labels);
        let n = c.mesh.area_normal(t as usize);
        if labels == [into, from] {
            normals.push(n);
        } else if labels == [from, into] {
            normals.push(-n);
        } else {
            return None;
        }
    }
    let [into, from] = pair?;
    let mut line = normals.iter().sum::<DVec3>();
    for k in 0..3 {
        if fixed[k] {
            line[k] = 0.0;
        }
    }
    let line = line.normalize_or_zero();
    let crosses = normals.iter().all(|n| n.dot(line) > 0.0);
    (line != DVec3::ZERO && crosses).then_some((line, into, from))
}

/// Where the phase along `p + s·n`, |s| ≤ `reach`, changes from `from` to `into`; `None`
/// unless the line's ends lie in those two phases.
fn crossing(
    initial: &dyn PhaseSampler,
    p: DVec3,
    n: DVec3,
    reach: f64,
    into: PhaseId,
    from: PhaseId,
) -> Option<DVec3> {
    let phase = |s: f64| initial.sample(p + s * n).1;
    if phase(reach) != into || phase(-reach) != from {
        return None;
    }
    let (mut lo, mut hi) = (-reach, reach);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if phase(mid) == into {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(p + 0.5 * (lo + hi) * n)
}
