//! The independent intersection checker of the front tracker's intersection-free invariant:
//! every pair of triangles of a mesh that meet where they should not, decided with the exact
//! predicates of [`super::predicates`] (no tolerance), after a hash-grid broad phase.
//!
//! Triangles sharing no vertex index must be disjoint (touching counts as intersecting);
//! triangles sharing one vertex must meet only there; triangles sharing an edge only along it.

use super::broadphase::StaticGrid;
use super::collision::{cell_size_for, swept_triangle_box};
use super::predicates::{orient2d, orient3d, segment_triangle, triangles_intersect};
use crate::LabeledMesh;
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use std::cmp::Ordering;

/// The pairs `(s, t)`, `s < t`, of triangles of `mesh` that intersect improperly (module
/// doc), sorted. Empty for an intersection-free mesh. Vertex indices must be in range;
/// removed slots ([`super::collision::is_removed`]) are skipped.
pub fn self_intersections(mesh: &LabeledMesh) -> Vec<(u32, u32)> {
    let boxes: Vec<(DVec3, DVec3)> = (0..mesh.triangles.len())
        .into_par_iter()
        .map(|t| swept_triangle_box(&mesh.triangles[t], &mesh.vertices, &mesh.vertices))
        .collect();
    let cell = cell_size_for(&boxes);
    let grid = StaticGrid::build(boxes, cell);
    (0..mesh.triangles.len() as u32)
        .into_par_iter()
        .map_init(Vec::new, |cand, s| {
            let (lo, hi) = grid.boxes()[s as usize];
            grid.query(lo, hi, cand);
            cand.iter()
                .filter(|&&t| t > s && pair_intersects(mesh, s, t))
                .map(|&t| (s, t))
                .collect::<Vec<_>>()
        })
        .flatten()
        .collect()
}

/// Triangles `s` and `t` meet beyond what their shared vertex indices allow (exact).
pub fn pair_intersects(mesh: &LabeledMesh, s: u32, t: u32) -> bool {
    let (ts, tt) = (mesh.triangles[s as usize], mesh.triangles[t as usize]);
    let (ps, pt) = (mesh.corners(s as usize), mesh.corners(t as usize));
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .filter(|&(i, j)| ts[i] == tt[j])
        .collect();
    match shared.as_slice() {
        [] => triangles_intersect(ps, pt),
        [(i, j)] => {
            // Meeting beyond the shared vertex: one triangle's opposite edge meets the other
            // (the intersection is convex and contains the shared vertex; any further point
            // extends to an exit point on one of the two opposite edges).
            let opp = |p: &[DVec3; 3], k: usize| (p[(k + 1) % 3], p[(k + 2) % 3]);
            let (a, b) = opp(&ps, *i);
            let (c, d) = opp(&pt, *j);
            segment_triangle(a, b, pt[0], pt[1], pt[2])
                || segment_triangle(c, d, ps[0], ps[1], ps[2])
        }
        [(i0, j0), (i1, _)] => {
            // Shared edge: in different planes they meet only along it; in a common plane
            // they overlap iff the opposite vertices lie on the same side of the edge.
            let (a, b) = (ps[*i0], ps[*i1]);
            let c = ps[3 - i0 - i1];
            let d = pt[(0..3)
                .find(|&k| tt[k] != ts[*i0] && tt[k] != ts[*i1])
                .unwrap_or(*j0)];
            coplanar_same_side(a, b, c, d)
        }
        _ => true,
    }
}

/// Triangles `abc` and `abd` sharing the edge `ab` overlap beyond it: they are coplanar and
/// `c`, `d` lie strictly on the same side of the line `ab`. A degenerate triangle (apex on the
/// line) meets a non-degenerate one only along `ab`; two degenerate ones (all points
/// collinear) overlap beyond `ab` iff both apexes stick out past the same end.
fn coplanar_same_side(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    if orient3d(a, b, c, d) != Ordering::Equal {
        return false;
    }
    let proj = |p: DVec3, k: usize| match k {
        0 => DVec2::new(p.y, p.z),
        1 => DVec2::new(p.z, p.x),
        _ => DVec2::new(p.x, p.y),
    };
    // A projection in which either triangle keeps its area is a bijection of the common
    // plane, so there the signs are the 3D sides (a zero meaning a degenerate triangle).
    for k in 0..3 {
        let (a2, b2) = (proj(a, k), proj(b, k));
        let (sc, sd) = (orient2d(a2, b2, proj(c, k)), orient2d(a2, b2, proj(d, k)));
        if sc != Ordering::Equal || sd != Ordering::Equal {
            return sc == sd;
        }
    }
    let k = (0..3)
        .max_by(|&i, &j| (b - a)[i].abs().total_cmp(&(b - a)[j].abs()))
        .unwrap_or(0);
    let (lo, hi) = (a[k].min(b[k]), a[k].max(b[k]));
    let beyond = |p: DVec3| (p[k] > hi) as i8 - (p[k] < lo) as i8;
    beyond(c) != 0 && beyond(c) == beyond(d)
}

#[cfg(test)]
mod tests;
