//! The regions of a labeled mesh (paper 000 §3: "a closed volume of space" of one material;
//! two regions of the same material are different regions): the connected volumes of each
//! phase, found from the mesh alone, for the T2 process (§5.2) and the live region count.
//!
//! A region's boundary is made of half-faces (a triangle's side that carries its phase).
//! Around an edge the triangles sit at angles about the edge's axis; two half-faces facing the
//! same wedge between angularly consecutive triangles bound the same region there (derived
//! here; the paper does not spell it out). With `d` the unit vector from `a` to `b` and `w`
//! the part of `apex - a` normal to `d`, a triangle traversing `a → b` has normal
//! `(b - a) × (apex - a) = |b - a| d × w`, the direction in which the angle about `d` grows:
//! its front faces the next triangle counter-clockwise and its back the previous one; a
//! triangle traversing `b → a` the reverse. Angles are compared with exact `orient3d`
//! signs, so nearly coplanar sheets are ordered correctly. Joining half-faces across every
//! edge gives shells: connected boundary surfaces of one phase (regions touching only at a
//! vertex or along an edge stay apart, as open volumes do).
//!
//! Counting: a shell's signed volume (divergence theorem with its half-faces oriented out of
//! the phase) is positive for the outer boundary of a region and negative for a cavity (the
//! boundary of something the region surrounds). Each shell of positive or zero volume is one
//! region; each cavity joins the region of the smallest outer shell of its phase that
//! contains it (that region must surround it: any other outer shell containing it contains
//! the whole region, so it is larger). Cavities no outer shell contains belong to the
//! unbounded region of their phase (the background of a domain without box walls), which
//! counts once per phase and has infinite volume. `OUTSIDE` half-faces form no region.

use std::cmp::Ordering;

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use crate::front::connectivity::Connectivity;
use crate::front::predicates::orient3d;

/// One connected volume of one phase.
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    /// Its phase.
    pub phase: PhaseId,
    /// The live triangles bounding it (outer shell and cavities), sorted.
    pub triangles: Vec<u32>,
    /// Enclosed volume (outer shell minus cavities); `f64::INFINITY` for the unbounded
    /// region of a domain without walls.
    pub volume: f64,
}

/// The regions of `c` (module doc), sorted by phase, then by lowest triangle index. Requires
/// a closed, label-consistent mesh without coincident triangles (run
/// [`super::degenerate::remove_degenerate_pairs`] first: the two triangles of a pair sit at
/// the same angle, and half-faces whose phases disagree are never joined).
pub fn regions(c: &Connectivity) -> Vec<Region> {
    let n = c.mesh.triangles.len();
    let mut sets = DisjointSets::new(2 * n);
    let mut around = Vec::new();
    for [a, b] in c.edges() {
        c.edge_triangles(a, b, &mut around);
        sort_around_edge(c, a, b, &mut around);
        for (i, &t) in around.iter().enumerate() {
            let next = around[(i + 1) % around.len()];
            let (h, g) = (ccw_side(c, t, a, b), cw_side(c, next, a, b));
            if phase_of(c, h) == phase_of(c, g) {
                sets.union(h, g);
            }
        }
    }
    let shells = shells(c, &mut sets);
    group_shells(c, shells)
}

/// A connected boundary surface of one phase.
struct Shell {
    phase: PhaseId,
    /// Half-faces `2 t + side` (side 0: front, 1: back), in increasing order.
    half_faces: Vec<u32>,
    volume: f64,
}

/// The shells of the joined half-faces, `OUTSIDE` left out, in order of their first
/// half-face; each volume is summed about its shell's first vertex, which keeps the tetra
/// products small.
fn shells(c: &Connectivity, sets: &mut DisjointSets) -> Vec<Shell> {
    let mut index = vec![u32::MAX; sets.parent.len()];
    let mut out: Vec<Shell> = Vec::new();
    for h in 0..sets.parent.len() as u32 {
        let t = h / 2;
        if !c.is_live(t) || phase_of(c, h) == OUTSIDE {
            continue;
        }
        let root = sets.find(h) as usize;
        if index[root] == u32::MAX {
            index[root] = out.len() as u32;
            out.push(Shell {
                phase: phase_of(c, h),
                half_faces: Vec::new(),
                volume: 0.0,
            });
        }
        out[index[root] as usize].half_faces.push(h);
    }
    for shell in &mut out {
        let origin = c.position(c.triangle(shell.half_faces[0] / 2)[0]);
        shell.volume = shell
            .half_faces
            .iter()
            .map(|&h| {
                let [p, q, r] = outward_corners(c, h).map(|x| x - origin);
                p.dot(q.cross(r)) / 6.0
            })
            .sum();
    }
    out
}

/// Turns shells into regions (module doc: outer shells, cavities attached to the smallest
/// containing outer shell of their phase, the rest to the unbounded region of their phase).
fn group_shells(c: &Connectivity, shells: Vec<Shell>) -> Vec<Region> {
    let outer: Vec<usize> = (0..shells.len())
        .filter(|&s| shells[s].volume >= 0.0)
        .collect();
    let mut by_size = outer.clone();
    by_size.sort_by(|&x, &y| {
        shells[x]
            .volume
            .total_cmp(&shells[y].volume)
            .then(x.cmp(&y))
    });
    // Region of each shell: an index into `outer`, or `outer.len() + k` for the unbounded
    // region of the k-th phase found without a container.
    let mut owner = vec![usize::MAX; shells.len()];
    for (k, &s) in outer.iter().enumerate() {
        owner[s] = k;
    }
    let mut unbounded: Vec<PhaseId> = Vec::new();
    for s in 0..shells.len() {
        if owner[s] != usize::MAX {
            continue;
        }
        let probe = probe_point(c, &shells[s]);
        let container = by_size.iter().copied().find(|&o| {
            shells[o].phase == shells[s].phase && winding_number(c, &shells[o], probe) > 0.5
        });
        owner[s] = match container {
            Some(o) => owner[o],
            None => {
                let k = match unbounded.iter().position(|&p| p == shells[s].phase) {
                    Some(k) => k,
                    None => {
                        unbounded.push(shells[s].phase);
                        unbounded.len() - 1
                    }
                };
                outer.len() + k
            }
        };
    }
    let mut regions: Vec<Region> = outer
        .iter()
        .map(|&s| shells[s].phase)
        .chain(unbounded.iter().copied())
        .map(|phase| Region {
            phase,
            triangles: Vec::new(),
            volume: 0.0,
        })
        .collect();
    for (s, shell) in shells.iter().enumerate() {
        let r = &mut regions[owner[s]];
        r.triangles.extend(shell.half_faces.iter().map(|&h| h / 2));
        r.volume += shell.volume;
    }
    for r in regions.iter_mut().skip(outer.len()) {
        r.volume = f64::INFINITY;
    }
    for r in &mut regions {
        r.triangles.sort_unstable();
        r.triangles.dedup();
    }
    regions.sort_by(|x, y| (x.phase, x.triangles.first()).cmp(&(y.phase, y.triangles.first())));
    regions
}

/// Phase carried by half-face `h`.
fn phase_of(c: &Connectivity, h: u32) -> PhaseId {
    c.labels(h / 2)[(h % 2) as usize]
}

/// Corners of half-face `h`'s triangle ordered so the normal points out of its phase: as
/// stored for the back side, reversed for the front side.
fn outward_corners(c: &Connectivity, h: u32) -> [DVec3; 3] {
    let [p, q, r] = c.triangle(h / 2).map(|v| c.position(v));
    if h % 2 == 1 {
        [p, q, r]
    } else {
        [p, r, q]
    }
}

/// Does triangle `t` traverse its edge from `a` to `b`?
fn traverses(c: &Connectivity, t: u32, a: u32, b: u32) -> bool {
    let tri = c.triangle(t);
    (0..3).any(|k| tri[k] == a && tri[(k + 1) % 3] == b)
}

/// Half-face of `t` facing counter-clockwise about the axis `a → b` (module doc).
fn ccw_side(c: &Connectivity, t: u32, a: u32, b: u32) -> u32 {
    2 * t + u32::from(!traverses(c, t, a, b))
}

/// Half-face of `t` facing clockwise about the axis `a → b`.
fn cw_side(c: &Connectivity, t: u32, a: u32, b: u32) -> u32 {
    2 * t + u32::from(traverses(c, t, a, b))
}

/// Sorts the triangles on edge `(a, b)` counter-clockwise about `a → b`, starting from the
/// lowest-index one, with exact orientation signs; triangles at the same angle (only
/// coincident ones in an intersection-free mesh) by index.
fn sort_around_edge(c: &Connectivity, a: u32, b: u32, tris: &mut [u32]) {
    if tris.len() < 3 {
        return;
    }
    tris.sort_unstable();
    let (pa, pb) = (c.position(a), c.position(b));
    let apex = |t: u32| {
        let v = c
            .triangle(t)
            .into_iter()
            .find(|&v| v != a && v != b)
            .expect("a live triangle has three distinct vertices");
        c.position(v)
    };
    let c0 = apex(tris[0]);
    let axis = pb - pa;
    let normal_part = |p: DVec3| {
        let w = p - pa;
        w - axis * (w.dot(axis) / axis.length_squared())
    };
    // Quarter of the angle from the reference apex: 0 at the reference angle, 1 in (0, π),
    // 2 at π, 3 in (π, 2π).
    let half = |p: DVec3| match orient3d(pa, pb, c0, p) {
        Ordering::Greater => 1,
        Ordering::Less => 3,
        Ordering::Equal if normal_part(p).dot(normal_part(c0)) >= 0.0 => 0,
        Ordering::Equal => 2,
    };
    tris.sort_by(|&s, &t| {
        let (ps, pt) = (apex(s), apex(t));
        half(ps).cmp(&half(pt)).then_with(|| {
            // Within an open half-turn, `t` is further counter-clockwise than `s` iff
            // `orient3d(a, b, s, t) > 0`.
            match orient3d(pa, pb, ps, pt) {
                Ordering::Greater => Ordering::Less,
                Ordering::Less => Ordering::Greater,
                Ordering::Equal => s.cmp(&t),
            }
        })
    });
}

/// A point strictly inside a triangle of `shell` (the centroid of its largest one), to test
/// on which side of other shells the shell lies: shells share no triangle, and in an
/// intersection-free mesh another triangle meets this one only on its boundary.
fn probe_point(c: &Connectivity, shell: &Shell) -> DVec3 {
    let t = shell
        .half_faces
        .iter()
        .map(|&h| h / 2)
        .max_by(|&s, &t| c.mesh.area(s as usize).total_cmp(&c.mesh.area(t as usize)))
        .expect("a shell has at least one half-face");
    let [p, q, r] = c.triangle(t).map(|v| c.position(v));
    (p + q + r) / 3.0
}

/// Winding number of `shell` (oriented out of its phase) about `q`: 1 inside an outer shell,
/// 0 outside; the sum of the signed solid angles of its triangles over 4π (Van Oosterom and
/// Strackee's formula).
fn winding_number(c: &Connectivity, shell: &Shell, q: DVec3) -> f64 {
    let solid: f64 = shell
        .half_faces
        .iter()
        .map(|&h| {
            let [x, y, z] = outward_corners(c, h).map(|p| p - q);
            let (lx, ly, lz) = (x.length(), y.length(), z.length());
            let det = x.dot(y.cross(z));
            let den = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
            2.0 * det.atan2(den)
        })
        .sum();
    solid / (4.0 * std::f64::consts::PI)
}

/// Union–find over half-faces with path halving and union by index (the smaller root wins,
/// so the result does not depend on the order of unions).
struct DisjointSets {
    parent: Vec<u32>,
}

impl DisjointSets {
    /// `n` singletons.
    fn new(n: usize) -> DisjointSets {
        DisjointSets {
            parent: (0..n as u32).collect(),
        }
    }

    /// Representative of `x`'s set.
    fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let grand = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = grand;
            x = grand;
        }
        x
    }

    /// Joins the sets of `x` and `y`.
    fn union(&mut self, x: u32, y: u32) {
        let (rx, ry) = (self.find(x), self.find(y));
        let (lo, hi) = (rx.min(ry), rx.max(ry));
        self.parent[hi as usize] = lo;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::{icosphere, lattice_mesh, two_spheres};
    use crate::mesh::LabeledMesh;

    /// Phase and volume of each region, in output order.
    fn summary(mesh: LabeledMesh) -> Vec<(PhaseId, f64)> {
        crate::invariants::check(&mesh, 0.0).expect("fixture is valid");
        regions(&Connectivity::new(mesh))
            .iter()
            .map(|r| (r.phase, r.volume))
            .collect()
    }

    /// Polyhedral volume of a level-`level` icosphere of radius `r`.
    fn ball(r: f64, level: u32) -> f64 {
        icosphere(DVec3::ZERO, r, level, 1, 0).phase_volumes(2)[1]
    }

    /// Volumes agree to rounding of sums of a few thousand tetra terms of size <= 1.
    const TOL: f64 = 1e-12;

    #[test]
    fn two_spheres_in_a_background_are_three_regions() {
        let mesh = two_spheres(0.1, 2);
        let c = Connectivity::new(mesh.clone());
        let r = regions(&c);
        assert_eq!(r.len(), 3, "{r:?}");
        let v = ball(0.25, 2);
        assert_eq!((r[0].phase, r[0].volume), (0, f64::INFINITY));
        assert_eq!(r[0].triangles.len(), mesh.triangle_count());
        for (k, region) in r.iter().enumerate().skip(1) {
            assert_eq!(region.phase, k as PhaseId);
            assert_eq!(region.triangles.len(), mesh.triangle_count() / 2);
            assert!((region.volume - v).abs() < TOL, "{region:?} vs {v}");
        }
    }

    #[test]
    fn nested_spheres_attach_each_cavity_to_the_innermost_container() {
        // Radii 0.4 .. 0.1, phases 1, 2, 1, 2 from the outside in, in phase 0: two shells
        // of phase 1 and the inner one's cavity must not go to the outer one.
        let radii = [0.4, 0.3, 0.2, 0.1];
        let phases: [PhaseId; 5] = [0, 1, 2, 1, 2];
        let mut mesh = LabeledMesh::default();
        for (k, &r) in radii.iter().enumerate() {
            mesh.append(&icosphere(DVec3::ZERO, r, 2, phases[k + 1], phases[k]));
        }
        let got = summary(mesh);
        let v: Vec<f64> = radii.iter().map(|&r| ball(r, 2)).collect();
        let expected = [
            (0, f64::INFINITY),
            (1, v[0] - v[1]),
            (1, v[2] - v[3]),
            (2, v[1] - v[2]),
            (2, v[3]),
        ];
        assert_eq!(got.len(), expected.len(), "{got:?}");
        for (g, e) in got.iter().zip(&expected) {
            assert_eq!(g.0, e.0, "{got:?}");
            assert!(
                g.1 == e.1 || (g.1 - e.1).abs() < TOL,
                "{got:?} vs {expected:?}"
            );
        }
    }

    #[test]
    fn box_cells_split_by_planes() {
        // Two halves: 2 regions of 1/2. Dyadic coordinates: exact up to rounding.
        let halves = summary(lattice_mesh(2, |i, _, _| i as PhaseId));
        assert_eq!(halves.len(), 2);
        assert!(
            halves.iter().all(|&(_, v)| (v - 0.5).abs() < TOL),
            "{halves:?}"
        );
        // Checkerboard of two phases: cells of one phase touch only along edges (4 sheets
        // around each inner edge) and at the centre vertex, so all 8 cells are regions.
        let checker = summary(lattice_mesh(2, |i, j, k| ((i + j + k) % 2) as PhaseId));
        assert_eq!(checker.len(), 8, "{checker:?}");
        assert!(checker.iter().all(|&(_, v)| (v - 0.125).abs() < TOL));
        assert_eq!(checker.iter().filter(|r| r.0 == 0).count(), 4);
        // The centre cell of a 3³ lattice is a cavity of the surrounding region, whose outer
        // shell is the box.
        let corner = summary(lattice_mesh(3, |i, j, k| {
            PhaseId::from(i == 1 && j == 1 && k == 1)
        }));
        assert_eq!(corner.len(), 2, "{corner:?}");
        assert!((corner[0].1 - 26.0 / 27.0).abs() < TOL, "{corner:?}");
        assert!((corner[1].1 - 1.0 / 27.0).abs() < TOL, "{corner:?}");
    }
}
