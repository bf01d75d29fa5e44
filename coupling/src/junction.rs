//! Triple curves of a labelled mesh, where three or more interfaces meet, and the direction in
//! which each interface leaves them. The mesh right at a junction is the contouring's least
//! accurate part (a triple point may sit a fraction of a cell off, bending the first triangles
//! of each sheet, and its edges zigzag about the true curve), so the curve's direction is
//! taken across the interfaces' mean normals within `reach`, and each interface's direction
//! is fitted to it a little way off the curve: over its vertices between a quarter of `reach`
//! and `reach` from the edge, projected onto the plane across the curve, a quadratic whose
//! tangent at the curve is the direction.

use std::collections::{BTreeMap, HashMap};

use glam::{DMat3, DVec2, DVec3};
use polyphase_tracker::{LabeledMesh, PhaseId, OUTSIDE};

/// One edge of a triple curve.
#[derive(Clone, Debug, PartialEq)]
pub struct JunctionEdge {
    /// The edge's midpoint.
    pub point: DVec3,
    /// The edge's extent along the curve (m).
    pub length: f64,
    /// Unit vector along the curve there, across the interfaces' normals.
    pub along: DVec3,
    /// Each interface meeting there, as its phase pair (ascending), with the unit conormal:
    /// across the curve, in the direction the interface leaves it.
    pub branches: Vec<((PhaseId, PhaseId), DVec3)>,
}

/// The edges shared by triangles of at least three different phase pairs (the domain's
/// boundary faces left out) whose every interface could be fitted, in edge order.
pub fn junction_edges(mesh: &LabeledMesh, reach: f64) -> Vec<JunctionEdge> {
    let pair_of = |t: usize| {
        let [a, b] = mesh.labels[t];
        (a != b && a != OUTSIDE && b != OUTSIDE).then_some((a.min(b), a.max(b)))
    };
    let mut edges: BTreeMap<(u32, u32), Vec<(PhaseId, PhaseId)>> = BTreeMap::new();
    // Per pair, the area normals (pointing into the pair's higher phase) summed at each of its
    // vertices, and its vertices bucketed by cells of size `reach`.
    let mut normals: BTreeMap<(PhaseId, PhaseId), HashMap<u32, DVec3>> = BTreeMap::new();
    let mut buckets: BTreeMap<(PhaseId, PhaseId), HashMap<[i64; 3], Vec<u32>>> = BTreeMap::new();
    let cell = |x: DVec3| (x / reach).floor().as_i64vec3().to_array();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let Some(pair) = pair_of(t) else { continue };
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            edges.entry((a.min(b), a.max(b))).or_default().push(pair);
        }
        let side = if mesh.labels[t][0] == pair.1 {
            1.0
        } else {
            -1.0
        };
        let n = side * mesh.area_normal(t);
        let at = normals.entry(pair).or_default();
        let bucket = buckets.entry(pair).or_default();
        for &v in tri {
            *at.entry(v).or_insert(DVec3::ZERO) += n;
            let list = bucket.entry(cell(mesh.vertices[v as usize])).or_default();
            if !list.contains(&v) {
                list.push(v);
            }
        }
    }
    edges
        .into_iter()
        .filter_map(|((a, b), mut pairs)| {
            pairs.sort_unstable();
            pairs.dedup();
            if pairs.len() < 3 {
                return None;
            }
            let (p, q) = (mesh.vertices[a as usize], mesh.vertices[b as usize]);
            let point = 0.5 * (p + q);
            // Each interface's vertices within `reach` (sorted, so that the sums below do not
            // depend on bucket order) and its mean normal there.
            let home = cell(point);
            let near: Vec<(Vec<u32>, DVec3)> = pairs
                .iter()
                .map(|pair| {
                    let mut vs = Vec::new();
                    for dz in -1..=1 {
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                let key = [home[0] + dx, home[1] + dy, home[2] + dz];
                                vs.extend(buckets[pair].get(&key).into_iter().flatten().filter(
                                    |&&v| (mesh.vertices[v as usize] - point).length() <= reach,
                                ));
                            }
                        }
                    }
                    vs.sort_unstable();
                    let normal = vs.iter().map(|v| normals[pair][v]).sum::<DVec3>();
                    (vs, normal)
                })
                .collect();
            // The curve runs across every interface's normal: along the cross product of the
            // two most different ones (a single edge of a contoured triple curve can lean by
            // tens of degrees), turned the edge's way.
            let mut along = DVec3::ZERO;
            for i in 0..near.len() {
                for j in i + 1..near.len() {
                    let c = near[i]
                        .1
                        .normalize_or_zero()
                        .cross(near[j].1.normalize_or_zero());
                    if c.length_squared() > along.length_squared() {
                        along = c;
                    }
                }
            }
            let along = along.try_normalize()?;
            let along = if along.dot(q - p) < 0.0 {
                -along
            } else {
                along
            };
            let (e1, e2) = along.any_orthonormal_pair();
            let branches = pairs
                .into_iter()
                .zip(&near)
                .map(|(pair, (vs, _))| {
                    let offsets: Vec<DVec2> = vs
                        .iter()
                        .map(|&v| mesh.vertices[v as usize] - point)
                        .filter(|d| (*d - d.dot(along) * along).length() >= 0.25 * reach)
                        .map(|d| DVec2::new(d.dot(e1), d.dot(e2)))
                        .collect();
                    let t = tangent(&offsets, reach)?;
                    Some((pair, t.x * e1 + t.y * e2))
                })
                .collect::<Option<Vec<_>>>()?;
            Some(JunctionEdge {
                point,
                length: (q - p).dot(along),
                along,
                branches,
            })
        })
        .collect()
}

/// Unit tangent at the origin of the branch through `points` (offsets from the curve, all on
/// one side of it): `w = w₀ + s·u + c·u²` fitted in the frame of the points' mean direction u,
/// its tangent at u = 0. `None` with fewer than three points or a degenerate fit.
pub(crate) fn tangent(points: &[DVec2], reach: f64) -> Option<DVec2> {
    if points.len() < 3 {
        return None;
    }
    let u_axis = points.iter().sum::<DVec2>().try_normalize()?;
    let w_axis = u_axis.perp();
    // Normal equations of the least-squares fit (symmetric, so rows or columns alike).
    let (mut m, mut rhs) = (DMat3::ZERO, DVec3::ZERO);
    for d in points {
        let (u, w) = (d.dot(u_axis) / reach, d.dot(w_axis) / reach);
        let row = DVec3::new(1.0, u, u * u);
        m += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
        rhs += row * w;
    }
    let det = m.determinant();
    if det.is_nan() || det.abs() <= 1e-12 * (m.x_axis.x * m.y_axis.y * m.z_axis.z).abs() {
        return None;
    }
    let slope = (m.inverse() * rhs).y;
    (u_axis + slope * w_axis).try_normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tangent_of_an_arc_is_found_at_its_end() {
        // Points of a circle of radius 10 through the origin, leaving it at 30°, from 1 to 3
        // units along it (the fit's annulus).
        let start = 30f64.to_radians();
        let centre = 10.0 * DVec2::new(-start.sin(), start.cos());
        let points: Vec<DVec2> = (10..30)
            .map(|i| {
                let a = start - std::f64::consts::FRAC_PI_2 + i as f64 * 0.01;
                centre + 10.0 * DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let t = tangent(&points, 3.0).expect("a tangent");
        // The quadratic holds the arc's bending; what is left is its third-order term
        // (κ² s³ / 6 ≈ 5e-3 units at s = 3), far under 0.1°.
        let angle = t.y.atan2(t.x).to_degrees();
        assert!((angle - 30.0).abs() < 0.1, "{angle}");
    }
}
