//! Removal of vanishing regions, the T2 process (paper 000 §5.2, Fig. 13): a region shrunk
//! below a minimum volume (by mean-curvature flow, say) is contracted to a point, and its
//! space goes to its neighbours.
//!
//! The contraction merges every vertex of the region's boundary into one vertex at a target
//! point, as one pseudo-motion: triangles with two or more of those vertices vanish, the
//! others follow the merged vertex. Every edge's half-face balance
//! ([`crate::invariants::check`]) survives the merge (a vanishing triangle's two edges to
//! the merged vertex carry opposite traversals, so they cancel), so the mesh stays closed and
//! label-consistent; coincident triangles it leaves behind are resolved by
//! [`remove_degenerate_pairs`]. With bounds relaxed as in the fail-safe pass of Appendix A.4,
//! a target is accepted when no surviving triangle falls below the minimum area or turns
//! over, domain-boundary faces stay in their planes, and exact CCD finds no collision of the
//! motion (the merged vertices count as one, the vanishing triangles are left out, as for an
//! edge collapse).
//! When no target passes, the region is shrunk by collapses of its own edges until it
//! degenerates ([`shrink`]), as remeshing makes the paper's regions vanish.
//! The operation is atomic: when neither way works, or the region count would not drop by
//! exactly one, the mesh is restored.

use glam::DVec3;
use polyphase_grid::OUTSIDE;

mod shrink;

pub(crate) use self::shrink::{collapse_on_walls, WALL_TOLERANCE};

use self::shrink::shrink;
use super::degenerate::remove_degenerate_pairs;
use super::regions::{regions, Region};
use crate::front::ccd::{edge_edge, vertex_triangle};
use crate::front::connectivity::{Connectivity, DEAD};
use crate::front::params::FrontParams;

/// Region vertices tried as targets after the region's centroid, nearest first.
const VERTEX_TARGETS: usize = 4;

/// The shape checks of a contraction, in absolute units.
struct ShapeBounds {
    /// Smallest area of a moved triangle.
    min_area: f64,
    /// Largest distance of a moved domain-boundary face's vertex from the face's plane.
    plane_tolerance: f64,
}

/// What [`remove_small_regions`] did: regions removed, and pieces that shrinking regions split
/// into on the way (each then removed in turn or left, small); the region count ([`regions`])
/// fell by `removed − split`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Vanished {
    pub removed: usize,
    pub split: usize,
}

/// Removes the regions of `c` with volume below `min_volume`, smallest first. Coincident
/// triangle pairs are resolved first. A region whose contraction is refused is shrunk by
/// collapses of its edges instead ([`shrink`]), which may split it into small pieces first;
/// regions both refuse stay. Removed triangles leave tombstones ([`Connectivity::compact`]
/// squeezes them out). Of the bounds of `params` at target edge length `target` only the
/// minimum area is kept (a contraction leaving slivers would hand them to the fail-safe
/// pass); the others are relaxed as in the fail-safe pass.
pub fn remove_small_regions(
    c: &mut Connectivity,
    params: &FrontParams,
    target: f64,
    min_volume: f64,
) -> Vanished {
    remove_degenerate_pairs(c);
    let bounds = ShapeBounds {
        min_area: params.min_area * target * target,
        // Moved boundary faces stay in their planes up to rounding: a target on the same
        // face is off its plane by ~1e-16 of the coordinates, one on another face by ~L.
        plane_tolerance: 1e-9 * target,
    };
    let (mut removed, mut split) = (0, 0);
    let mut all = regions(c);
    loop {
        let mut small: Vec<&Region> = all.iter().filter(|r| r.volume < min_volume).collect();
        if small.is_empty() {
            return Vanished { removed, split };
        }
        small.sort_by(|x, y| {
            x.volume
                .total_cmp(&y.volume)
                .then((x.phase, x.triangles.first()).cmp(&(y.phase, y.triangles.first())))
        });
        let before = c.clone();
        let mut next = None;
        for r in small {
            if contract(c, &r.triangles, &bounds) {
                remove_degenerate_pairs(c);
                let after = regions(c);
                if region_count(c, &after) + 1 == all.len() {
                    next = Some(after);
                    break;
                }
                *c = before.clone();
            }
            if let Some((after, pieces)) = shrink(c, params, target, r, &all, min_volume) {
                split += pieces;
                next = Some(after);
                break;
            }
            *c = before.clone();
        }
        match next {
            Some(after) => {
                all = after;
                removed += 1;
            }
            None => return Vanished { removed, split },
        }
    }
}

/// The number of regions of `c` given its shells' regions `all`: removing the last interface
/// leaves one phase filling the domain, which [`regions`] (a count over boundary shells) does
/// not see, so that is one region, a drop by one from two.
pub(crate) fn region_count(c: &Connectivity, all: &[Region]) -> usize {
    if c.mesh.triangles.iter().all(|&t| t == DEAD) {
        1
    } else {
        all.len()
    }
}

/// Contracts the vertices of `triangles` (a region's boundary) into one, at the first target
/// that passes the checks of the module doc: the centroid of those vertices, then the
/// [`VERTEX_TARGETS`] vertices nearest to it. When some of them lie on domain-boundary faces
/// only those are tried. Returns whether it contracted; `c` is untouched otherwise.
fn contract(c: &mut Connectivity, triangles: &[u32], bounds: &ShapeBounds) -> bool {
    let plan = Contraction::new(c, triangles);
    let merged = &plan.merged;
    let centroid = merged.iter().map(|&v| c.position(v)).sum::<DVec3>() / merged.len() as f64;
    let pinned: Vec<u32> = merged
        .iter()
        .copied()
        .filter(|&v| c.on_boundary(v))
        .collect();
    let mut targets: Vec<DVec3> = Vec::new();
    if pinned.is_empty() {
        targets.push(centroid);
    }
    let mut nearest = if pinned.is_empty() {
        merged.clone()
    } else {
        pinned
    };
    nearest.sort_by(|&x, &y| {
        let d = |v: u32| (c.position(v) - centroid).length_squared();
        d(x).total_cmp(&d(y)).then(x.cmp(&y))
    });
    targets.extend(nearest.iter().take(VERTEX_TARGETS).map(|&v| c.position(v)));
    let Some(p) = targets
        .into_iter()
        .find(|&p| shapes_allow(c, &plan, p, bounds) && motion_is_safe(c, &plan, p))
    else {
        return false;
    };
    let keep = merged[0];
    for &t in &plan.vanishing {
        c.remove_triangle(t);
    }
    for &t in &plan.moved {
        let tri = c
            .triangle(t)
            .map(|v| if plan.is_merged(v) { keep } else { v });
        let labels = c.labels(t);
        c.remove_triangle(t);
        c.add_triangle(tri, labels);
    }
    c.mesh.vertices[keep as usize] = p;
    true
}

/// The vertices a contraction merges and the triangles it removes or moves.
struct Contraction {
    /// The region's vertices, sorted; the first one survives.
    merged: Vec<u32>,
    /// Live triangles with two or more merged vertices, sorted.
    vanishing: Vec<u32>,
    /// Live triangles with exactly one merged vertex, sorted.
    moved: Vec<u32>,
}

impl Contraction {
    /// The contraction of the vertices of `triangles`.
    fn new(c: &Connectivity, triangles: &[u32]) -> Contraction {
        let mut merged: Vec<u32> = triangles.iter().flat_map(|&t| c.triangle(t)).collect();
        merged.sort_unstable();
        merged.dedup();
        let mut incident: Vec<u32> = merged
            .iter()
            .flat_map(|&v| c.vertex_triangles(v).iter().copied())
            .collect();
        incident.sort_unstable();
        incident.dedup();
        let count = |t: u32| {
            c.triangle(t)
                .iter()
                .filter(|v| merged.binary_search(v).is_ok())
                .count()
        };
        let (vanishing, moved) = incident.into_iter().partition(|&t| count(t) >= 2);
        Contraction {
            merged,
            vanishing,
            moved,
        }
    }

    /// Is `v` one of the merged vertices?
    fn is_merged(&self, v: u32) -> bool {
        self.merged.binary_search(&v).is_ok()
    }

    /// Position of `v` after the contraction to `p`.
    fn end_position(&self, c: &Connectivity, p: DVec3, v: u32) -> DVec3 {
        if self.is_merged(v) {
            p
        } else {
            c.position(v)
        }
    }
}

/// No moved triangle falls below the minimum area or turns over, and moved domain-boundary
/// faces stay in their planes.
fn shapes_allow(c: &Connectivity, plan: &Contraction, p: DVec3, bounds: &ShapeBounds) -> bool {
    plan.moved.iter().all(|&t| {
        let before = c.mesh.area_normal(t as usize);
        let [a, b, d] = c.triangle(t).map(|v| plan.end_position(c, p, v));
        let after = (b - a).cross(d - a);
        let flat = !c.labels(t).contains(&OUTSIDE)
            || c.triangle(t).iter().all(|&v| {
                let off = (plan.end_position(c, p, v) - c.position(c.triangle(t)[0]))
                    .dot(before.normalize());
                off.abs() <= bounds.plane_tolerance
            });
        0.5 * after.length() > bounds.min_area && before.dot(after) > 0.0 && flat
    })
}

/// Exact CCD of the contraction (Brochu & Bridson 2009, as in the remesher's pseudo-motion
/// check, which aliases only the two ends of one edge): every vertex–triangle and edge–edge
/// pair between a moved triangle and a live triangle near it, the vanishing triangles left
/// out, merged vertices treated as one (pairs sharing a vertex after the merge touch by
/// construction and are skipped).
fn motion_is_safe(c: &Connectivity, plan: &Contraction, p: DVec3) -> bool {
    let (vanishing, moved) = (&plan.vanishing, &plan.moved);
    let is_merged = |v: u32| plan.is_merged(v);
    let alias = |v: u32| if is_merged(v) { plan.merged[0] } else { v };
    let x0 = |v: u32| c.position(v);
    let x1 = |v: u32| plan.end_position(c, p, v);
    let swept = |tri: [u32; 3]| {
        tri.iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(x0(v)).min(x1(v)), hi.max(x0(v)).max(x1(v)))
            })
    };
    let boxes: Vec<(DVec3, DVec3)> = moved.iter().map(|&t| swept(c.triangle(t))).collect();
    let (lo, hi) = boxes.iter().fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), (l, h)| (lo.min(*l), hi.max(*h)),
    );
    let near: Vec<u32> = (0..c.mesh.triangles.len() as u32)
        .filter(|&s| c.is_live(s) && vanishing.binary_search(&s).is_err())
        .filter(|&s| {
            let (sl, sh) = swept(c.triangle(s));
            !(sl.cmpgt(hi).any() || lo.cmpgt(sh).any())
        })
        .collect();
    for (&t, &(tlo, thi)) in moved.iter().zip(&boxes) {
        let tv = c.triangle(t);
        for &s in &near {
            let sv = c.triangle(s);
            let (slo, shi) = swept(sv);
            if s == t || tlo.cmpgt(shi).any() || slo.cmpgt(thi).any() {
                continue;
            }
            for (verts, tri) in [(sv, tv), (tv, sv)] {
                let tri_alias = tri.map(alias);
                for v in verts {
                    if tri_alias.contains(&alias(v))
                        || !(is_merged(v) || tri.iter().any(|&u| is_merged(u)))
                    {
                        continue;
                    }
                    let ids = [v, tri[0], tri[1], tri[2]];
                    if vertex_triangle(&ids.map(x0), &ids.map(x1)) {
                        return false;
                    }
                }
            }
            for i in 0..3 {
                let e = [tv[i], tv[(i + 1) % 3]];
                for j in 0..3 {
                    let f = [sv[j], sv[(j + 1) % 3]];
                    let fa = f.map(alias);
                    if e.iter().any(|&v| fa.contains(&alias(v)))
                        || !e.iter().chain(&f).any(|&v| is_merged(v))
                    {
                        continue;
                    }
                    let ids = [e[0], e[1], f[0], f[1]];
                    if edge_edge(&ids.map(x0), &ids.map(x1)) {
                        return false;
                    }
                }
            }
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use polyphase_grid::PhaseId;

    use super::*;
    use crate::front::intersection::self_intersections;
    use crate::front::topology::clean;
    use crate::mesh::fixtures::{icosphere, lattice_mesh, push_oriented};
    use crate::mesh::LabeledMesh;

    /// Removes the regions below `min_volume` at target edge length `target`, checks the
    /// region count fell by the number removed (less the pieces split off) and the mesh is
    /// clean, and returns `(removed, mesh after)`.
    fn run(mesh: LabeledMesh, target: f64, min_volume: f64) -> (usize, LabeledMesh) {
        crate::invariants::check(&mesh, 0.0).expect("fixture is valid");
        assert!(self_intersections(&mesh).is_empty(), "fixture intersects");
        let mut c = Connectivity::new(mesh);
        let before = regions(&c).len();
        let done = remove_small_regions(&mut c, &FrontParams::default(), target, min_volume);
        assert_eq!(regions(&c).len() + done.removed, before + done.split);
        (done.removed, clean(&c))
    }

    /// Rounding of the tetra sums of meshes of unit size and a few thousand triangles.
    const TOL: f64 = 1e-12;

    #[test]
    fn tiny_ball_inside_a_ball_goes_to_the_surrounding_phase() {
        let outer = icosphere(DVec3::ZERO, 0.3, 2, 1, 0);
        let mut mesh = outer.clone();
        mesh.append(&icosphere(DVec3::new(0.05, 0.0, 0.0), 0.02, 1, 2, 1));
        let v = mesh.phase_volumes(3);
        let target = 0.08;
        // (L/2)³ = 6.4e-5, above the tiny ball (~3e-5), far below the outer shell (~0.1).
        let (removed, after) = run(mesh.clone(), target, (0.5 * target).powi(3));
        assert_eq!(removed, 1);
        // The tiny ball and all its vertices are gone, the rest untouched.
        assert_eq!(after, outer);
        let w = after.phase_volumes(3);
        assert!((w[1] - (v[1] + v[2])).abs() < TOL, "{v:?} -> {w:?}");
        // Nothing else is small enough: a second call removes nothing.
        let mut c = Connectivity::new(after.clone());
        let params = FrontParams::default();
        let done = remove_small_regions(&mut c, &params, target, 6.4e-5);
        assert_eq!(done, Vanished::default());
        assert_eq!(c.mesh, after);
    }

    /// A level-2 sphere of radius 0.3 (phase 1 in phase 0) with a small double cone of phase
    /// 2 sitting on it at vertex 0, at the junction of the two phases: each triangle
    /// `[0, u, w]` of the fan of vertex 0 becomes the strip `[q_u, u, w]`, `[q_u, w, q_w]`
    /// (`q` a third of the way from vertex 0) and the cone faces to apexes 0.015 above and
    /// below. Returns the mesh and its cone's vertices' centroid.
    fn sphere_with_cone() -> (LabeledMesh, DVec3) {
        let mut mesh = icosphere(DVec3::ZERO, 0.3, 2, 1, 0);
        let v = mesh.vertices[0];
        let n = v.normalize();
        let top = mesh.vertices.len() as u32;
        mesh.vertices.extend([v + 0.015 * n, v - 0.015 * n]);
        let mut ring: BTreeMap<u32, u32> = BTreeMap::new();
        let mut out = LabeledMesh {
            vertices: mesh.vertices.clone(),
            ..LabeledMesh::default()
        };
        for (&tri, &labels) in mesh.triangles.iter().zip(&mesh.labels) {
            let Some(k) = tri.iter().position(|&x| x == 0) else {
                out.triangles.push(tri);
                out.labels.push(labels);
                continue;
            };
            let (u, w) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let mut q = |x: u32| {
                *ring.entry(x).or_insert_with(|| {
                    let p = v + (out.vertices[x as usize] - v) / 3.0;
                    out.vertices.push(p);
                    out.vertices.len() as u32 - 1
                })
            };
            let (qu, qw) = (q(u), q(w));
            out.triangles
                .extend([[qu, u, w], [qu, w, qw], [top, qu, qw], [top + 1, qu, qw]]);
            out.labels.extend([[0, 1], [0, 1], [0, 2], [2, 1]]);
        }
        let cone: Vec<u32> = ring.values().copied().chain([top, top + 1]).collect();
        let centroid = cone
            .iter()
            .map(|&x| out.vertices[x as usize])
            .sum::<DVec3>()
            / cone.len() as f64;
        (out, centroid)
    }

    #[test]
    fn small_region_at_a_junction_is_contracted_to_its_centroid() {
        let (mesh, centroid) = sphere_with_cone();
        let v = mesh.phase_volumes(3);
        let target = 0.08;
        // The cone (~1e-5) is below (L/2)³ = 6.4e-5.
        assert!(v[2] > 0.0 && v[2] < 6.4e-5, "{v:?}");
        let (removed, after) = run(mesh, target, (0.5 * target).powi(3));
        assert_eq!(removed, 1);
        // The result is the original sphere with vertex 0 moved to the cone's centroid:
        // phase 1 gets the lower cone, minus the sliver between the old fan and the new one
        // (the centroid lies a little inside the sphere), phase 0 the rest.
        let mut expected = icosphere(DVec3::ZERO, 0.3, 2, 1, 0);
        expected.vertices[0] = centroid;
        assert_eq!(after.triangle_count(), expected.triangle_count());
        let (w, e) = (after.phase_volumes(3), expected.phase_volumes(3));
        for (x, y) in w.iter().zip(&e) {
            assert!((x - y).abs() < TOL, "{w:?} vs {e:?}");
        }
        // The shares are within the cone's volume of where they were.
        assert!((w[1] - v[1]).abs() < v[2] && w[2] == 0.0, "{v:?} -> {w:?}");
    }

    #[test]
    fn column_across_a_flat_interface_is_split_between_the_two_phases() {
        // 4³ box: phase 1 below z = 1/2, phase 0 above, and the cells (1, 1, 1) and
        // (1, 1, 2) of phase 2 straddling the interface (volume 1/32, below (L/2)³ = 0.064
        // for L = 0.8). Its centroid lies on the interface, so the interface stays flat and
        // each side gets the half of the column that was on it.
        let mesh = lattice_mesh(4, |i, j, k| match (i, j, k) {
            (1, 1, 1 | 2) => 2,
            (_, _, k) => PhaseId::from(k < 2),
        });
        let v = mesh.phase_volumes(3);
        let (removed, after) = run(mesh, 0.8, 0.4f64.powi(3));
        assert_eq!(removed, 1);
        let w = after.phase_volumes(3);
        // Dyadic coordinates: exact apart from rounding of the tetra sums.
        assert!((w[0] - (v[0] + 1.0 / 64.0)).abs() < TOL, "{v:?} -> {w:?}");
        assert!((w[1] - (v[1] + 1.0 / 64.0)).abs() < TOL, "{v:?} -> {w:?}");
        assert_eq!(w[2], 0.0);
        // Every vertex of the interface is still on it.
        let c = Connectivity::new(after.clone());
        for t in 0..after.triangle_count() as u32 {
            if c.labels(t) == [0, 1] {
                assert!(c.triangle(t).iter().all(|&x| c.position(x).z == 0.5));
            }
        }
    }

    #[test]
    fn cell_in_a_box_corner_contracts_onto_the_walls() {
        // Corner cell of phase 1 in a 3³ box of phase 0: all but one of its vertices lie on
        // the walls, so only those are targets and the walls must stay flat.
        let mesh = lattice_mesh(3, |i, j, k| PhaseId::from(i + j + k == 0));
        let (removed, after) = run(mesh, 0.8, 0.4f64.powi(3));
        assert_eq!(removed, 1);
        let w = after.phase_volumes(2);
        // Phase 0 fills the unchanged box (dyadic-free thirds: rounding only).
        assert!((w[0] - 1.0).abs() < TOL && w[1] == 0.0, "{w:?}");
        // Every wall vertex is still on the box surface.
        let on_wall = |p: &DVec3| p.to_array().iter().any(|&x| x == 0.0 || x == 1.0);
        let c = Connectivity::new(after.clone());
        for t in 0..after.triangle_count() as u32 {
            if c.labels(t).contains(&OUTSIDE) {
                assert!(c.triangle(t).iter().all(|&v| on_wall(&c.position(v))));
            }
        }
    }

    #[test]
    fn ccd_refuses_a_contraction_through_another_sheet() {
        let (mesh, centroid) = sphere_with_cone();
        let mut c = Connectivity::new(mesh);
        let cone = regions(&c)
            .into_iter()
            .find(|r| r.phase == 2)
            .expect("the cone is a region");
        let plan = Contraction::new(&c, &cone.triangles);
        // Every triangle touching the cone either vanishes or moves: the 5 strips'
        // outer halves move, their inner halves and the 10 cone faces vanish.
        assert_eq!((plan.moved.len(), plan.vanishing.len()), (5, 15));
        assert!(motion_is_safe(&c, &plan, centroid));
        // A small stray triangle (as a sheet inside the cone would be) across the path of a
        // ring vertex of a moved strip: the vertex crosses it on the way to the centroid.
        let q = c
            .triangle(plan.moved[0])
            .into_iter()
            .find(|&v| plan.is_merged(v))
            .expect("a moved triangle has a merged vertex");
        let from = c.position(q);
        let mid = 0.5 * (from + centroid);
        let along = (centroid - from).normalize();
        let side = along.cross(DVec3::Z).normalize();
        let up = along.cross(side);
        let corners = [side, up - side, -up - side].map(|d| c.add_vertex(mid + 1e-3 * d));
        c.add_triangle(corners, [3, 2]);
        assert!(!motion_is_safe(&c, &plan, centroid));
    }

    #[test]
    fn thin_shell_around_a_ball_is_refused_whole() {
        // A thin shell of phase 2 around a ball of phase 3, inside a ball of phase 1: the
        // shell is small, the ball inside it is not. Contracting the shell merges the ball's
        // vertices too, so the region count would drop by two: the removal is undone.
        let mut mesh = icosphere(DVec3::ZERO, 0.3, 2, 1, 0);
        mesh.append(&icosphere(DVec3::ZERO, 0.03, 1, 2, 1));
        mesh.append(&icosphere(DVec3::ZERO, 0.027, 1, 3, 2));
        let v = mesh.phase_volumes(4);
        let min_volume = 0.5 * v[3];
        assert!(v[2] < min_volume, "{v:?}");
        let (removed, after) = run(mesh.clone(), 0.08, min_volume);
        assert_eq!(removed, 0);
        assert_eq!(after, mesh);
    }

    #[test]
    fn several_small_regions_go_in_one_call() {
        // Two tiny balls of phases 2 and 3 and a tiny tetrahedron of phase 2 inside a ball
        // of phase 1: three removals, each lowering the count by one (checked in `run`).
        let outer = icosphere(DVec3::ZERO, 0.3, 2, 1, 0);
        let mut mesh = outer.clone();
        mesh.append(&icosphere(DVec3::new(0.1, 0.0, 0.0), 0.02, 1, 2, 1));
        mesh.append(&icosphere(DVec3::new(-0.1, 0.0, 0.0), 0.015, 1, 3, 1));
        let n = mesh.vertices.len() as u32;
        let corners = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        mesh.vertices
            .extend(corners.map(|p| DVec3::new(0.0, 0.1, 0.0) + 0.02 * p));
        let inside = DVec3::new(0.0, 0.1, 0.0) + DVec3::splat(0.004);
        for tri in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            push_oriented(&mut mesh, tri.map(|k| n + k), inside, 1, 2);
        }
        let v = mesh.phase_volumes(4);
        let (removed, after) = run(mesh, 0.08, 0.04f64.powi(3));
        assert_eq!(removed, 3);
        assert_eq!(after, outer);
        let w = after.phase_volumes(4);
        // Phase 1 gets everything it surrounded.
        assert!((w[1] - (v[1] + v[2] + v[3])).abs() < TOL, "{v:?} -> {w:?}");
    }
}
