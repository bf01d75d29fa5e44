//! Multiphase marching-tetrahedra stencils (paper 004 §5.1, Fig. 5) on the Kuhn split of the
//! unit cube, and the splitting of labelled tet faces on the domain boundary.
//!
//! Every output polygon is oriented combinatorially: its normal is computed from *nominal*
//! vertex positions (edge midpoints, face and tet centroids, which never degenerate) and
//! compared with the direction from the back phase's corners to the front phase's corners.
//! In nominal positions the stencils partition each tet consistently with its neighbours
//! (a face's pieces depend only on the face's labels), so the oriented result is closed and
//! label-consistent whatever the real (bisected) positions are.

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

/// A mesh vertex, identified by what defines it, so that neighbouring cells share it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum VKey {
    /// A lattice node (domain-boundary faces only).
    Node(u64),
    /// Crossing on the lattice edge between two nodes (sorted).
    Edge(u64, u64),
    /// Triple point on the tet face of three nodes (sorted).
    Face(u64, u64, u64),
    /// Quadruple point in tet `.1` (Kuhn index) of cell `.0`.
    Tet(u32, u8),
    /// Centre of face `.1` (axis·2 + side) of coarse leaf `.0` on the domain boundary.
    Centre(u32, u8),
}

/// An oriented polygon (triangle or quad) with labels `[front, back]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Poly {
    pub verts: [VKey; 4],
    pub len: u8,
    pub labels: [PhaseId; 2],
    /// Quads only: split along `verts[0]`–`verts[2]` (always valid) instead of the shorter
    /// diagonal.
    pub fixed_diagonal: bool,
}

/// The 6 Kuhn tets of the unit cube (corner bits x + 2y + 4z): monotone paths
/// 000 → e_a → e_a + e_b → 111. Identical in every cube, so each cube face is split along
/// its min→max diagonal in both cubes sharing it.
pub(crate) const KUHN: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Cube-local position of corner `c`.
#[inline]
pub(crate) fn corner_offset(c: usize) -> DVec3 {
    DVec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64)
}

/// A vertex of a stencil, local to a simplex of up to 4 corners.
#[derive(Clone, Copy, Debug)]
enum Lv {
    P(usize),
    E(usize, usize),
    F(usize, usize, usize),
    T,
}

/// A tet or a tet face: its corners' lattice ids, nominal (cube-local) positions and labels.
pub(crate) struct Simplex {
    pub nodes: [u64; 4],
    pub local: [DVec3; 4],
    pub labels: [PhaseId; 4],
    /// Key of this tet's quadruple point (unused for faces).
    pub tet_key: VKey,
}

impl Simplex {
    fn key(&self, v: Lv) -> VKey {
        let n = &self.nodes;
        match v {
            Lv::P(i) => VKey::Node(n[i]),
            Lv::E(i, j) => VKey::Edge(n[i].min(n[j]), n[i].max(n[j])),
            Lv::F(i, j, k) => {
                let mut s = [n[i], n[j], n[k]];
                s.sort_unstable();
                VKey::Face(s[0], s[1], s[2])
            }
            Lv::T => self.tet_key,
        }
    }

    fn nominal(&self, v: Lv) -> DVec3 {
        let p = &self.local;
        match v {
            Lv::P(i) => p[i],
            Lv::E(i, j) => 0.5 * (p[i] + p[j]),
            Lv::F(i, j, k) => (p[i] + p[j] + p[k]) / 3.0,
            Lv::T => 0.25 * (p[0] + p[1] + p[2] + p[3]),
        }
    }

    fn centroid(&self, idx: &[usize]) -> DVec3 {
        idx.iter().map(|&i| self.local[i]).sum::<DVec3>() / idx.len() as f64
    }

    /// Emit polygon `vs` separating `back` from `front`, oriented so its nominal normal has a
    /// positive component along `dir` (pointing from back into front).
    fn emit(
        &self,
        vs: &[Lv],
        back: PhaseId,
        front: PhaseId,
        dir: DVec3,
        fixed_diagonal: bool,
        out: &mut Vec<Poly>,
    ) {
        let q: Vec<DVec3> = vs.iter().map(|&v| self.nominal(v)).collect();
        let n = (q[1] - q[0]).cross(q[2] - q[0]);
        let mut keys = [VKey::Node(0); 4];
        for (k, &v) in keys.iter_mut().zip(vs) {
            *k = self.key(v);
        }
        if n.dot(dir) < 0.0 {
            keys[1..vs.len()].reverse();
        }
        out.push(Poly {
            verts: keys,
            len: vs.len() as u8,
            labels: [front, back],
            fixed_diagonal,
        });
    }

    /// The stencil of a tet (paper 004 Fig. 5): interface polygons between its labels.
    pub fn tet_stencil(&self, out: &mut Vec<Poly>) {
        let l = self.labels;
        let mut distinct: Vec<PhaseId> = l.to_vec();
        distinct.sort_unstable();
        distinct.dedup();
        match distinct.len() {
            2 => self.two_labels(out),
            3 => self.three_labels(out),
            4 => self.four_labels(out),
            _ => {}
        }
    }

    fn two_labels(&self, out: &mut Vec<Poly>) {
        let l = self.labels;
        let same: Vec<usize> = (1..4).filter(|&i| l[i] == l[0]).collect();
        match same.len() {
            // 3:1 with a lone corner.
            0 | 2 => {
                let lone = if same.is_empty() {
                    0
                } else {
                    (1..4).find(|&i| l[i] != l[0]).unwrap_or(0)
                };
                let o: Vec<usize> = (0..4).filter(|&i| i != lone).collect();
                let dir = self.centroid(&o) - self.local[lone];
                let vs = [Lv::E(lone, o[0]), Lv::E(lone, o[1]), Lv::E(lone, o[2])];
                self.emit(&vs, l[lone], l[o[0]], dir, false, out);
            }
            // 2:2: {i, j} against {k, m}.
            _ => {
                let (i, j) = (0, same[0]);
                let o: Vec<usize> = (1..4).filter(|&x| x != j).collect();
                let (k, m) = (o[0], o[1]);
                let dir = self.centroid(&[k, m]) - self.centroid(&[i, j]);
                let vs = [Lv::E(i, k), Lv::E(i, m), Lv::E(j, m), Lv::E(j, k)];
                self.emit(&vs, l[i], l[k], dir, false, out);
            }
        }
    }

    fn three_labels(&self, out: &mut Vec<Poly>) {
        let l = self.labels;
        let Some((i, j)) = (0..4)
            .flat_map(|i| (i + 1..4).map(move |j| (i, j)))
            .find(|&(i, j)| l[i] == l[j])
        else {
            return;
        };
        let o: Vec<usize> = (0..4).filter(|&x| x != i && x != j).collect();
        let (k, m) = (o[0], o[1]);
        let (pk, pm, pa) = (self.local[k], self.local[m], self.centroid(&[i, j]));
        self.emit(
            &[Lv::E(k, m), Lv::F(i, k, m), Lv::F(j, k, m)],
            l[k],
            l[m],
            pm - pk,
            false,
            out,
        );
        self.emit(
            &[Lv::E(i, k), Lv::E(j, k), Lv::F(j, k, m), Lv::F(i, k, m)],
            l[i],
            l[k],
            pk - pa,
            false,
            out,
        );
        self.emit(
            &[Lv::E(i, m), Lv::E(j, m), Lv::F(j, k, m), Lv::F(i, k, m)],
            l[i],
            l[m],
            pm - pa,
            false,
            out,
        );
    }

    fn four_labels(&self, out: &mut Vec<Poly>) {
        let l = self.labels;
        for i in 0..4 {
            for j in i + 1..4 {
                let dir = self.local[j] - self.local[i];
                for k in (0..4).filter(|&k| k != i && k != j) {
                    self.emit(
                        &[Lv::E(i, j), Lv::F(i, j, k), Lv::T],
                        l[i],
                        l[j],
                        dir,
                        false,
                        out,
                    );
                }
            }
        }
    }

    /// Split a tet face lying on the domain boundary (corners 0..3 of `self`) into one
    /// polygon per label, labelled `[OUTSIDE, phase]` and facing `outward`.
    pub fn boundary_face(&self, outward: DVec3, out: &mut Vec<Poly>) {
        let l = self.labels;
        if l[0] == l[1] && l[1] == l[2] {
            self.emit(
                &[Lv::P(0), Lv::P(1), Lv::P(2)],
                l[0],
                OUTSIDE,
                outward,
                false,
                out,
            );
        } else if l[0] != l[1] && l[1] != l[2] && l[0] != l[2] {
            for (i, &li) in l.iter().enumerate().take(3) {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                self.emit(
                    &[Lv::P(i), Lv::E(i, j), Lv::F(0, 1, 2), Lv::E(i, k)],
                    li,
                    OUTSIDE,
                    outward,
                    true,
                    out,
                );
            }
        } else {
            let lone = (0..3)
                .find(|&i| l[(i + 1) % 3] == l[(i + 2) % 3])
                .unwrap_or(0);
            let (j, k) = ((lone + 1) % 3, (lone + 2) % 3);
            self.emit(
                &[Lv::P(lone), Lv::E(lone, j), Lv::E(lone, k)],
                l[lone],
                OUTSIDE,
                outward,
                false,
                out,
            );
            self.emit(
                &[Lv::P(j), Lv::P(k), Lv::E(lone, k), Lv::E(lone, j)],
                l[j],
                OUTSIDE,
                outward,
                false,
                out,
            );
        }
    }
}
