//! Small closed labeled meshes with known geometry, shared by the tests of this crate.

use super::LabeledMesh;
use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};
use std::collections::BTreeMap;

/// The unit cube cut into `n³` cells, cell `(i, j, k)` holding phase `phase(i, j, k)`: one quad
/// (two triangles) between every pair of face-neighbouring cells of different phases, and
/// `OUTSIDE` quads on the cube boundary. Vertices are the shared lattice points, so the mesh is
/// closed and label-consistent by construction (non-manifold where three or more phases meet).
pub(crate) fn lattice_mesh(
    n: usize,
    phase: impl Fn(usize, usize, usize) -> PhaseId,
) -> LabeledMesh {
    let m = n + 1;
    let mut mesh = LabeledMesh::default();
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                mesh.vertices
                    .push(DVec3::new(i as f64, j as f64, k as f64) / n as f64);
            }
        }
    }
    let cell = |c: [i64; 3]| -> PhaseId {
        if c.iter().all(|&x| x >= 0 && (x as usize) < n) {
            phase(c[0] as usize, c[1] as usize, c[2] as usize)
        } else {
            OUTSIDE
        }
    };
    let vid = |p: [i64; 3]| (p[0] + m as i64 * (p[1] + m as i64 * p[2])) as u32;
    for axis in 0..3 {
        let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
        for s in 0..=n as i64 {
            for cu in 0..n as i64 {
                for cw in 0..n as i64 {
                    let mut upper = [0i64; 3];
                    upper[axis] = s;
                    upper[u] = cu;
                    upper[w] = cw;
                    let mut lower = upper;
                    lower[axis] = s - 1;
                    let (front, back) = (cell(upper), cell(lower));
                    if front == back {
                        continue;
                    }
                    // Quad corners counter-clockwise seen from +axis (u × w = axis).
                    let corner = |du: i64, dw: i64| {
                        let mut p = upper;
                        p[u] += du;
                        p[w] += dw;
                        vid(p)
                    };
                    let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
                    mesh.triangles.push([q[0], q[1], q[2]]);
                    mesh.triangles.push([q[0], q[2], q[3]]);
                    mesh.labels.push([front, back]);
                    mesh.labels.push([front, back]);
                }
            }
        }
    }
    mesh
}

/// A sphere of radius `r` approximated by an icosahedron subdivided `level` times, vertices on
/// the sphere, normals pointing out: front = `outside`, back = `inside`.
pub(crate) fn icosphere(
    centre: DVec3,
    r: f64,
    level: u32,
    inside: PhaseId,
    outside: PhaseId,
) -> LabeledMesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut verts: Vec<DVec3> = [
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ]
    .iter()
    .map(|p| DVec3::from_array(*p).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                verts.push((verts[a as usize] + verts[b as usize]).normalize());
                verts.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let n = tris.len();
    LabeledMesh {
        vertices: verts.into_iter().map(|v| centre + r * v).collect(),
        triangles: tris,
        labels: vec![[outside, inside]; n],
    }
}

/// Deterministic pseudo-random numbers for tests.
pub(crate) use crate::sampling::SplitMix64 as Rng;

/// Adds triangle `[a, b, c]` (vertex indices) with labels `front`/`back`, ordered so its normal
/// points away from `back_interior`, a point inside the back phase.
pub(crate) fn push_oriented(
    mesh: &mut LabeledMesh,
    [a, b, c]: [u32; 3],
    back_interior: DVec3,
    front: PhaseId,
    back: PhaseId,
) {
    let p = |i: u32| mesh.vertices[i as usize];
    let n = (p(b) - p(a)).cross(p(c) - p(a));
    let tri = if n.dot(p(a) - back_interior) > 0.0 {
        [a, b, c]
    } else {
        [a, c, b]
    };
    mesh.triangles.push(tri);
    mesh.labels.push([front, back]);
}

/// Two radius-¼ icospheres of phases 1 and 2 in phase 0, centred on the x axis with a gap of
/// `gap` between them: the collision tests' standard pair.
pub(crate) fn two_spheres(gap: f64, level: u32) -> LabeledMesh {
    let mut m = icosphere(DVec3::new(-0.25 - gap / 2.0, 0.0, 0.0), 0.25, level, 1, 0);
    m.append(&icosphere(
        DVec3::new(0.25 + gap / 2.0, 0.0, 0.0),
        0.25,
        level,
        2,
        0,
    ));
    m
}
