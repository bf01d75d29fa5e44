//! Closing the contour at the domain boundary: every leaf face on the grid box gets
//! triangles labelled `[OUTSIDE, phase]`, facing out of the domain.
//!
//! Interface cells are handled with the stencils (their boundary tet faces are split by
//! label, sharing edge and triple-point vertices with the interior). Here: leaves with one
//! phase, boxes (in a slab, the coarse leaves are columns spanning its thickness). A leaf face
//! with only its 4 corners on its perimeter becomes 2 triangles along the min→max diagonal; a
//! coarse leaf face whose edges carry hanging nodes (corners of smaller neighbouring leaf
//! faces) becomes a fan around a new centre vertex through every such node, so the closure is
//! conforming (no T-junctions) with O(perimeter) triangles per leaf face.

use glam::DVec3;
use polyphase_grid::OUTSIDE;
use rayon::prelude::*;

use super::stencils::{Poly, VKey};
use super::tree::{Cell, MdTree, LEAF};

impl MdTree {
    /// Appends the boundary polygons of the single-phase leaves, in cell order.
    pub(crate) fn closure_polys(&self, polys: &mut Vec<Poly>) {
        let lat = self.lattice;
        let closure = self
            .cells
            .par_iter()
            .enumerate()
            .filter(|(_, c)| c.child == LEAF && !c.mixed)
            .flat_map_iter(|(ci, cell)| {
                let mut out = Vec::new();
                for axis in 0..3 {
                    for side in 0..2u64 {
                        let coord = cell.min[axis] + side * cell.edge[axis];
                        if coord != side * lat.dims[axis] {
                            continue;
                        }
                        let ring = self.face_ring(cell, axis, coord);
                        // The ring turns e_u → e_v, so its normal is e_u × e_v = e_axis.
                        let flip = side == 0;
                        let labels = [OUTSIDE, cell.chi];
                        let tri = |a: VKey, b: VKey, c: VKey| Poly {
                            verts: if flip { [a, c, b, c] } else { [a, b, c, c] },
                            len: 3,
                            labels,
                            fixed_diagonal: false,
                        };
                        if ring.len() == 4 {
                            let r = [0, 1, 2, 3].map(|i| VKey::Node(ring[i]));
                            out.push(tri(r[0], r[1], r[2]));
                            out.push(tri(r[0], r[2], r[3]));
                        } else {
                            let centre = VKey::Centre(ci as u32, (axis * 2) as u8 + side as u8);
                            for i in 0..ring.len() {
                                let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                                out.push(tri(centre, VKey::Node(a), VKey::Node(b)));
                            }
                        }
                    }
                }
                out
            });
        polys.par_extend(closure);
    }

    /// Lattice ids of the leaf corners on the perimeter of the face of `cell` at coordinate
    /// `coord` along `axis`, walked from its min corner along +u, +v, −u, −v (u, v the next
    /// axes after `axis`): its 4 corners and the hanging nodes between them.
    pub(crate) fn face_ring(&self, cell: &Cell, axis: usize, coord: u64) -> Vec<u64> {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut ring = Vec::with_capacity(4);
        let mut p = cell.min;
        p[axis] = coord;
        for (dir, sign) in [(u, 1i64), (v, 1), (u, -1), (v, -1)] {
            ring.push(self.lattice.id(p));
            self.push_hanging(p, dir, sign, cell.edge[dir], &mut ring);
            p[dir] = (p[dir] as i64 + sign * cell.edge[dir] as i64) as u64;
        }
        ring
    }

    /// Appends, in walking order, the hanging nodes (corners of smaller leaves) inside the
    /// boundary leaf edge that starts at `p` and runs `len` (a power of two) cells along axis
    /// `dir` in direction `sign`. Cells are dyadic, so a leaf corner inside the edge makes the
    /// edge's midpoint one (the corner's cell lies in a neighbour cell of half the edge's
    /// length, which has the midpoint as a corner on the edge): probing midpoints recursively
    /// finds them all with one lookup per node found, plus one per empty half. A point on the
    /// domain boundary is a leaf corner exactly when it is a stored node: every cell's corners
    /// are sampled and are corners of its leaves, and the only other nodes, cell centres, lie
    /// strictly inside their cells.
    fn push_hanging(&self, p: [u64; 3], dir: usize, sign: i64, len: u64, ring: &mut Vec<u64>) {
        if len < 2 {
            return;
        }
        let mut mid = p;
        mid[dir] = (p[dir] as i64 + sign * (len / 2) as i64) as u64;
        let id = self.lattice.id(mid);
        if self.nodes.get(id).is_none() {
            return;
        }
        self.push_hanging(p, dir, sign, len / 2, ring);
        ring.push(id);
        self.push_hanging(mid, dir, sign, len / 2, ring);
    }

    /// Position of the centre of face `face` (axis·2 + side) of leaf `cell`.
    pub(crate) fn face_centre(&self, cell: u32, face: u8) -> DVec3 {
        let c = self.cells[cell as usize];
        let (axis, side) = ((face / 2) as usize, (face % 2) as u64);
        let mut p = DVec3::from_array([0, 1, 2].map(|a| c.min[a] as f64 + 0.5 * c.edge[a] as f64));
        p[axis] = (c.min[axis] + side * c.edge[axis]) as f64;
        self.lattice.origin + p * self.lattice.h
    }
}
