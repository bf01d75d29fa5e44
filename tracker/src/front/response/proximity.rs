//! Closest points between mesh primitives (floating point) and the proximity pairs of a static
//! configuration, the input of the repulsion pass of [`super::resolve`] (Bridson et al. 2002
//! §7.2: pairs closer than the thickness get their approach stopped before CCD runs).

use crate::front::broadphase::StaticGrid;
use crate::front::collision::{cell_size_for, swept_triangle_box, Contact, Detector};
use glam::DVec3;
use rayon::prelude::*;

/// Barycentric weights `[wa, wb, wc]` (summing to 1, all ≥ 0) of the point of triangle `abc`
/// closest to `p`, by the Voronoi-region case analysis of the triangle's vertices, edges and
/// face.
pub fn point_triangle_closest(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let w = d1 / (d1 - d3);
        return [1.0 - w, w, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = va + vb + vc;
    if denom.abs() <= f64::MIN_POSITIVE {
        // Degenerate triangle whose Voronoi tests all failed by rounding: nearest vertex.
        let d = [a, b, c].map(|x| x.distance_squared(p));
        let i = (0..3).fold(0, |m, i| if d[i] < d[m] { i } else { m });
        let mut w = [0.0; 3];
        w[i] = 1.0;
        return w;
    }
    let (v, w) = (vb / denom, vc / denom);
    [1.0 - v - w, v, w]
}

/// Parameters `(s, t) ∈ [0, 1]²` of the closest points `p0 + s (p1 − p0)` and
/// `q0 + t (q1 − q0)` of two segments (minimisation of the squared distance, clamped to the
/// segments; parallel segments get one of the closest pairs).
pub fn segment_segment_closest(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let tiny = f64::MIN_POSITIVE;
    if a <= tiny && e <= tiny {
        return (0.0, 0.0);
    }
    if a <= tiny {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= tiny {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > 0.0 {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

/// Distance from `p` to triangle `abc`.
pub fn point_triangle_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let w = point_triangle_closest(p, a, b, c);
    p.distance(w[0] * a + w[1] * b + w[2] * c)
}

/// Distance between segments `p0 p1` and `q0 q1`.
pub fn segment_segment_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let (s, t) = segment_segment_closest(p0, p1, q0, q1);
    (p0 + s * (p1 - p0)).distance(q0 + t * (q1 - q0))
}

/// The vertex–triangle and edge–edge pairs (sharing no vertex) of the static configuration `x`
/// closer than `h`, as [`Contact`]s in the order of [`crate::front::collision::detect`].
pub fn proximity_pairs(
    topology: &Detector,
    triangles: &[[u32; 3]],
    x: &[DVec3],
    h: f64,
) -> Vec<Contact> {
    let pad = DVec3::splat(h);
    let boxes: Vec<(DVec3, DVec3)> = triangles
        .par_iter()
        .map(|t| {
            let (lo, hi) = swept_triangle_box(t, x, x);
            (lo - pad, hi + pad)
        })
        .collect();
    let cell = cell_size_for(&boxes);
    let grid = StaticGrid::build(boxes, cell);
    let mut out: Vec<Contact> = topology
        .vertices()
        .par_iter()
        .map_init(Vec::new, |cand, &v| {
            let p = x[v as usize];
            grid.query(p, p, cand);
            cand.iter()
                .filter(|&&t| {
                    let tri = triangles[t as usize];
                    let [a, b, c] = tri.map(|i| x[i as usize]);
                    !tri.contains(&v) && point_triangle_distance(p, a, b, c) < h
                })
                .map(|&t| Contact::VertexTriangle {
                    vertex: v,
                    triangle: t,
                })
                .collect::<Vec<_>>()
        })
        .flatten()
        .collect();
    let (edges, tri_edges) = (topology.edges(), topology.tri_edges());
    // Edge boxes padded by h: two edges closer than h have overlapping padded boxes, which
    // settles most candidates before any distance is computed.
    let edge_boxes: Vec<(DVec3, DVec3)> = edges
        .par_iter()
        .map(|&[a, b]| {
            let (p, q) = (x[a as usize], x[b as usize]);
            (p.min(q) - pad, p.max(q) + pad)
        })
        .collect();
    let ee: Vec<Contact> = (0..edges.len() as u32)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(cand, others), e| {
                let ea = edges[e as usize];
                let (p0, p1) = (x[ea[0] as usize], x[ea[1] as usize]);
                grid.query(p0.min(p1), p0.max(p1), cand);
                others.clear();
                others.extend(
                    cand.iter()
                        .flat_map(|&t| tri_edges[t as usize])
                        .filter(|&f| f > e),
                );
                others.sort_unstable();
                others.dedup();
                let (elo, ehi) = edge_boxes[e as usize];
                others
                    .iter()
                    .filter(|&&f| {
                        let (flo, fhi) = edge_boxes[f as usize];
                        elo.cmple(fhi).all() && flo.cmple(ehi).all()
                    })
                    .map(|&f| edges[f as usize])
                    .filter(|eb| {
                        !ea.iter().any(|v| eb.contains(v))
                            && segment_segment_distance(
                                p0,
                                p1,
                                x[eb[0] as usize],
                                x[eb[1] as usize],
                            ) < h
                    })
                    .map(|eb| Contact::EdgeEdge { a: ea, b: eb })
                    .collect::<Vec<_>>()
            },
        )
        .flatten()
        .collect();
    out.extend(ee);
    out
}
