//! Continuous collision detection for vertex–triangle and edge–edge pairs moving linearly over
//! `t ∈ [0, 1]`: an inclusion-based bisection in the spirit of Tight Inclusion (Wang et al.
//! 2021) that never misses a contact.
//!
//! # Method
//! A contact is a zero of `F(t, u, v)` on its parameter domain, where
//! - vertex–triangle: `F = p(t) − a(t) − u (b(t) − a(t)) − v (c(t) − a(t))`, `u, v ≥ 0`,
//!   `u + v ≤ 1`;
//! - edge–edge: `F = a0(t) + u (a1(t) − a0(t)) − b0(t) − v (b1(t) − b0(t))`, `u, v ∈ [0, 1]`;
//!
//! and `x(t) = x(0) + t (x(1) − x(0))`. `F` is affine in each of `t`, `u`, `v` separately, so
//! on any box of `(t, u, v)` each coordinate of `F` takes its extreme values at the box's eight
//! corners. A box whose corner values (widened by a rigorous rounding-error bound) exclude 0 in
//! some coordinate, or along a separating direction (see [`separated_along`]), holds no contact
//! and is discarded; otherwise it is split in two and the halves are examined depth first,
//! the one whose `F` range is better centred on zero first (a `t`-ordered, breadth-first
//! search instead must exhaust every box just before a degenerate contact, e.g. parallel
//! edges becoming collinear, which costs thousands of boxes). The separating-direction test is what keeps near-parallel sliding at a small gap
//! cheap: there the per-coordinate ranges straddle zero until the boxes are tiny.
//!
//! # Why it never returns `false` for a real contact
//! Every discarded box provably contains no zero of the exact `F` (the same argument covers
//! `F · n` for a fixed vector `n`, [`separated_along`]):
//! - the corners are dyadic numbers (halvings of `[0, 1]`), represented exactly;
//! - the corner values are computed by a fixed sequence of `f64` operations ([`corner_values`])
//!   on inputs bounded by `m_k` (the largest `|x_k|` of the eight input points) and parameters
//!   in `[0, 1]`; a forward error analysis (each operation adds at most `2⁻⁵³` of its result;
//!   a lerp errs by `5`, a difference of lerps by `12`, the final value, bounded by `6 m_k`, by
//!   `51` units of `2⁻⁵³ m_k`) bounds the error by `51 · 2⁻⁵³ m_k`; we use
//!   `64 · 2⁻⁵³ m_k` plus `f64::MIN_POSITIVE` for underflow ([`rounding_bound`]);
//! - vertex–triangle boxes are discarded for lying outside the domain only when
//!   `u_lo + v_lo > 1`, which is exact for dyadic bounds.
//!
//! A box is reported as a contact (the search stops) when the corner values, widened, contain
//! zero and are all within `δ = NEAR_MISS_REL ×` (extent of the eight points) in every
//! coordinate, when it cannot be split further (widths below `2⁻³⁶`), or after
//! [`MAX_BOXES`] boxes (a safety cap never reached in the tests). So `true` may also mean a near
//! miss: in the first case some point of the domain has `|F|∞ ≤ δ + 2 ε`, i.e. the primitives
//! come within `√3 (δ + 2 ε)` of each other. Inputs must be finite with `|x| < 1e150`.

use crate::front::response::proximity::{point_triangle_closest, segment_segment_closest};
use glam::DVec3;

/// Relative near-miss tolerance `δ / extent` (see the module doc): pairs closer than about
/// `1e-6` times the size of their swept bounding box (as in Tight Inclusion) may be reported as touching.
pub const NEAR_MISS_REL: f64 = 1e-6;

/// Boxes examined before giving up and reporting a (possible) contact.
pub const MAX_BOXES: usize = 1 << 14;

/// Parameter boxes narrower than this in every direction are not split further.
const MIN_WIDTH: f64 = 1.0 / (1u64 << 36) as f64;

/// A (possible) contact found by the search: the start `t` of the accepted box's time interval
/// (a contact, or a near miss, happens in it; not necessarily the earliest one) and the
/// parameters `u`, `v` at the middle of that box (barycentric coordinates of `b`, `c` for
/// vertex–triangle, edge parameters for edge–edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub u: f64,
    pub v: f64,
}

/// `true` if the vertex `x[0]` touches the triangle `x[1], x[2], x[3]` at some `t ∈ [0, 1]`
/// when every point moves linearly from `x0` to `x1` (touching at `t = 0` or `t = 1` counts).
/// Never `false` for a real contact; may be `true` for a near miss (module doc).
pub fn vertex_triangle(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> bool {
    vertex_triangle_hit(x0, x1).is_some()
}

/// `true` if the segment `x[0] x[1]` touches the segment `x[2] x[3]` at some `t ∈ [0, 1]` under
/// linear motion from `x0` to `x1`. Never `false` for a real contact; may be `true` for a near
/// miss (module doc).
pub fn edge_edge(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> bool {
    edge_edge_hit(x0, x1).is_some()
}

/// [`vertex_triangle`] with the contact's approximate time and barycentric coordinates.
pub fn vertex_triangle_hit(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> Option<Hit> {
    let sweep = |i: usize| (x0[i].min(x1[i]), x0[i].max(x1[i]));
    let (plo, phi) = sweep(0);
    let (mut tlo, mut thi) = sweep(1);
    for i in 2..4 {
        let (lo, hi) = sweep(i);
        tlo = tlo.min(lo);
        thi = thi.max(hi);
    }
    if !boxes_overlap(plo, phi, tlo, thi)
        || separated_by_closest_points(Kind::VertexTriangle, x0, x1)
    {
        return None;
    }
    search(Kind::VertexTriangle, x0, x1)
}

/// [`edge_edge`] with the contact's approximate time and edge parameters.
pub fn edge_edge_hit(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> Option<Hit> {
    let sweep = |i: usize, j: usize| {
        (
            x0[i].min(x1[i]).min(x0[j].min(x1[j])),
            x0[i].max(x1[i]).max(x0[j].max(x1[j])),
        )
    };
    let (alo, ahi) = sweep(0, 1);
    let (blo, bhi) = sweep(2, 3);
    if !boxes_overlap(alo, ahi, blo, bhi) || separated_by_closest_points(Kind::EdgeEdge, x0, x1) {
        return None;
    }
    search(Kind::EdgeEdge, x0, x1)
}

/// Closed boxes overlap (exact comparisons).
pub fn boxes_overlap(alo: DVec3, ahi: DVec3, blo: DVec3, bhi: DVec3) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

/// `true` if one fixed direction keeps the two primitives apart over the whole motion, by more
/// than twice the near-miss distance `δ` of [`search`]: the direction `n` from the second
/// primitive's closest point to the first's at `t = 1/2`. The gap along `n` between a point of
/// each primitive is smallest at a corner pair and affine in `t`, so positive gaps at both ends
/// for every corner pair prove it throughout. This is the cheap verdict for the common pair of
/// nearby primitives that move together (neighbours on a smooth surface), where the per-coordinate
/// ranges and the triangle normal of [`separated_along`] separate nothing until the boxes are
/// small. A pair this test passes is one [`search`] would also pass (its near misses lie within
/// `√3 (δ + 2 ε) < 2 δ`), so results do not change, only their cost.
fn separated_by_closest_points(kind: Kind, x0: &[DVec3; 4], x1: &[DVec3; 4]) -> bool {
    let m: [DVec3; 4] = std::array::from_fn(|i| x0[i] + 0.5 * (x1[i] - x0[i]));
    let (n, pairs): (DVec3, &[(usize, usize)]) = match kind {
        Kind::VertexTriangle => {
            let w = point_triangle_closest(m[0], m[1], m[2], m[3]);
            let q = w[0] * m[1] + w[1] * m[2] + w[2] * m[3];
            (m[0] - q, &[(0, 1), (0, 2), (0, 3)])
        }
        Kind::EdgeEdge => {
            let (s, t) = segment_segment_closest(m[0], m[1], m[2], m[3]);
            let p = m[0] + s * (m[1] - m[0]);
            let q = m[2] + t * (m[3] - m[2]);
            (p - q, &[(0, 2), (0, 3), (1, 2), (1, 3)])
        }
    };
    if n == DVec3::ZERO || !n.is_finite() {
        return false;
    }
    let (lo, hi) = x0
        .iter()
        .chain(x1.iter())
        .fold((x0[0], x0[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let delta = NEAR_MISS_REL * (hi - lo).max_element();
    // Each gap `n · (x_i − x_j)` errs by at most `4 · 2⁻⁵³ Σ |n_k| |x_ik − x_jk|` (one rounded
    // difference, three products, two sums), bounded here with a margin.
    let na = n.abs();
    let margin = 2.0 * delta * n.length() * (1.0 + 1e-12);
    [x0, x1].iter().all(|x| {
        pairs.iter().all(|&(i, j)| {
            let f = x[i] - x[j];
            let slack = 4.0 * f64::EPSILON * na.dot(f.abs()) * (1.0 + 1e-12) + f64::MIN_POSITIVE;
            n.dot(f) - slack > margin
        })
    })
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    VertexTriangle,
    EdgeEdge,
}

/// A box of the `(t, u, v)` domain: `lo[d]`, `hi[d]` for `d` = 0 (t), 1 (u), 2 (v).
#[derive(Clone, Copy, Debug, PartialEq)]
struct ParamBox {
    lo: [f64; 3],
    hi: [f64; 3],
}

/// Rigorous bound, per coordinate, on the rounding error of a computed corner value of `F`
/// (module doc): `64 · 2⁻⁵³ · max |x_k|` plus an underflow allowance.
fn rounding_bound(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> DVec3 {
    let m = x0
        .iter()
        .chain(x1.iter())
        .fold(DVec3::ZERO, |m, p| m.max(p.abs()));
    m * (64.0 * f64::EPSILON / 2.0) + DVec3::splat(f64::MIN_POSITIVE)
}

fn search(kind: Kind, x0: &[DVec3; 4], x1: &[DVec3; 4]) -> Option<Hit> {
    let err = rounding_bound(x0, x1);
    let (lo, hi) = x0
        .iter()
        .chain(x1.iter())
        .fold((x0[0], x0[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let delta = NEAR_MISS_REL * (hi - lo).max_element();
    // A box that survives the exclusion tests, with its corner values, `F` range and score.
    let examine = |b: ParamBox| -> Option<Candidate> {
        if kind == Kind::VertexTriangle && b.lo[1] + b.lo[2] > 1.0 {
            return None;
        }
        let corners = corner_values(kind, x0, x1, &b);
        let (flo, fhi) = corners
            .iter()
            .fold((corners[0], corners[0]), |(lo, hi), &f| {
                (lo.min(f), hi.max(f))
            });
        let (flo, fhi) = (flo - err, fhi + err);
        if flo.cmpgt(DVec3::ZERO).any() || fhi.cmplt(DVec3::ZERO).any() {
            return None;
        }
        if separated_along(kind, x0, x1, &b, &corners, err) {
            return None;
        }
        let half = (0.5 * (fhi - flo)).max(DVec3::splat(f64::MIN_POSITIVE));
        let score = ((0.5 * (fhi + flo)).abs() / half).max_element();
        Some(Candidate {
            b,
            corners,
            width: fhi - flo - 2.0 * err,
            score,
        })
    };
    let root = examine(ParamBox {
        lo: [0.0; 3],
        hi: [1.0; 3],
    })?;
    let mut stack = vec![root];
    let mut examined = 0usize;
    while let Some(c) = stack.pop() {
        examined += 1;
        if examined > MAX_BOXES || c.width.cmple(DVec3::splat(delta)).all() {
            return Some(hit_of(&c.b));
        }
        let Some(d) = split_direction(&c.corners, &c.b) else {
            return Some(hit_of(&c.b));
        };
        let mid = 0.5 * (c.b.lo[d] + c.b.hi[d]);
        let (mut first, mut second) = (c.b, c.b);
        first.hi[d] = mid;
        second.lo[d] = mid;
        match (examine(first), examine(second)) {
            (Some(a), Some(b)) => {
                // The child whose F range is better centred on zero is examined first.
                let (later, sooner) = if b.score < a.score { (a, b) } else { (b, a) };
                stack.push(later);
                stack.push(sooner);
            }
            (Some(a), None) | (None, Some(a)) => stack.push(a),
            (None, None) => {}
        }
    }
    None
}

/// A box of the search that could hold a contact.
struct Candidate {
    b: ParamBox,
    corners: [DVec3; 8],
    /// Width of the computed `F` range per coordinate (without the rounding allowance).
    width: DVec3,
    /// Where zero sits in the widened `F` range: 0 at the centre, 1 on its boundary
    /// (largest over coordinates).
    score: f64,
}

/// `true` if `F · n` provably keeps one strict sign on the box for the primitive's normal `n`
/// at the box's middle time (triangle normal, or the edges' cross product) or for the mean
/// corner value of `F`. For a fixed `n`, `F · n` is again affine in each parameter, so its range
/// is spanned by the corner values; each computed dot product errs by at most
/// `Σ |n_k| ε_k` (input error) plus `3 · 2⁻⁵³ Σ |n_k F_k|` (three products and two sums),
/// bounded here with a margin.
fn separated_along(
    kind: Kind,
    x0: &[DVec3; 4],
    x1: &[DVec3; 4],
    b: &ParamBox,
    corners: &[DVec3; 8],
    err: DVec3,
) -> bool {
    let tm = 0.5 * (b.lo[0] + b.hi[0]);
    let p: [DVec3; 4] = std::array::from_fn(|i| x0[i] + tm * (x1[i] - x0[i]));
    let normal = match kind {
        Kind::VertexTriangle => (p[2] - p[1]).cross(p[3] - p[1]),
        Kind::EdgeEdge => (p[1] - p[0]).cross(p[3] - p[2]),
    };
    let mean = corners.iter().sum::<DVec3>() / 8.0;
    [normal, mean].iter().any(|&n| {
        if n == DVec3::ZERO || !n.is_finite() {
            return false;
        }
        let na = n.abs();
        let input = na.dot(err);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for f in corners {
            let slack =
                (input + 4.0 * f64::EPSILON * na.dot(f.abs())) * (1.0 + 1e-12) + f64::MIN_POSITIVE;
            let g = f.dot(n);
            lo = lo.min(g - slack);
            hi = hi.max(g + slack);
        }
        lo > 0.0 || hi < 0.0
    })
}

fn hit_of(b: &ParamBox) -> Hit {
    Hit {
        t: b.lo[0],
        u: 0.5 * (b.lo[1] + b.hi[1]),
        v: 0.5 * (b.lo[2] + b.hi[2]),
    }
}

/// The direction whose parameter change moves `F` the most (largest corner difference along
/// it), among those still wider than [`MIN_WIDTH`]; `None` if the box cannot be split.
fn split_direction(corners: &[DVec3; 8], b: &ParamBox) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for d in 0..3 {
        if b.hi[d] - b.lo[d] < MIN_WIDTH {
            continue;
        }
        let bit = 1 << d;
        let spread = (0..8)
            .filter(|i| i & bit == 0)
            .map(|i| (corners[i | bit] - corners[i]).abs().max_element())
            .fold(0.0, f64::max);
        if best.is_none_or(|(_, s)| spread > s) {
            best = Some((d, spread));
        }
    }
    best.map(|(d, _)| d)
}

/// `F` at the eight corners of `b`; corner `i` takes `t`, `u`, `v` from `hi` where bits 0, 1,
/// 2 of `i` are set. The operation sequence is the one the module doc's error bound counts.
fn corner_values(kind: Kind, x0: &[DVec3; 4], x1: &[DVec3; 4], b: &ParamBox) -> [DVec3; 8] {
    let at = |t: f64| -> [DVec3; 4] { std::array::from_fn(|i| x0[i] + t * (x1[i] - x0[i])) };
    let pos = [at(b.lo[0]), at(b.hi[0])];
    std::array::from_fn(|i| {
        let p = &pos[i & 1];
        let u = if i & 2 == 0 { b.lo[1] } else { b.hi[1] };
        let v = if i & 4 == 0 { b.lo[2] } else { b.hi[2] };
        match kind {
            Kind::VertexTriangle => {
                let (pa, ba, ca) = (p[0] - p[1], p[2] - p[1], p[3] - p[1]);
                (pa - u * ba) - v * ca
            }
            Kind::EdgeEdge => (p[0] + u * (p[1] - p[0])) - (p[2] + v * (p[3] - p[2])),
        }
    })
}

#[cfg(test)]
mod tests;
