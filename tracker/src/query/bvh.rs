//! Axis-aligned bounding-box tree over triangles for exact nearest-point queries. Built top
//! down: each node splits its triangles at the median centroid along the longest axis of the
//! centroid bounds (ties broken by index, so the tree is a pure function of the input),
//! O(N log N) with linear-time selection, halves split in parallel. Queries descend the nearer child first and prune
//! every box farther than the best distance found so far. Boxes are stored in `f32`, rounded
//! outwards (so they still contain their triangles), making a node 32 bytes and a pair of
//! siblings one cache line: queries are bound by memory traffic, not arithmetic.

use glam::DVec3;
use rayon::prelude::*;

/// Most triangles per leaf.
const LEAF_SIZE: usize = 4;
/// Traversal stack depth: median splits give depth <= ceil(log2(N)) <= 32 for `u32` counts,
/// and the stack holds at most one entry per level.
const STACK: usize = 64;

/// A tree node: bounding box and either two children at `first`, `first + 1` (`count == 0`,
/// `first` even so that both share a cache line) or the triangles `first .. first + count` of
/// the tree's order.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Node {
    lo: [f32; 3],
    hi: [f32; 3],
    first: u32,
    count: u32,
}

/// Largest `f32` not above `x`.
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) > x {
        f.next_down()
    } else {
        f
    }
}

/// Smallest `f32` not below `x`.
fn f32_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x {
        f.next_up()
    } else {
        f
    }
}

/// The tree; triangle `i` of the tree's order is input triangle `order[i]`.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    pub(crate) order: Vec<u32>,
}

/// Squared distance from `p` to the box of `node` (zero inside).
#[inline(always)]
fn box_distance2(p: DVec3, node: &Node) -> f64 {
    let lo = DVec3::new(node.lo[0].into(), node.lo[1].into(), node.lo[2].into());
    let hi = DVec3::new(node.hi[0].into(), node.hi[1].into(), node.hi[2].into());
    let d = (lo - p).max(p - hi).max(DVec3::ZERO);
    d.length_squared()
}

/// Centre of the box of `node`.
#[inline(always)]
fn box_centre(node: &Node) -> DVec3 {
    let c = |k: usize| 0.5 * (f64::from(node.lo[k]) + f64::from(node.hi[k]));
    DVec3::new(c(0), c(1), c(2))
}

/// A triangle while building: bounds, centroid and input index.
#[derive(Clone, Copy, Debug)]
struct Prim {
    lo: DVec3,
    hi: DVec3,
    centroid: DVec3,
    id: u32,
}

/// Slices longer than this are split in parallel.
const PARALLEL_MIN: usize = 4096;

/// Reorders `prims` into tree order: the first half (by centroid along the longest axis of
/// the centroid bounds, ties by index) before the second, recursively. The split position
/// depends only on the length, so the tree's shape is implicit, and the result is the same
/// whether the halves run in parallel or not.
fn partition(prims: &mut [Prim]) {
    if prims.len() <= LEAF_SIZE {
        return;
    }
    let bounds = |ps: &[Prim]| {
        ps.iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.centroid), hi.max(p.centroid))
            })
    };
    let (clo, chi) = if prims.len() > PARALLEL_MIN {
        // min/max are exact, so the chunked reduction equals the serial one.
        prims.par_chunks(PARALLEL_MIN).map(bounds).reduce(
            || (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
    } else {
        bounds(prims)
    };
    let ext = chi - clo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.centroid[axis]
            .total_cmp(&b.centroid[axis])
            .then(a.id.cmp(&b.id))
    });
    let (left, right) = prims.split_at_mut(mid);
    if left.len() > PARALLEL_MIN {
        rayon::join(|| partition(left), || partition(right));
    } else {
        partition(left);
        partition(right);
    }
}

impl Bvh {
    /// Builds the tree over triangles given by their corner positions.
    pub(crate) fn build(tris: &[[DVec3; 3]]) -> Bvh {
        let n = tris.len();
        let mut prims: Vec<Prim> = tris
            .par_iter()
            .enumerate()
            .map(|(i, t)| Prim {
                lo: t[0].min(t[1]).min(t[2]),
                hi: t[0].max(t[1]).max(t[2]),
                centroid: (t[0] + t[1] + t[2]) / 3.0,
                id: i as u32,
            })
            .collect();
        partition(&mut prims);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * n.div_ceil(LEAF_SIZE) + 2),
            order: prims.iter().map(|p| p.id).collect(),
        };
        if n > 0 {
            // Root, then an unused slot so that every sibling pair starts at an even index.
            bvh.nodes.push(Node::default());
            bvh.nodes.push(Node::default());
            bvh.emit(&prims, 0, 0, n);
        }
        bvh
    }

    /// Fills node `node` for tree-order triangles `start..end` (and its subtree, depth first;
    /// recursion depth <= log2 N) and returns its `f64` bounds.
    fn emit(&mut self, prims: &[Prim], node: usize, start: usize, end: usize) -> (DVec3, DVec3) {
        let (lo, hi) = if end - start <= LEAF_SIZE {
            self.nodes[node].first = start as u32;
            self.nodes[node].count = (end - start) as u32;
            prims[start..end]
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p.lo), hi.max(p.hi))
                })
        } else {
            let left = self.nodes.len();
            self.nodes.push(Node::default());
            self.nodes.push(Node::default());
            self.nodes[node].first = left as u32;
            let mid = start + (end - start) / 2;
            let (llo, lhi) = self.emit(prims, left, start, mid);
            let (rlo, rhi) = self.emit(prims, left + 1, mid, end);
            (llo.min(rlo), lhi.max(rhi))
        };
        self.nodes[node].lo = [f32_down(lo.x), f32_down(lo.y), f32_down(lo.z)];
        self.nodes[node].hi = [f32_up(hi.x), f32_up(hi.y), f32_up(hi.z)];
        (lo, hi)
    }

    /// Visits the leaves that may hold a triangle closer than the running bound, nearer boxes
    /// first. `test(i, bound2)` examines tree-order triangle `i` and returns the new squared
    /// bound (the smaller of `bound2` and its squared distance). Boxes at exactly the bound
    /// are still visited, so equal-distance ties can be resolved by the caller independently
    /// of the visiting order. Returns the final bound.
    #[inline]
    pub(crate) fn nearest(
        &self,
        p: DVec3,
        mut bound2: f64,
        mut test: impl FnMut(usize, f64) -> f64,
    ) -> f64 {
        let Some(root) = self.nodes.first() else {
            return bound2;
        };
        if box_distance2(p, root) > bound2 {
            return bound2;
        }
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut top = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let first = n.first as usize;
                for i in first..first + n.count as usize {
                    bound2 = test(i, bound2);
                }
            } else {
                let l = n.first as usize;
                let (a, b) = (&self.nodes[l], &self.nodes[l + 1]);
                let da = box_distance2(p, a);
                let db = box_distance2(p, b);
                // Nearer box first; when `p` is inside both, the one whose centre is nearer,
                // which finds a tight bound sooner.
                let a_first = if da == db {
                    (p - box_centre(a)).length_squared() <= (p - box_centre(b)).length_squared()
                } else {
                    da < db
                };
                let (near, dn, far, df) = if a_first {
                    (l, da, l + 1, db)
                } else {
                    (l + 1, db, l, da)
                };
                if dn <= bound2 {
                    if df <= bound2 {
                        stack[top] = (far as u32, df);
                        top += 1;
                    }
                    node = near;
                    continue;
                }
            }
            // Pop the next box still within the bound.
            loop {
                if top == 0 {
                    return bound2;
                }
                top -= 1;
                let (next, d) = stack[top];
                if d <= bound2 {
                    node = next as usize;
                    break;
                }
            }
        }
    }
}
