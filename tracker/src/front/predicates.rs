//! Exact geometric predicates on `f64` coordinates: orientation signs and closed
//! segment/triangle intersection tests whose answers are exact for every finite input.
//!
//! Orientation signs come from Shewchuk's adaptive-precision `orient2d`/`orient3d` (the
//! `robust` crate: floating-point filter, then exact expansion arithmetic when the filter cannot
//! decide), so the intersection tests built on them make no rounding decisions of their own:
//! every branch is taken on an exact sign or an exact coordinate comparison. Coplanar and
//! collinear configurations are decided in axis-aligned projections, which are exact (they only
//! drop a coordinate); see [`segment_triangle`] for why testing all three projections is exact.
//! Inputs must be finite and small enough that products of three coordinate differences do not
//! overflow (|x| < 1e100 is plenty).

use glam::{DVec2, DVec3};
use std::cmp::Ordering;

/// Exact sign of `(b - a) × (c - a) · (d - a)`: `Greater` when `d` lies on the side the normal
/// of triangle `abc` points to (the front side, as in [`crate::LabeledMesh`]), `Equal` when
/// the four points are coplanar.
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Ordering {
    // `robust::orient3d` is positive when `d` is below the plane seen with `abc`
    // counter-clockwise, i.e. it is the negated determinant above.
    let r = robust::orient3d(coord3(a), coord3(b), coord3(c), coord3(d));
    0.0.partial_cmp(&r).unwrap_or(Ordering::Equal)
}

/// Exact sign of `(b - a) × (c - a)` (z component) in 2D: `Greater` when `a, b, c` turn
/// counter-clockwise, `Equal` when collinear.
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> Ordering {
    let r = robust::orient2d(coord2(a), coord2(b), coord2(c));
    r.partial_cmp(&0.0).unwrap_or(Ordering::Equal)
}

fn coord3(p: DVec3) -> robust::Coord3D<f64> {
    robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

fn coord2(p: DVec2) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

/// Drops coordinate `axis` (0, 1 or 2): the exact projection onto an axis-aligned plane.
fn project(p: DVec3, axis: usize) -> DVec2 {
    match axis {
        0 => DVec2::new(p.y, p.z),
        1 => DVec2::new(p.z, p.x),
        _ => DVec2::new(p.x, p.y),
    }
}

/// `p` lies on the closed segment `ab` in 2D (exact).
fn on_segment_2d(p: DVec2, a: DVec2, b: DVec2) -> bool {
    orient2d(a, b, p) == Ordering::Equal
        && p.x >= a.x.min(b.x)
        && p.x <= a.x.max(b.x)
        && p.y >= a.y.min(b.y)
        && p.y <= a.y.max(b.y)
}

/// The closed segments `pq` and `ab` share a point in 2D (exact, degenerate segments included).
pub fn segments_intersect_2d(p: DVec2, q: DVec2, a: DVec2, b: DVec2) -> bool {
    let d1 = orient2d(p, q, a);
    let d2 = orient2d(p, q, b);
    let d3 = orient2d(a, b, p);
    let d4 = orient2d(a, b, q);
    let straddles =
        |x: Ordering, y: Ordering| x != Ordering::Equal && y != Ordering::Equal && x != y;
    if straddles(d1, d2) && straddles(d3, d4) {
        return true;
    }
    on_segment_2d(a, p, q)
        || on_segment_2d(b, p, q)
        || on_segment_2d(p, a, b)
        || on_segment_2d(q, a, b)
}

/// The closed segment `pq` meets the closed (possibly degenerate) triangle `abc` in 2D (exact).
fn segment_triangle_2d(p: DVec2, q: DVec2, a: DVec2, b: DVec2, c: DVec2) -> bool {
    if segments_intersect_2d(p, q, a, b)
        || segments_intersect_2d(p, q, b, c)
        || segments_intersect_2d(p, q, c, a)
    {
        return true;
    }
    // No edge is hit, so the segment is either inside or outside: test one endpoint. A
    // degenerate triangle is the union of its edges, which were tested above.
    let s = orient2d(a, b, c);
    s != Ordering::Equal
        && orient2d(a, b, p) == s
        && orient2d(b, c, p) == s
        && orient2d(c, a, p) == s
}

/// The closed segments `pq` and `ab` share a point in 3D (exact, degenerate segments included).
/// Coplanar segments intersect iff their projections onto all three axis planes intersect: at
/// least one projection is a bijection of their common plane (or line), and every projection of
/// an intersection point is a common point.
pub fn segments_intersect(p: DVec3, q: DVec3, a: DVec3, b: DVec3) -> bool {
    orient3d(p, q, a, b) == Ordering::Equal
        && (0..3).all(|k| {
            segments_intersect_2d(project(p, k), project(q, k), project(a, k), project(b, k))
        })
}

/// The closed segment `pq` meets the closed triangle `abc` (exact; degenerate segments and
/// triangles included).
///
/// If the segment's endpoints are not both in the triangle's plane (which forces a
/// non-degenerate triangle), it meets the triangle iff it reaches the plane (endpoint signs not
/// strictly equal) and its line passes through the closed triangle: the three tetrahedra
/// `p q a b`, `p q b c`, `p q c a` have no two orientations of strictly opposite sign. Otherwise
/// everything is coplanar (or the triangle is degenerate and then the union of its edges) and
/// the test runs in all three axis projections, exact by the argument of
/// [`segments_intersect`].
pub fn segment_triangle(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    let sp = orient3d(a, b, c, p);
    let sq = orient3d(a, b, c, q);
    if sp == sq && sp != Ordering::Equal {
        return false;
    }
    if sp != Ordering::Equal || sq != Ordering::Equal {
        let s = [
            orient3d(p, q, a, b),
            orient3d(p, q, b, c),
            orient3d(p, q, c, a),
        ];
        let pos = s.contains(&Ordering::Greater);
        let neg = s.contains(&Ordering::Less);
        return !(pos && neg);
    }
    if triangle_is_degenerate(a, b, c) {
        return segments_intersect(p, q, a, b)
            || segments_intersect(p, q, b, c)
            || segments_intersect(p, q, c, a);
    }
    (0..3).all(|k| {
        segment_triangle_2d(
            project(p, k),
            project(q, k),
            project(a, k),
            project(b, k),
            project(c, k),
        )
    })
}

/// The point `p` lies in the closed triangle `abc` (exact).
pub fn point_in_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    segment_triangle(p, p, a, b, c)
}

/// `a`, `b`, `c` are collinear (or coincide): every axis projection of the triangle has zero
/// area (exact).
pub fn triangle_is_degenerate(a: DVec3, b: DVec3, c: DVec3) -> bool {
    (0..3).all(|k| orient2d(project(a, k), project(b, k), project(c, k)) == Ordering::Equal)
}

/// The closed triangles `abc` and `def` share at least one point (exact). Two closed convex
/// sets in a common plane or in different planes meet iff an edge of one meets the other: an
/// extreme point of the (convex, compact) intersection lies on the boundary of one of them.
pub fn triangles_intersect(t: [DVec3; 3], s: [DVec3; 3]) -> bool {
    // Plane filter: all of one triangle strictly on one side of the other's plane.
    let strictly_one_side = |t: &[DVec3; 3], s: &[DVec3; 3]| {
        let o = s.map(|x| orient3d(t[0], t[1], t[2], x));
        o[0] != Ordering::Equal && o[0] == o[1] && o[1] == o[2]
    };
    if strictly_one_side(&t, &s) || strictly_one_side(&s, &t) {
        return false;
    }
    (0..3).any(|i| segment_triangle(t[i], t[(i + 1) % 3], s[0], s[1], s[2]))
        || (0..3).any(|i| segment_triangle(s[i], s[(i + 1) % 3], t[0], t[1], t[2]))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use num_rational::BigRational;
    use num_traits::{Signed, Zero};

    fn q(x: f64) -> BigRational {
        BigRational::from_float(x).expect("finite")
    }

    /// Exact rational orientation, the oracle for [`orient3d`].
    fn orient3d_exact(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Ordering {
        let s = |p: DVec3, o: DVec3| [q(p.x) - q(o.x), q(p.y) - q(o.y), q(p.z) - q(o.z)];
        let (u, v, w) = (s(b, a), s(c, a), s(d, a));
        let det = &u[0] * (&v[1] * &w[2] - &v[2] * &w[1]) - &u[1] * (&v[0] * &w[2] - &v[2] * &w[0])
            + &u[2] * (&v[0] * &w[1] - &v[1] * &w[0]);
        if det.is_zero() {
            Ordering::Equal
        } else if det.is_positive() {
            Ordering::Greater
        } else {
            Ordering::Less
        }
    }

    /// Deterministic splitmix64 stream for the random tests.
    pub(crate) struct Rng(pub u64);
    impl Rng {
        pub fn next_u64(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// Uniform in [-1, 1).
        pub fn f(&mut self) -> f64 {
            (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        pub fn v(&mut self) -> DVec3 {
            DVec3::new(self.f(), self.f(), self.f())
        }
    }

    #[test]
    fn orient3d_matches_rationals_on_near_coplanar_points() {
        let mut rng = Rng(7);
        let mut zeros = 0;
        for i in 0..400 {
            let (a, b, c) = (rng.v(), rng.v(), rng.v());
            // A point on the plane up to rounding, then nudged by a few ulps: the naive
            // determinant's rounding error dwarfs the true value here.
            let (s, t) = (rng.f(), rng.f());
            let mut d = a + s * (b - a) + t * (c - a);
            for _ in 0..(i % 4) {
                d.x = d.x.next_up();
            }
            let exact = orient3d_exact(a, b, c, d);
            assert_eq!(orient3d(a, b, c, d), exact);
            zeros += usize::from(exact == Ordering::Equal);
            // Exactly coplanar: a lattice point on the plane z = 0 through a scaled lattice.
            let l = |x: f64, y: f64| DVec3::new(x, y, 0.0) * 2f64.powi(-20) + DVec3::splat(0.5);
            let (a, b, c, d) = (
                l(1.0, 3.0),
                l(7.0, -2.0),
                l(-5.0, 11.0),
                l(3.0, 3.0 + i as f64),
            );
            assert_eq!(orient3d(a, b, c, d), Ordering::Equal);
            assert_eq!(orient3d_exact(a, b, c, d), Ordering::Equal);
        }
        // Sanity of the oracle on this sample: some random "on-plane" points are not exactly
        // on it, which is the point of the test.
        assert!(zeros < 400);
    }

    #[test]
    fn orient3d_sign_convention_matches_mesh_normals() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(orient3d(a, b, c, DVec3::Z), Ordering::Greater);
        assert_eq!(orient3d(a, b, c, -DVec3::Z), Ordering::Less);
        assert_eq!(orient2d(DVec2::ZERO, DVec2::X, DVec2::Y), Ordering::Greater);
    }

    #[test]
    fn segment_triangle_degenerate_cases() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        // Crossing through the interior, touching a vertex, touching an edge, ending on the face.
        assert!(segment_triangle(
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            a,
            b,
            c
        ));
        assert!(segment_triangle(
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, 1.0),
            a,
            b,
            c
        ));
        assert!(segment_triangle(
            DVec3::new(0.5, 0.5, -1.0),
            DVec3::new(0.5, 0.5, 1.0),
            a,
            b,
            c
        ));
        assert!(segment_triangle(
            DVec3::new(0.2, 0.2, 0.0),
            DVec3::new(0.2, 0.2, 1.0),
            a,
            b,
            c
        ));
        // Passing just beside the hypotenuse (one ulp outside) misses.
        let x = 0.5f64.next_up();
        assert!(!segment_triangle(
            DVec3::new(x, 0.5, -1.0),
            DVec3::new(x, 0.5, 1.0),
            a,
            b,
            c
        ));
        // Coplanar: crossing, touching an edge from outside, disjoint.
        assert!(segment_triangle(
            DVec3::new(-1.0, 0.2, 0.0),
            DVec3::new(2.0, 0.2, 0.0),
            a,
            b,
            c
        ));
        assert!(segment_triangle(
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            a,
            b,
            c
        ));
        assert!(!segment_triangle(
            DVec3::new(1.0, 0.5, 0.0),
            DVec3::new(2.0, 0.5, 0.0),
            a,
            b,
            c
        ));
        // Coplanar segment strictly inside the triangle.
        assert!(segment_triangle(
            DVec3::new(0.1, 0.1, 0.0),
            DVec3::new(0.2, 0.1, 0.0),
            a,
            b,
            c
        ));
        // Degenerate triangle (a segment) against skew and crossing segments.
        let (d, e) = (DVec3::ZERO, DVec3::X);
        assert!(segment_triangle(
            DVec3::new(0.5, -1.0, 0.0),
            DVec3::new(0.5, 1.0, 0.0),
            d,
            e,
            e
        ));
        assert!(!segment_triangle(
            DVec3::new(0.5, -1.0, 1.0),
            DVec3::new(0.5, 1.0, 0.5),
            d,
            e,
            e
        ));
        // Parallel segments: collinear overlap, collinear disjoint, parallel offset.
        assert!(segments_intersect(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0)
        ));
        assert!(!segments_intersect(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(1.5, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0)
        ));
        assert!(!segments_intersect(
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(1.0, 1.0, 0.0)
        ));
    }

    #[test]
    fn triangles_intersect_cases() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Piercing, touching at a vertex, coplanar overlap, coplanar disjoint, parallel planes.
        let pierce = [
            DVec3::new(0.2, 0.2, -1.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(3.0, 3.0, 0.0),
        ];
        assert!(triangles_intersect(t, pierce));
        let touch = [
            DVec3::X,
            DVec3::new(2.0, 0.0, 1.0),
            DVec3::new(2.0, 1.0, -1.0),
        ];
        assert!(triangles_intersect(t, touch));
        let overlap = [
            DVec3::new(0.1, 0.1, 0.0),
            DVec3::new(2.0, 0.1, 0.0),
            DVec3::new(0.1, 2.0, 0.0),
        ];
        assert!(triangles_intersect(t, overlap));
        let apart = [
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
        ];
        assert!(!triangles_intersect(t, apart));
        let lifted = t.map(|p| p + DVec3::new(0.0, 0.0, 1e-300));
        assert!(!triangles_intersect(t, lifted));
    }
}
