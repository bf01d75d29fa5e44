//! Index arithmetic of the staggered grid: cells, faces per component, edges per axis pair,
//! with periodic wrap where an axis is periodic.

/// Linear index in a box of `dims`, x fastest.
#[inline]
pub(crate) fn idx(dims: [usize; 3], p: [usize; 3]) -> usize {
    p[0] + dims[0] * (p[1] + dims[1] * p[2])
}

/// Inverse of [`idx`].
#[inline]
pub(crate) fn unidx(dims: [usize; 3], i: usize) -> [usize; 3] {
    [
        i % dims[0],
        (i / dims[0]) % dims[1],
        i / (dims[0] * dims[1]),
    ]
}

/// Cell counts and periodicity; knows how many faces and edges each axis has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Layout {
    pub n: [usize; 3],
    pub periodic: [bool; 3],
}

impl Layout {
    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// Node (face-position) count along `axis`: n+1 between walls, n when periodic.
    #[inline]
    pub fn nodes(&self, axis: usize) -> usize {
        self.n[axis] + usize::from(!self.periodic[axis])
    }

    /// Dimensions of the face array of component `a`.
    pub fn face_dims(&self, a: usize) -> [usize; 3] {
        let mut d = self.n;
        d[a] = self.nodes(a);
        d
    }

    /// Dimensions of the edge array whose edges sit at nodes along `a` and `b`.
    pub fn edge_dims(&self, a: usize, b: usize) -> [usize; 3] {
        let mut d = self.n;
        d[a] = self.nodes(a);
        d[b] = self.nodes(b);
        d
    }

    /// Whether node index `i` along `axis` lies on a domain wall.
    #[inline]
    pub fn on_wall(&self, axis: usize, i: usize) -> bool {
        !self.periodic[axis] && (i == 0 || i == self.n[axis])
    }

    /// Cell index `i - 1` along `axis` (wrapping when periodic), None past a wall.
    #[inline]
    pub fn cell_below(&self, axis: usize, i: usize) -> Option<usize> {
        if i > 0 {
            Some(i - 1)
        } else if self.periodic[axis] {
            Some(self.n[axis] - 1)
        } else {
            None
        }
    }

    /// Node index above cell `i` along `axis` (wrapping when periodic).
    #[inline]
    pub fn node_above(&self, axis: usize, i: usize) -> usize {
        if self.periodic[axis] && i + 1 == self.n[axis] {
            0
        } else {
            i + 1
        }
    }

    /// Cell `i` at node `i` along `axis` (the cell above the node), None at the upper wall.
    #[inline]
    pub fn cell_above_node(&self, axis: usize, i: usize) -> Option<usize> {
        (i < self.n[axis]).then_some(i)
    }
}

/// Fills `out` (a box of `dims`, x fastest) in parallel with `f(position)`, row by row so no
/// index is ever divided back into coordinates.
pub(crate) fn par_fill(dims: [usize; 3], out: &mut [f64], f: impl Fn([usize; 3]) -> f64 + Sync) {
    use rayon::prelude::*;
    let (nx, ny) = (dims[0], dims[1]);
    out.par_chunks_mut(nx).enumerate().for_each(|(row, o)| {
        let (j, k) = (row % ny, row / ny);
        for (i, v) in o.iter_mut().enumerate() {
            *v = f([i, j, k]);
        }
    });
}
