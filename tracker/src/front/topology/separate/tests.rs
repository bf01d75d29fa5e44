//! Vertex separation and junction collapses on built configurations: two spheres touching at a
//! vertex (Fig. 10 without gap triangles), four quarter-prisms around a quadruple edge (Fig. 9
//! extruded, Fig. 4: the flow picks the direction), and a film shrinking between two triple
//! curves (Fig. 5: collapse, then separation). Each separation is also checked inside
//! [`separate_vertices`] (closed, consistent, intersection-free) as it happens.

use glam::{DQuat, DVec3};
use polyphase_grid::{PhaseId, VelocityField};

use super::*;
use crate::front::intersection::self_intersections;
use crate::mesh::fixtures::{icosphere, lattice_mesh};
use crate::mesh::LabeledMesh;

/// Closed, label-consistent and free of intersections, or panic saying which failed.
fn assert_clean(mesh: &LabeledMesh) {
    if let Err(e) = crate::invariants::check(mesh, 0.0) {
        panic!("{e}");
    }
    let hits = self_intersections(mesh);
    assert!(hits.is_empty(), "{hits:?}");
}

/// Every vertex with a missing arc, with its missing arcs.
fn irregular(c: &Connectivity) -> Vec<(u32, Vec<[PhaseId; 2]>)> {
    (0..c.mesh.vertices.len() as u32)
        .map(|v| (v, missing_arcs(c, v)))
        .filter(|(_, m)| !m.is_empty())
        .collect()
}

/// Number of triangles separating phases `a` and `b`.
fn interface(mesh: &LabeledMesh, a: PhaseId, b: PhaseId) -> usize {
    mesh.labels
        .iter()
        .filter(|l| **l == [a, b] || **l == [b, a])
        .count()
}

/// The linear field `u = rates ∘ (x − centre)` (componentwise), constant in time.
struct Linear {
    centre: DVec3,
    rates: DVec3,
}

impl VelocityField for Linear {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        self.rates * (x - self.centre)
    }
}

/// Unit icospheres (level 2) of phases 1 (above) and 2 (below) in phase 0, rotated so that
/// one vertex of each lies at the origin and merged there: they touch at that vertex only
/// (each lies strictly on its side of the plane z = 0 elsewhere).
fn touching_spheres() -> LabeledMesh {
    let place = |phase: PhaseId, up: f64| {
        let mut m = icosphere(DVec3::ZERO, 1.0, 2, phase, 0);
        let q = DQuat::from_rotation_arc(m.vertices[0], DVec3::new(0.0, 0.0, -up));
        for p in &mut m.vertices {
            *p = q * *p + DVec3::new(0.0, 0.0, up);
        }
        m.vertices[0] = DVec3::ZERO;
        m
    };
    let mut mesh = place(1, 1.0);
    let below = place(2, -1.0);
    let offset = mesh.vertices.len() as u32;
    mesh.append(&below);
    // Merge the lower sphere's touching vertex (now `offset`) into the upper one's (0).
    for tri in &mut mesh.triangles {
        for v in tri.iter_mut() {
            if *v == offset {
                *v = 0;
            }
        }
    }
    let mut c = Connectivity::new(mesh);
    c.compact();
    c.mesh
}

/// The unit cube in 4×4×4 cells, split into four quarter-prisms around the vertical line
/// x = y = ½ and rotated 45° about it, so that the regions lie right (+x, phase 1), top
/// (+y, 2), left (3) and bottom (4) of it: the pairs {1, 3} (along x) and {2, 4} (along y)
/// meet only along the line, a quadruple edge irregular along its whole length (its two ends
/// on the domain walls z = 0 and z = 1).
fn quadruple_prism() -> LabeledMesh {
    let mut mesh = lattice_mesh(4, |i, j, _| match (i >= 2, j >= 2) {
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
        (false, false) => 4,
    });
    let centre = DVec3::new(0.5, 0.5, 0.0);
    let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_4);
    for p in &mut mesh.vertices {
        let r = q * (*p - centre);
        // z is untouched by the rotation; keep it exact so the walls stay planar.
        *p = DVec3::new(r.x + centre.x, r.y + centre.y, p.z);
    }
    mesh
}

#[test]
fn spheres_touching_at_a_vertex_separate_once() {
    let mesh = touching_spheres();
    assert_clean(&mesh);
    let mut c = Connectivity::new(mesh.clone());
    assert_eq!(irregular(&c), vec![(0, vec![[1, 2]])]);
    let target = mesh.mean_edge_length();
    let n = separate_vertices(
        &mut c,
        &FrontParams::default(),
        target,
        &SeparationStrength::AreaDecrease,
    );
    // One missing arc, no gap triangles (both cones face phase 0 on either side).
    assert_eq!(n, 1);
    assert_clean(&c.mesh);
    assert!(irregular(&c).is_empty(), "{:?}", irregular(&c));
    assert_eq!(c.mesh.vertices.len(), mesh.vertices.len() + 1);
    assert_eq!(c.mesh.triangle_count(), mesh.triangle_count());
    // The two apexes: ε above and below the origin (d is along z by symmetry up to the
    // icosphere's orientation, so only the distance is exact to rounding).
    let eps = SEPARATION_FRACTION * target;
    let apexes: Vec<DVec3> = c
        .mesh
        .vertices
        .iter()
        .copied()
        .filter(|p| p.length() < 2.0 * eps)
        .collect();
    assert_eq!(apexes.len(), 2, "{apexes:?}");
    assert!(((apexes[0] - apexes[1]).length() - 2.0 * eps).abs() < 1e-12);
    // Each apex moved into its sphere, which loses at most ε × (its one-ring area ≈ 6 × the
    // area of an equilateral triangle of side `target`) / 3.
    let (before, after) = (mesh.phase_volumes(3), c.mesh.phase_volumes(3));
    let bound = eps * 6.0 * 3f64.sqrt() / 4.0 * target * target / 3.0;
    for k in [1, 2] {
        let lost = before[k] - after[k];
        assert!(
            lost > 0.0 && lost < bound,
            "phase {k}: lost {lost}, bound {bound}"
        );
    }
}

/// Separates the quadruple prism under the linear field with `rates` and returns the result
/// and the number of separations.
fn separate_prism(rates: DVec3) -> (LabeledMesh, usize) {
    let mesh = quadruple_prism();
    assert_clean(&mesh);
    let mut c = Connectivity::new(mesh);
    // The five vertices of the quadruple line each miss {1, 3} and {2, 4}.
    let before = irregular(&c);
    assert_eq!(before.len(), 5, "{before:?}");
    assert!(before.iter().all(|(_, m)| *m == vec![[1, 3], [2, 4]]));
    let field = Linear {
        centre: DVec3::new(0.5, 0.5, 0.5),
        rates,
    };
    let n = separate_vertices(
        &mut c,
        &FrontParams::default(),
        0.25,
        &SeparationStrength::Velocity(&field, 0.0),
    );
    assert_clean(&c.mesh);
    (c.mesh, n)
}

/// The new interface between `plus` and `minus` lies where the geometry says: just off the
/// centroid of each of its triangles along `dir`, the point-phase oracle (which reads the
/// phase from the nearest sheet's normal and labels) finds `plus`, and `minus` on the other
/// side. Checks that the gap triangles' labels agree with their orientation, not only with
/// each other. Returns how many triangles were checked.
fn assert_sides(mesh: &LabeledMesh, plus: PhaseId, minus: PhaseId, dir: DVec3) -> usize {
    let q = crate::query::MeshQuery::new(mesh, 0);
    let mut n = 0;
    for t in 0..mesh.triangle_count() {
        let [f, b] = mesh.labels[t];
        if [f.min(b), f.max(b)] != [plus.min(minus), plus.max(minus)] {
            continue;
        }
        let centre = mesh.corners(t).iter().sum::<DVec3>() / 3.0;
        // 1e-4 of the domain: well inside the gap triangles (height ~¼, width ~ε = 0.025).
        let h = 1e-4;
        assert_eq!(q.query(centre + h * dir).phase, plus, "triangle {t}");
        assert_eq!(q.query(centre - h * dir).phase, minus, "triangle {t}");
        n += 1;
    }
    n
}

#[test]
fn a_quadruple_edge_separates_the_way_the_flow_asks() {
    // Converging in x, stretching in y: top (2) and bottom (4) are pulled apart, left (3)
    // and right (1) are pushed together and get a new interface.
    let (mesh, n) = separate_prism(DVec3::new(-1.0, 1.0, 0.0));
    let c = Connectivity::new(mesh.clone());
    assert!(irregular(&c).is_empty(), "{:?}", irregular(&c));
    assert_eq!(n, 5, "one separation per vertex of the line");
    assert!(interface(&mesh, 1, 3) > 0);
    assert_eq!(interface(&mesh, 2, 4), 0);
    // Two gap triangles per vertex of the line, one to each axial neighbour (one at the ends).
    assert_eq!(assert_sides(&mesh, 1, 3, DVec3::X), 8);
    // The reverse flow separates the other pair.
    let (mesh, n) = separate_prism(DVec3::new(1.0, -1.0, 0.0));
    let c = Connectivity::new(mesh.clone());
    assert!(irregular(&c).is_empty(), "{:?}", irregular(&c));
    assert_eq!(n, 5);
    assert!(interface(&mesh, 2, 4) > 0);
    assert_eq!(interface(&mesh, 1, 3), 0);
    assert_eq!(assert_sides(&mesh, 2, 4, DVec3::Y), 8);
    // Volumes: the quarter-prisms (1/4 each) change by O(ε) slivers only.
    for (k, v) in mesh.phase_volumes(5).iter().enumerate().skip(1) {
        // Each of the 5 separations moves vertices by ε = 0.025 over a one-ring of area
        // ≲ 1/4: well under 0.01 in all.
        assert!((v - 0.25).abs() < 0.01, "phase {k}: {v}");
    }
}

#[test]
fn no_separation_without_positive_strength() {
    // Compressed in both x and y: every separation direction has negative strength.
    // The zero field has zero strength everywhere, which is not positive either.
    // Compaction drops the lattice's interior points (on no wall), nothing else.
    let mut unchanged = Connectivity::new(quadruple_prism());
    unchanged.compact();
    for rates in [DVec3::new(-1.0, -1.0, 0.0), DVec3::ZERO] {
        let (mesh, n) = separate_prism(rates);
        assert_eq!(n, 0, "rates {rates}");
        assert_eq!(mesh, unchanged.mesh, "rates {rates}: the mesh changed");
    }
}

/// A film of phases 1 (above, y > ⅔) | 2 (below) between two triple curves, squeezed to width
/// `2 δ` in x: the unit cube in 3×3×3 cells, column i = 0 phase 3, i = 2 phase 4, the middle
/// column split at y = ⅔; then x is mapped piecewise linearly so that the middle column spans
/// `[½ − δ, ½ + δ]`. The triple curves run along z at x = ½ ± δ, y = ⅔; the film's edges
/// across x at z = ⅓ and ⅔ join them (at z = 0 and 1 they lie on the domain wall).
fn squeezed_film(delta: f64) -> LabeledMesh {
    let mut mesh = lattice_mesh(3, |i, j, _| match (i, j) {
        (0, _) => 3,
        (2, _) => 4,
        (_, 2) => 1,
        _ => 2,
    });
    let (x1, x2) = (1.0 / 3.0, 2.0 / 3.0);
    for p in &mut mesh.vertices {
        p.x = if p.x <= x1 {
            p.x / x1 * (0.5 - delta)
        } else if p.x <= x2 {
            0.5 - delta + (p.x - x1) / (x2 - x1) * 2.0 * delta
        } else {
            0.5 + delta + (p.x - x2) / (1.0 - x2) * (0.5 - delta)
        };
    }
    mesh
}

#[test]
fn junction_edges_collapse_only_where_the_flow_shortens_them() {
    let target = 1.0 / 3.0;
    // δ = 0.04: film edges 0.08 < min edge 1/6. Merging the triple curves tilts the walls
    // between the columns by δ over a one-ring of area ~⅓, a volume change of ~δ/3·⅓ ≈ 0.0044:
    // above the default bound (0.02 L³ = 0.00074), so the bound is raised for this test.
    let params = FrontParams {
        max_volume_change: 0.2,
        ..FrontParams::default()
    };
    let mesh = squeezed_film(0.04);
    assert_clean(&mesh);
    let ab_before = interface(&mesh, 1, 2);
    // Converging in x shortens the film edges (along x); stretching in x lengthens them.
    for (rates, expected) in [
        (DVec3::new(-1.0, 1.0, 0.0), 2),
        (DVec3::new(1.0, -1.0, 0.0), 0),
    ] {
        let field = Linear {
            centre: DVec3::splat(0.5),
            rates,
        };
        let mut c = Connectivity::new(mesh.clone());
        // The caller's per-vertex data (positions and velocities on entry): indices stay
        // valid during the call.
        let x = c.mesh.vertices.clone();
        let u: Vec<DVec3> = x.iter().map(|&p| field.velocity(p, 0.0)).collect();
        let shrinking_now = |a: u32, b: u32| {
            let (a, b) = (a as usize, b as usize);
            (u[a] - u[b]).dot(x[a] - x[b]) < 0.0
        };
        let n = collapse_junction_edges(&mut c, &params, target, &shrinking_now);
        assert_eq!(n, expected, "rates {rates}");
        assert_clean(&c.mesh);
        // Where the curves met, the vertices are quadruple: four regions, film (1|2) still
        // reaching them from the wall strips, {3, 4} the missing arc.
        let quads: Vec<(u32, Vec<[PhaseId; 2]>)> = irregular(&c);
        assert_eq!(quads.len(), expected, "{quads:?}");
        assert!(quads.iter().all(|(_, m)| *m == vec![[3, 4]]), "{quads:?}");
        assert_eq!(interface(&c.mesh, 1, 2), ab_before - 2 * expected);
        // Separation agrees with the collapse (§5.1.7): the flow pushes 3 and 4 together,
        // so separating them has negative strength and nothing is undone.
        let s = separate_vertices(
            &mut c,
            &params,
            target,
            &SeparationStrength::Velocity(&field, 0.0),
        );
        assert_eq!(s, 0);
    }
}

#[test]
fn eight_octants_meeting_at_a_point_resolve_into_regular_vertices() {
    // Fig. 11 and 12 generalised: eight phases in the octants of the unit cube (4³ cells);
    // the centre misses 16 of its 28 arcs, the six ends of its quadruple edges on the walls
    // miss two each.
    let mesh = lattice_mesh(4, |i, j, k| (i / 2 + 2 * (j / 2) + 4 * (k / 2)) as PhaseId);
    let mut c = Connectivity::new(mesh);
    let before = irregular(&c);
    assert_eq!(before.len(), 13, "{before:?}");
    assert!(before.iter().any(|(_, m)| m.len() == 16), "{before:?}");
    let n = separate_vertices(
        &mut c,
        &FrontParams::default(),
        0.25,
        &SeparationStrength::AreaDecrease,
    );
    assert_clean(&c.mesh);
    assert!(irregular(&c).is_empty(), "{:?}", irregular(&c));
    // Measured (deterministic): at least one separation per irregular vertex.
    assert_eq!(n, 16);
    let volumes = c.mesh.phase_volumes(8);
    // The walls stay flat (separations on them move within their plane): the phases still
    // fill the unit cube, up to rounding of the tetra sums.
    assert!(
        (volumes.iter().sum::<f64>() - 1.0).abs() < 1e-12,
        "{volumes:?}"
    );
    for (k, v) in volumes.iter().enumerate() {
        // Each phase is moved by the separations at its own corner's vertices (≲ 7), each by
        // ε = 0.025 over a one-ring of area ≲ 6 × L²/2 ≈ 0.19: ≲ 7 × 0.025 × 0.19 / 3 ≈ 0.011.
        assert!((v - 0.125).abs() < 0.012, "phase {k}: {v}");
    }
}

#[test]
fn a_separation_that_would_sweep_through_a_bubble_is_cancelled() {
    // A tiny tetrahedral bubble of phase 3 inside sphere 1, just above the contact: moving the
    // apex of sphere 1 up by ε would sweep its cone over the bubble, which no final position
    // touches: only the sweep tests see it (the vertex-in-tetrahedron test of §5.1.8 and the
    // edge-through-side test each cancel it alone; with both disabled this test fails).
    let mut mesh = touching_spheres();
    let eps = SEPARATION_FRACTION * mesh.mean_edge_length();
    let centre = DVec3::new(0.0, 0.0, 0.5 * eps);
    let s = 0.05 * eps;
    let base = mesh.vertices.len() as u32;
    mesh.vertices.extend([
        centre + DVec3::new(s, s, s),
        centre + DVec3::new(s, -s, -s),
        centre + DVec3::new(-s, s, -s),
        centre + DVec3::new(-s, -s, s),
    ]);
    for k in 0..4 {
        let f = [base + k, base + (k + 1) % 4, base + (k + 2) % 4];
        crate::mesh::fixtures::push_oriented(&mut mesh, f, centre, 1, 3);
    }
    assert_clean(&mesh);
    let mut c = Connectivity::new(mesh.clone());
    let n = separate_vertices(
        &mut c,
        &FrontParams::default(),
        mesh.mean_edge_length(),
        &SeparationStrength::AreaDecrease,
    );
    // Only the other assignment (sphere 2's apex moving down, away from the bubble) is safe;
    // both move both apexes, so neither happens.
    assert_eq!(n, 0);
    assert_clean(&c.mesh);
    assert_eq!(irregular(&c).len(), 1);
}
