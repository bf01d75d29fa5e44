//! Closest point on a triangle, with the feature (face, edge, vertex) it lies on (Ericson,
//! "Real-Time Collision Detection" §5.1.5: Voronoi regions tested with barycentric
//! dot products), guarded so that degenerate triangles give finite results.

use glam::DVec3;

/// Where on triangle `[a, b, c]` the closest point lies. Edge `k` joins corner `k` and corner
/// `(k + 1) % 3` (0 = ab, 1 = bc, 2 = ca); vertex `k` is corner `k`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Region {
    Face,
    Edge(u8),
    Vertex(u8),
}

/// Closest point to `p` on the triangle `[a, b, c]` and the region it lies in.
#[inline]
pub(crate) fn closest_point(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, Region) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Region::Vertex(0));
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Region::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        // d1 - d3 = |ab|²: zero only when a == b (degenerate, handled edge by edge).
        let den = d1 - d3;
        return match den > 0.0 {
            true => (a + ab * (d1 / den), Region::Edge(0)),
            false => closest_on_edges(p, [a, b, c]),
        };
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Region::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let den = d2 - d6; // |ac|²
        return match den > 0.0 {
            true => (a + ac * (d2 / den), Region::Edge(2)),
            false => closest_on_edges(p, [a, b, c]),
        };
    }
    let va = d3 * d6 - d5 * d4;
    let (e, f) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e >= 0.0 && f >= 0.0 {
        let den = e + f; // |bc|²
        return match den > 0.0 {
            true => (b + (c - b) * (e / den), Region::Edge(1)),
            false => closest_on_edges(p, [a, b, c]),
        };
    }
    let sum = va + vb + vc;
    if va > 0.0 && vb > 0.0 && vc > 0.0 && sum.is_finite() {
        let (v, w) = (vb / sum, vc / sum);
        return (a + ab * v + ac * w, Region::Face);
    }
    // Only reachable through rounding on a (near-)degenerate triangle: the closest point is
    // then on its boundary.
    closest_on_edges(p, [a, b, c])
}

/// Closest point among the three edges of a (degenerate) triangle.
#[cold]
fn closest_on_edges(p: DVec3, v: [DVec3; 3]) -> (DVec3, Region) {
    let mut best = (v[0], Region::Vertex(0));
    let mut best_d2 = f64::INFINITY;
    for k in 0..3 {
        let (s, e) = (v[k], v[(k + 1) % 3]);
        let d = e - s;
        let len2 = d.length_squared();
        let t = if len2 > 0.0 {
            ((p - s).dot(d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (q, region) = match t {
            t if t <= 0.0 => (s, Region::Vertex(k as u8)),
            t if t >= 1.0 => (e, Region::Vertex(((k + 1) % 3) as u8)),
            t => (s + d * t, Region::Edge(k as u8)),
        };
        let d2 = (p - q).length_squared();
        if d2 < best_d2 {
            best_d2 = d2;
            best = (q, region);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regions_of_a_right_triangle() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let cases = [
            (
                DVec3::new(0.2, 0.2, 1.0),
                DVec3::new(0.2, 0.2, 0.0),
                Region::Face,
            ),
            (DVec3::new(-1.0, -1.0, 0.5), a, Region::Vertex(0)),
            (DVec3::new(2.0, -0.5, 0.0), b, Region::Vertex(1)),
            (DVec3::new(-0.1, 3.0, 0.0), c, Region::Vertex(2)),
            (
                DVec3::new(0.5, -1.0, 0.3),
                DVec3::new(0.5, 0.0, 0.0),
                Region::Edge(0),
            ),
            (
                DVec3::new(1.0, 1.0, -2.0),
                DVec3::new(0.5, 0.5, 0.0),
                Region::Edge(1),
            ),
            (
                DVec3::new(-1.0, 0.25, 0.0),
                DVec3::new(0.0, 0.25, 0.0),
                Region::Edge(2),
            ),
        ];
        for (p, q, r) in cases {
            let (y, region) = closest_point(p, a, b, c);
            // Dyadic inputs: the barycentric arithmetic is exact here.
            assert!((y - q).length() < 1e-15, "{p}: {y} vs {q}");
            assert_eq!(region, r, "{p}");
        }
    }

    #[test]
    fn degenerate_triangles_give_finite_points() {
        let p = DVec3::new(0.3, 0.7, -0.2);
        let needle = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 1e-300, 0.0)];
        let flat = [DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)];
        let point = [DVec3::ONE; 3];
        let pair = [DVec3::ZERO, DVec3::ZERO, DVec3::Y];
        for [a, b, c] in [needle, flat, point, pair] {
            let (y, _) = closest_point(p, a, b, c);
            assert!(y.is_finite(), "{a} {b} {c}: {y}");
            // The closest point lies on the segment hull of the corners, so it can be no
            // farther than the nearest corner.
            let nearest_corner = [a, b, c]
                .iter()
                .map(|v| v.distance(p))
                .fold(f64::INFINITY, f64::min);
            assert!(y.distance(p) <= nearest_corner + 1e-15, "{a} {b} {c}: {y}");
        }
    }
}
