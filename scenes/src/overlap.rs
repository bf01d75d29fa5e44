//! Ambiguous overlaps: shapes of different phases with equal priority that share volume inside
//! the domain leave open which phase fills it, so validation refuses them. Found by octree
//! subdivision with the shapes' distance bounds (a cell farther from a shape than its
//! half-diagonal cannot meet it), down to a finest cell of extent / (16·2^depth).

use glam::DVec3;
use rayon::prelude::*;

use crate::shapes::Shape;

/// Levels below the 16-cell cover: the finest cell is 1/1024 of the longest extent, an eighth
/// of a tracker cell at resolution 128; thinner overlaps may go unnoticed.
pub const DEFAULT_DEPTH: u32 = 6;

/// The first pair (i < j, in `shapes` order) of shapes that conflict (different phases, equal
/// priority) and a point inside both in the box `lo..hi`, or `None`.
pub fn find_ambiguous_overlap(
    shapes: &[Shape],
    lo: DVec3,
    hi: DVec3,
    max_depth: u32,
) -> Option<(usize, usize, DVec3)> {
    let candidates: Vec<usize> = (0..shapes.len())
        .filter(|&i| (0..shapes.len()).any(|j| conflict(&shapes[i], &shapes[j])))
        .collect();
    if candidates.is_empty() {
        return None;
    }
    let ext = hi - lo;
    let (s, tops) = crate::volume::cover(lo, hi);
    // A point counts as inside a shape when at least this deep: two shapes that only touch
    // (boxes sharing a face) must not be reported because of rounding on the shared face.
    let tol = 1e-9 * ext.max_element();
    let found: Vec<Option<(usize, usize, DVec3)>> = tops
        .par_iter()
        .map(|&c0| {
            let c1 = (c0 + DVec3::splat(s)).min(hi);
            search(shapes, &candidates, c0, c1, max_depth, tol)
        })
        .collect();
    // The first in cover order, whatever the thread count.
    found.into_iter().flatten().next()
}

fn conflict(a: &Shape, b: &Shape) -> bool {
    a.phase != b.phase && a.priority == b.priority
}

fn search(
    shapes: &[Shape],
    candidates: &[usize],
    lo: DVec3,
    hi: DVec3,
    depth: u32,
    tol: f64,
) -> Option<(usize, usize, DVec3)> {
    let c = (lo + hi) * 0.5;
    let size = hi - lo;
    let r = 0.5 * size.length();
    // Shapes that may meet this cell, with their distance bound at its centre.
    let near: Vec<(usize, f64)> = candidates
        .iter()
        .map(|&i| (i, shapes[i].sdf(c)))
        .filter(|&(_, d)| d < r)
        .collect();
    let keep: Vec<(usize, f64)> = near
        .iter()
        .copied()
        .filter(|&(i, _)| near.iter().any(|&(j, _)| conflict(&shapes[i], &shapes[j])))
        .collect();
    for (a, &(i, di)) in keep.iter().enumerate() {
        for &(j, dj) in &keep[a + 1..] {
            if di < -tol && dj < -tol && conflict(&shapes[i], &shapes[j]) {
                return Some((i.min(j), i.max(j), c));
            }
        }
    }
    if keep.is_empty() || depth == 0 {
        return None;
    }
    let ids: Vec<usize> = keep.iter().map(|&(i, _)| i).collect();
    // Split only the axes at least half as long as the longest, so thin slabs stay cheap.
    let split = size.cmpge(DVec3::splat(0.5 * size.max_element()));
    for o in 0..8u32 {
        let mut a = lo;
        let mut b = hi;
        let mut skip = false;
        for axis in 0..3 {
            let upper = o & (1 << axis) != 0;
            if !split.test(axis) {
                skip |= upper;
                continue;
            }
            if upper {
                a[axis] = c[axis];
            } else {
                b[axis] = c[axis];
            }
        }
        if skip {
            continue;
        }
        if let Some(hit) = search(shapes, &ids, a, b, depth - 1, tol) {
            return Some(hit);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::Primitive;

    fn ball(phase: u16, priority: i64, x: f64) -> Shape {
        Shape {
            phase,
            priority,
            primitive: Primitive::Sphere {
                center: DVec3::new(x, 0.5, 0.5),
                radius: 0.2,
            },
            clip: vec![],
        }
    }

    fn boxed(phase: u16, x0: f64, x1: f64) -> Shape {
        Shape {
            phase,
            priority: 0,
            primitive: Primitive::Box {
                lo: DVec3::new(x0, 0.0, 0.0),
                hi: DVec3::new(x1, 1.0, 1.0),
            },
            clip: vec![],
        }
    }

    #[test]
    fn overlap_of_equal_priority_is_found_and_priority_or_phase_resolves_it() {
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let find = |s: &[Shape]| find_ambiguous_overlap(s, lo, hi, DEFAULT_DEPTH);
        // Centres 0.3 apart, radii 0.2: a lens 0.1 thick around x = 0.5.
        let hit = find(&[ball(1, 0, 0.35), ball(2, 0, 0.65)]).expect("overlap");
        assert_eq!((hit.0, hit.1), (0, 1));
        assert!(ball(1, 0, 0.35).sdf(hit.2) < 0.0 && ball(2, 0, 0.65).sdf(hit.2) < 0.0);
        assert!(find(&[ball(1, 0, 0.35), ball(2, 1, 0.65)]).is_none());
        assert!(find(&[ball(1, 0, 0.35), ball(1, 0, 0.65)]).is_none());
        // Apart by 0.01 (about ten finest cells): no overlap.
        assert!(find(&[ball(1, 0, 0.29), ball(2, 0, 0.70)]).is_none());
        // Boxes sharing the face x = 0.4 touch without overlapping.
        assert!(find(&[boxed(1, 0.2, 0.4), boxed(2, 0.4, 0.6)]).is_none());
        assert!(find(&[boxed(1, 0.2, 0.41), boxed(2, 0.4, 0.6)]).is_some());
        // Overlapping only outside the domain is no conflict.
        assert!(find(&[boxed(1, -0.5, -0.1), boxed(2, -0.3, 0.5)]).is_none());
    }
}
