//! Snap-based merging on fixture meshes: spheres of two phases meet in a separating interface,
//! spheres of one phase fuse into one body, a gap closes only across the phase allowed in it,
//! a snap that would collide is cancelled, and a surface does not snap within its own plane.

use glam::{DQuat, DVec3};
use polyphase_grid::PhaseId;

use super::proximity::Prim;
use super::{merge_pass, MergeStats, Merger};
use crate::front::connectivity::Connectivity;
use crate::front::intersection::self_intersections;
use crate::front::params::FrontParams;
use crate::front::response::proximity::{point_triangle_distance, segment_segment_distance};
use crate::mesh::fixtures::{icosphere, push_oriented, two_spheres};
use crate::mesh::LabeledMesh;

/// Sphere radius of [`two_spheres`].
const R: f64 = 0.25;

/// Runs a merge with the checks after every operation and returns the compacted mesh; then
/// checks that it is closed, label-consistent and free of intersections.
fn merged(mesh: LabeledMesh, target: f64, distance: f64) -> (LabeledMesh, MergeStats) {
    let mut c = Connectivity::new(mesh);
    let mut m = Merger::new(&mut c, &FrontParams::default(), target, distance);
    m.verify = true;
    m.run();
    let stats = m.stats;
    c.compact();
    crate::invariants::check(&c.mesh, 0.0).expect("closed and label-consistent");
    assert_eq!(self_intersections(&c.mesh), vec![]);
    (c.mesh, stats)
}

/// [`two_spheres`] with the second sphere turned by `angle` about the x axis, so that its
/// vertices do not face the first sphere's (their meshes are mirror images otherwise); the
/// second sphere has phase `second`.
fn spheres(gap: f64, level: u32, angle: f64, second: PhaseId) -> LabeledMesh {
    let mut m = two_spheres(gap, level);
    let n = m.vertices.len() / 2;
    let centre = DVec3::new(R + gap / 2.0, 0.0, 0.0);
    let turn = DQuat::from_rotation_x(angle);
    for p in &mut m.vertices[n..] {
        *p = centre + turn * (*p - centre);
    }
    let half = m.labels.len() / 2;
    for l in &mut m.labels[half..] {
        *l = [0, second];
    }
    m
}

/// Smallest distance between triangles `s` of `a` and `t` of `b` (vertex–triangle and
/// edge–edge minima).
fn triangle_distance(a: &LabeledMesh, s: usize, b: &LabeledMesh, t: usize) -> f64 {
    let (p, q) = (a.corners(s), b.corners(t));
    let mut d = f64::INFINITY;
    for (x, y) in [(p, q), (q, p)] {
        for v in x {
            d = d.min(point_triangle_distance(v, y[0], y[1], y[2]));
        }
    }
    for i in 0..3 {
        for j in 0..3 {
            d = d.min(segment_segment_distance(
                p[i],
                p[(i + 1) % 3],
                q[j],
                q[(j + 1) % 3],
            ));
        }
    }
    d
}

/// Area of the triangles of either half of `mesh` (first sphere, second sphere) that come
/// within `distance` of the other half: every point a snap can move lies on them.
fn contact_area(mesh: &LabeledMesh, distance: f64) -> f64 {
    let half = mesh.triangle_count() / 2;
    let centroid = |t: usize| {
        let [a, b, c] = mesh.corners(t);
        (a + b + c) / 3.0
    };
    // Triangles are smaller than 0.1, so farther centroids cannot be within the distance.
    let reach = distance + 0.1;
    let near = |t: usize, others: std::ops::Range<usize>| {
        others
            .clone()
            .filter(|&s| centroid(s).distance(centroid(t)) < reach)
            .any(|s| triangle_distance(mesh, t, mesh, s) <= distance)
    };
    (0..half)
        .filter(|&t| near(t, half..2 * half))
        .chain((half..2 * half).filter(|&t| near(t, 0..half)))
        .map(|t| mesh.area(t))
        .sum()
}

/// Triangles with labels `{p, q}` either way round.
fn faces_between(mesh: &LabeledMesh, p: PhaseId, q: PhaseId) -> usize {
    mesh.labels
        .iter()
        .filter(|l| **l == [p, q] || **l == [q, p])
        .count()
}

/// Merges two spheres of phases 1 and 2 and checks the common checks and the volume bound.
/// The bound: a snap moves two vertices sharing no triangle by half their distance, at most
/// `distance / 2` each; moving one vertex of a triangle by `δ` sweeps a tetrahedron of volume
/// at most `|δ| area / 3`, so with every vertex of the contact triangles moving once a phase
/// changes by at most `contact area × distance / 2` (splits move nothing; the removal of
/// coincident pairs moves nothing).
fn merge_two_phases(angle: f64) -> MergeStats {
    let (gap, distance) = (0.004, 0.015);
    let mesh = spheres(gap, 3, angle, 2);
    let target = mesh.mean_edge_length();
    let before = mesh.phase_volumes(3);
    let bound = contact_area(&mesh, distance) * distance / 2.0;
    let (after, stats) = merged(mesh, target, distance);
    assert!(stats.snaps > 0 && stats.degenerate > 0, "{stats:?}");
    // The separating interface: the coincident pairs became faces between the two phases.
    let between = faces_between(&after, 1, 2);
    assert!(between > 0, "{stats:?}");
    let v = after.phase_volumes(3);
    for phase in 1..3 {
        let change = (v[phase] - before[phase]).abs();
        assert!(
            change <= bound,
            "phase {phase} moved {change:e}, bound {bound:e}"
        );
    }
    eprintln!(
        "angle {angle}: {stats:?}, {between} faces {{1, 2}}, volume changes {:e} {:e}, bound {bound:e}",
        v[1] - before[1],
        v[2] - before[2]
    );
    stats
}

#[test]
fn facing_spheres_of_two_phases_meet_in_an_interface() {
    // Mirror-image meshes: the vertices face each other, so no split is needed.
    let stats = merge_two_phases(0.0);
    assert_eq!(stats.splits, 0, "{stats:?}");
}

#[test]
fn turned_spheres_of_two_phases_are_split_to_match_and_meet() {
    let stats = merge_two_phases(0.3);
    assert!(stats.splits > 0, "{stats:?}");
}

/// Connected components of the triangles of `mesh` under edge adjacency.
fn components(mesh: &LabeledMesh) -> usize {
    let c = Connectivity::new(mesh.clone());
    let n = mesh.triangle_count();
    let mut seen = vec![false; n];
    let mut count = 0;
    for start in 0..n {
        if seen[start] {
            continue;
        }
        count += 1;
        seen[start] = true;
        let mut stack = vec![start as u32];
        let mut across = Vec::new();
        while let Some(t) = stack.pop() {
            let [a, b, d] = c.triangle(t);
            for (u, v) in [(a, b), (b, d), (d, a)] {
                c.edge_triangles(u, v, &mut across);
                for &s in &across {
                    if !seen[s as usize] {
                        seen[s as usize] = true;
                        stack.push(s);
                    }
                }
            }
        }
    }
    count
}

#[test]
fn spheres_of_one_phase_fuse_into_one_body() {
    for angle in [0.0, 0.3] {
        let (gap, distance) = (0.004, 0.015);
        let mesh = spheres(gap, 3, angle, 1);
        let target = mesh.mean_edge_length();
        let before = mesh.phase_volumes(2)[1];
        // As in `merge_two_phases`.
        let bound = contact_area(&mesh, distance) * distance / 2.0;
        let (after, stats) = merged(mesh, target, distance);
        assert!(stats.snaps > 0 && stats.degenerate > 0, "{stats:?}");
        // The faces where the bodies met were deleted, not kept as a film of phase 0 between
        // two layers of phase 1: no two triangles on the same three vertices remain.
        let mut keys: Vec<[u32; 3]> = after
            .triangles
            .iter()
            .map(|t| {
                let mut k = *t;
                k.sort_unstable();
                k
            })
            .collect();
        keys.sort_unstable();
        assert!(keys.windows(2).all(|w| w[0] != w[1]));
        assert_eq!(components(&after), 1, "{stats:?}");
        let change = (after.phase_volumes(2)[1] - before).abs();
        assert!(change <= bound, "moved {change:e}, bound {bound:e}");
        let c = Connectivity::new(after.clone());
        let edges = c.edges();
        let non_manifold = edges
            .iter()
            .filter(|&&[a, b]| c.edge_valence(a, b) != 2)
            .count();
        let chi = after.vertices.len() as i64 - edges.len() as i64 + after.triangle_count() as i64;
        eprintln!(
            "angle {angle}: {stats:?}, volume change {change:e} (bound {bound:e}), {non_manifold} non-manifold edges, Euler characteristic {chi}"
        );
        if angle == 0.0 {
            // Facing meshes fuse cleanly into one surface of sphere topology: every edge on
            // two triangles, Euler characteristic 2 (two spheres touching at a vertex would
            // give 3, joined through two holes 0). Turned ones keep a few edges where the
            // bodies cross at the rim of the contact (four triangles, phases 0 and 1
            // alternating, apexes beyond the merge distance), a T1 configuration (§5.1).
            assert_eq!(non_manifold, 0, "{stats:?}");
            assert_eq!(chi, 2, "{stats:?}");
        }
    }
}

#[test]
fn a_gap_closes_only_across_the_phase_allowed_in_it() {
    // Two bodies of phase 1 with phase 0 between them: as a gap of phase 0 they fuse; read as
    // if it were a sheet of phase 1 (a liquid's own thickness, which merging must not close)
    // nothing snaps.
    let (gap, distance) = (0.004, 0.015);
    let run = |across| {
        let mesh = spheres(gap, 3, 0.0, 1);
        let target = mesh.mean_edge_length();
        let mut c = Connectivity::new(mesh);
        merge_pass(&mut c, &FrontParams::default(), target, distance, across)
    };
    assert!(run(Some(0)).snaps > 0);
    assert_eq!(run(Some(1)), MergeStats::default());
}

/// Index of the vertex of `mesh` at `p` (to rounding).
fn vertex_at(mesh: &LabeledMesh, p: DVec3) -> u32 {
    mesh.vertices
        .iter()
        .position(|q| q.distance(p) < 1e-12)
        .expect("a fixture vertex lies there") as u32
}

#[test]
fn a_snap_through_a_third_surface_is_cancelled() {
    // The spheres' tips face each other on the x axis, `gap` apart; snapping them moves each
    // tip's fan into a cone ending at the origin. A small sphere of phase 3 sits in the
    // band that u's fan sweeps: 0.3 L off the axis the fan moves from x = -0.0053 to about
    // -0.0024 (derived from the sphere's sagitta and the fan's radius L), the small sphere
    // spans x in [-0.0046, -0.0030], clear of both spheres at the start.
    let gap = 0.01;
    let mesh = two_spheres(gap, 3);
    let target = mesh.mean_edge_length();
    let u = vertex_at(&mesh, DVec3::new(-gap / 2.0, 0.0, 0.0));
    let w = vertex_at(&mesh, DVec3::new(gap / 2.0, 0.0, 0.0));
    let mut blocked = mesh.clone();
    blocked.append(&icosphere(
        DVec3::new(-0.0038, 0.3 * target, 0.0),
        0.0008,
        1,
        3,
        0,
    ));
    assert_eq!(self_intersections(&blocked), vec![]);
    for (mesh, free) in [(blocked, false), (mesh, true)] {
        let mut c = Connectivity::new(mesh.clone());
        let mut m = Merger::new(&mut c, &FrontParams::default(), target, 0.015);
        assert_eq!(m.try_snap(u, w), free);
        let unsafe_cancelled = m.r.stats.unsafe_cancelled;
        if free {
            assert_eq!(unsafe_cancelled, 0);
        } else {
            // Cancelled by the collision check, and nothing changed.
            assert_eq!(unsafe_cancelled, 1);
            assert_eq!(c.mesh, mesh);
        }
        c.compact();
        crate::invariants::check(&c.mesh, 0.0).expect("closed and label-consistent");
        assert_eq!(self_intersections(&c.mesh), vec![]);
    }
}

/// A pyramid of phase 1 over a thin kite `a b c d` (diagonal `ac`, apexes `b`, `d` 2ε apart
/// on either side of it, in one plane), apex `e` above: `b` and `d` are close, share no edge,
/// and lie on adjacent triangles `abc`, `acd` at a flat angle.
fn kite_pyramid(eps: f64) -> LabeledMesh {
    let mut m = LabeledMesh {
        vertices: vec![
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(0.0, eps, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, -eps, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ],
        ..LabeledMesh::default()
    };
    // Inside the convex pyramid, above the kite's centre.
    let inside = DVec3::new(0.0, 0.0, 0.1);
    for tri in [
        [0, 1, 2],
        [0, 2, 3],
        [0, 1, 4],
        [1, 2, 4],
        [2, 3, 4],
        [3, 0, 4],
    ] {
        push_oriented(&mut m, tri, inside, 0, 1);
    }
    m
}

#[test]
fn a_surface_does_not_snap_within_its_own_plane() {
    let (eps, distance) = (0.05, 0.2);
    let mesh = kite_pyramid(eps);
    crate::invariants::check(&mesh, 0.0).expect("a closed pyramid");
    let mut c = Connectivity::new(mesh.clone());
    let mut m = Merger::new(&mut c, &FrontParams::default(), 1.0, distance);
    // Not vacuous: b and d are a proximity pair, and so is b with the side triangle cde.
    let pairs = m.proximity_pairs();
    assert!(pairs
        .iter()
        .any(|p| p.a == Prim::Vertex(1) && p.b == Prim::Vertex(3)));
    assert!(!m.fold_allows(&Prim::Vertex(1), &Prim::Vertex(3)));
    m.run();
    // Nothing was even attempted: no snap, no split, and no operation cancelled by a bound
    // or by the collision check (which would mean the fold rule let a pair through).
    assert_eq!(m.stats, MergeStats::default());
    assert_eq!(
        (m.r.stats.bound_cancelled, m.r.stats.unsafe_cancelled),
        (0, 0)
    );
    assert_eq!(c.mesh, mesh);
    crate::invariants::check(&c.mesh, 0.0).expect("closed and label-consistent");
    assert_eq!(self_intersections(&c.mesh), vec![]);
}

#[test]
fn the_fold_rule_measures_the_angle_between_adjacent_triangles() {
    // Triangles abc and acd on the edge ac (along x), d turned about it from the plane of
    // abc: interior angle 180° - turn.
    for (turn_degrees, allowed) in [(0.0, false), (80.0, false), (100.0, true), (170.0, true)] {
        let t = f64::to_radians(turn_degrees);
        let mesh = LabeledMesh {
            vertices: vec![
                DVec3::new(-1.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, -t.cos(), t.sin()),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            labels: vec![[0, 1]; 2],
        };
        let mut c = Connectivity::new(mesh);
        let m = Merger::new(&mut c, &FrontParams::default(), 1.0, 1.0);
        assert_eq!(
            m.fold_allows(&Prim::Vertex(1), &Prim::Vertex(3)),
            allowed,
            "turned {turn_degrees}°"
        );
    }
}

#[test]
fn merge_pass_is_deterministic_and_compacts() {
    let mesh = spheres(0.004, 2, 0.3, 2);
    let target = mesh.mean_edge_length();
    // The same result on one thread and on two.
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            let mut c = Connectivity::new(mesh.clone());
            let stats = merge_pass(&mut c, &FrontParams::default(), target, 0.03, None);
            (c.mesh, stats)
        })
    };
    let (first, stats) = run(1);
    // Snaps, but at this resolution (contact radius about one edge) no coincident pair: the
    // spheres end joined at vertices and edges, without a face between them.
    assert!(stats.snaps > 0, "{stats:?}");
    // Compacted: the vertices the snaps merged away and those of undone splits are gone (two
    // phases: the removal of coincident pairs keeps one triangle of each, so every vertex
    // stays in use).
    assert_eq!(
        first.vertices.len(),
        mesh.vertices.len() + stats.splits - stats.snaps
    );
    crate::invariants::check(&first, 0.0).expect("closed and label-consistent");
    assert_eq!(self_intersections(&first), vec![]);
    assert_eq!(run(2), (first, stats));
}
