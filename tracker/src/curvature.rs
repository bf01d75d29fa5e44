//! Mean curvature of the interfaces of a [`LabeledMesh`], measured off the mesh, for surface
//! tension. Contoured meshes are irregular (slivers, uneven valence), and cotangent formulas
//! amplify that irregularity into noise; a local least-squares fit of a quadratic height
//! function over a neighbourhood a few cells wide averages it out instead.
//!
//! At a query point x, for the interface between two phases, only that pair's triangles
//! count (near a triple curve the other interfaces stay out): the nearest point y on them
//! (the foot point), their vertices within `radius` of y connected through edges to the
//! nearest triangle, the area-weighted normal n there, and in the frame (t₁, t₂, n) at y the
//! weighted least-squares fit of `h(u, v) = a u² + b uv + c v² + d u + e v + f` to those
//! vertices. The curvature of the fitted graph at y, with its slope terms,
//! `κ = −∇·(∇h / √(1 + |∇h|²))`, is the answer. Its error on a contoured sphere of radius R
//! is mostly a bias, an overestimate of about 0.17·(radius/R)² (the quartic term of the
//! sphere's height, which a quadratic cannot hold): 0.4 % at radius 2.5 cells and R = 16
//! cells, 1.7 % at R = 8. Radii below about 1.5 cells hold too few vertices of a contoured
//! mesh for a steady fit.

use std::collections::BTreeMap;

use glam::DVec3;
use polyphase_grid::{PhaseId, OUTSIDE};

use crate::mesh::LabeledMesh;
use crate::query::MeshQuery;

/// Fewest vertices the six-coefficient fit is attempted with.
const MIN_POINTS: usize = 6;

/// Mean curvature of the interfaces of a labelled mesh, by local least-squares fits.
/// Immutable after construction, `Send + Sync`: share one across threads. Every answer is a
/// pure function of the mesh, the radius and the query, whatever the thread count.
#[derive(Clone, Debug)]
pub struct CurvatureSampler {
    radius: f64,
    /// One surface per phase pair that shares triangles, sorted by pair.
    surfaces: Vec<PairSurface>,
}

/// The triangles between phases `lo < hi`, oriented so that their normals point into `hi`.
#[derive(Clone, Debug)]
struct PairSurface {
    pair: (PhaseId, PhaseId),
    /// This pair's triangles only, over their own vertices, labelled `[hi, lo]`.
    mesh: LabeledMesh,
    /// Nearest points on `mesh`.
    query: MeshQuery,
    /// Vertices sharing an edge with vertex `v`: `neighbours[first[v] .. first[v + 1]]`,
    /// ascending.
    first: Vec<u32>,
    neighbours: Vec<u32>,
    /// Per vertex, the sum of its triangles' area normals (length: twice their area).
    area_normals: Vec<DVec3>,
}

impl CurvatureSampler {
    /// `radius`: the fitting neighbourhood (m), about 2–3 tracker cells: wider averages out
    /// more of the mesh's irregularity, narrower resolves smaller features (the fit's own
    /// error grows like (radius / R)² on a sphere of radius R). Faces with an `OUTSIDE` label
    /// (the domain boundary) are left out. A radius of zero or NaN makes every answer `None`.
    /// Panics if a triangle index is out of range or the
    /// label count differs, as [`MeshQuery::new`] does.
    pub fn new(mesh: &LabeledMesh, radius: f64) -> CurvatureSampler {
        assert_eq!(
            mesh.labels.len(),
            mesh.triangles.len(),
            "one label pair per triangle"
        );
        let mut by_pair: BTreeMap<(PhaseId, PhaseId), Vec<usize>> = BTreeMap::new();
        for (t, &[front, back]) in mesh.labels.iter().enumerate() {
            if front != back && front != OUTSIDE && back != OUTSIDE {
                by_pair
                    .entry((front.min(back), front.max(back)))
                    .or_default()
                    .push(t);
            }
        }
        let mut local = vec![u32::MAX; mesh.vertices.len()];
        let surfaces = by_pair
            .into_iter()
            .map(|(pair, tris)| PairSurface::new(mesh, pair, &tris, &mut local))
            .collect();
        CurvatureSampler { radius, surfaces }
    }

    /// κ = κ1 + κ2 (sum of principal curvatures) of the interface between phases `inside` and
    /// `outside` nearest to `x` (None when no triangle of that pair lies within
    /// `max_distance`), signed so that a region of `inside` that is convex there has κ > 0: a
    /// ball of `inside` of radius R gives 2/R; a cylinder of radius R (e.g. a disc in a
    /// slab/2D scene, extruded along z) gives 1/R; seen from `outside` (arguments swapped) the
    /// sign flips. Also `None` when fewer than six vertices of the pair lie within the
    /// radius of the foot point, when they do not determine a quadratic (all on one line),
    /// or when the mesh holds non-finite positions there.
    pub fn at(
        &self,
        x: DVec3,
        inside: PhaseId,
        outside: PhaseId,
        max_distance: f64,
    ) -> Option<f64> {
        if inside == outside || max_distance.is_nan() || max_distance < 0.0 {
            return None;
        }
        let pair = (inside.min(outside), inside.max(outside));
        let index = self.surfaces.binary_search_by_key(&pair, |s| s.pair).ok()?;
        let surface = &self.surfaces[index];
        let foot = surface.query.query_within(x, max_distance)?.point;
        let seed = surface.query.nearest_triangle(x)?;
        // The surface's normals point out of `lo`.
        let sign = if inside == pair.0 { 1.0 } else { -1.0 };
        surface
            .mean_curvature(foot, seed, self.radius)
            .filter(|k| k.is_finite())
            .map(|k| sign * k)
    }
}

impl PairSurface {
    /// The surface of the source triangles `tris` (all between the phases of `pair`);
    /// `local` maps source to local vertex indices, all `u32::MAX` on entry and on return.
    fn new(
        source: &LabeledMesh,
        pair: (PhaseId, PhaseId),
        tris: &[usize],
        local: &mut [u32],
    ) -> PairSurface {
        let mut mesh = LabeledMesh::default();
        for &t in tris {
            let [a, b, c] = source.triangles[t];
            // Reversing a triangle flips its normal towards the other phase.
            let oriented = if source.labels[t][0] == pair.1 {
                [a, b, c]
            } else {
                [a, c, b]
            };
            let tri = oriented.map(|v| {
                let slot = &mut local[v as usize];
                if *slot == u32::MAX {
                    *slot = mesh.vertices.len() as u32;
                    mesh.vertices.push(source.vertices[v as usize]);
                }
                *slot
            });
            mesh.triangles.push(tri);
            mesh.labels.push([pair.1, pair.0]);
        }
        for &t in tris {
            for v in source.triangles[t] {
                local[v as usize] = u32::MAX;
            }
        }
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, a), (b, c), (c, b), (c, a), (a, c)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let mut first = vec![0u32; mesh.vertices.len() + 1];
        for &(a, _) in &edges {
            first[a as usize + 1] += 1;
        }
        for v in 0..mesh.vertices.len() {
            first[v + 1] += first[v];
        }
        let neighbours = edges.iter().map(|&(_, b)| b).collect();
        let mut area_normals = vec![DVec3::ZERO; mesh.vertices.len()];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let n = mesh.area_normal(t);
            for &v in tri {
                area_normals[v as usize] += n;
            }
        }
        let query = MeshQuery::new(&mesh, pair.0);
        PairSurface {
            pair,
            mesh,
            query,
            first,
            neighbours,
            area_normals,
        }
    }

    /// Vertices sharing an edge with vertex `v`.
    fn neighbours_of(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.neighbours[self.first[v] as usize..self.first[v + 1] as usize]
    }

    /// κ (convex towards the normals' side positive) at the point `foot` of triangle `seed`,
    /// fitted over the vertices within `radius` connected to `seed`, in the frame of their
    /// area normals weighted like the fit.
    fn mean_curvature(&self, foot: DVec3, seed: usize, radius: f64) -> Option<f64> {
        let vertices = self.neighbourhood(foot, seed, radius);
        if vertices.len() < MIN_POINTS {
            return None;
        }
        let points: Vec<DVec3> = vertices
            .iter()
            .map(|&v| self.mesh.vertices[v as usize])
            .collect();
        let normal = vertices
            .iter()
            .zip(&points)
            .map(|(&v, &p)| weight(p - foot, radius) * self.area_normals[v as usize])
            .sum::<DVec3>()
            .try_normalize()
            .or_else(|| self.mesh.area_normal(seed).try_normalize())?;
        HeightFit::new(&points, foot, normal, radius).map(|fit| fit.curvature())
    }

    /// The vertices within `radius` of `foot` connected to a corner of triangle `seed` through
    /// edges between such vertices. Following connectivity rather than taking everything
    /// within the radius keeps other sheets of the same pair (a thin film's far side, a drop
    /// about to touch) out of the fit.
    fn neighbourhood(&self, foot: DVec3, seed: usize, radius: f64) -> Vec<u32> {
        let r2 = radius * radius;
        let within = |v: u32| (self.mesh.vertices[v as usize] - foot).length_squared() <= r2;
        // Every vertex looked at, within the radius or not, so that none is looked at twice.
        let mut seen = Vec::new();
        let mut found = Vec::new();
        for v in self.mesh.triangles[seed] {
            if insert(&mut seen, v) && within(v) {
                found.push(v);
            }
        }
        let mut next = 0;
        while let Some(&v) = found.get(next) {
            next += 1;
            for &u in self.neighbours_of(v) {
                if insert(&mut seen, u) && within(u) {
                    found.push(u);
                }
            }
        }
        found
    }
}

/// Inserts `x` into the ascending `set`; false if it was there. A neighbourhood holds a few
/// hundred entries, where this beats hashing.
fn insert(set: &mut Vec<u32>, x: u32) -> bool {
    match set.binary_search(&x) {
        Ok(_) => false,
        Err(i) => {
            set.insert(i, x);
            true
        }
    }
}

/// Fit weight of a point at offset `d` from the foot point: smooth, 1 at the foot, 0 from
/// `radius` on, so that points entering or leaving the neighbourhood change the fit little.
fn weight(d: DVec3, radius: f64) -> f64 {
    let s = 1.0 - d.length_squared() / (radius * radius);
    if s > 0.0 {
        s * s
    } else {
        0.0
    }
}

/// A fitted height function over the tangent plane at a foot point.
struct HeightFit {
    /// `[a, b, c, d, e, f]` of `h = a u² + b uv + c v² + d u + e v + f`, in units of the
    /// radius (u, v, h all divided by it, which keeps the normal equations well scaled).
    coef: [f64; 6],
    radius: f64,
}

impl HeightFit {
    /// Weighted least-squares fit to `points` in the frame of unit `normal` at `foot`; `None`
    /// when the points do not determine the six coefficients.
    fn new(points: &[DVec3], foot: DVec3, normal: DVec3, radius: f64) -> Option<HeightFit> {
        let (t1, t2) = normal.any_orthonormal_pair();
        let mut ata = [[0.0; 6]; 6];
        let mut atb = [0.0; 6];
        for &p in points {
            let d = p - foot;
            let w = weight(d, radius);
            let (u, v, h) = (
                d.dot(t1) / radius,
                d.dot(t2) / radius,
                d.dot(normal) / radius,
            );
            let row = [u * u, u * v, v * v, u, v, 1.0];
            for i in 0..6 {
                for j in 0..6 {
                    ata[i][j] += w * row[i] * row[j];
                }
                atb[i] += w * row[i] * h;
            }
        }
        let coef = solve6(ata, atb)?;
        Some(HeightFit { coef, radius })
    }

    /// `−∇·(∇h / √(1 + |∇h|²))` at u = v = 0: positive where the surface bends away from the
    /// normal (convex on the side it points out of).
    fn curvature(&self) -> f64 {
        let [a, b, c, d, e, _] = self.coef;
        let g2 = 1.0 + d * d + e * e;
        -((1.0 + e * e) * 2.0 * a - 2.0 * d * e * b + (1.0 + d * d) * 2.0 * c)
            / (g2 * g2.sqrt() * self.radius)
    }
}

/// Solves the symmetric 6×6 system `m x = b` by Gaussian elimination with partial pivoting;
/// `None` when a pivot falls below 1e-12 of the largest diagonal entry (rank deficient).
fn solve6(mut m: [[f64; 6]; 6], mut b: [f64; 6]) -> Option<[f64; 6]> {
    let scale = (0..6).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for k in 0..6 {
        let p = (k..6)
            .max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))
            .unwrap_or(k);
        let pivot = m[p][k].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        m.swap(k, p);
        b.swap(k, p);
        let pivot_row = m[k];
        for i in k + 1..6 {
            let f = m[i][k] / pivot_row[k];
            for (x, y) in m[i][k..].iter_mut().zip(&pivot_row[k..]) {
                *x -= f * y;
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; 6];
    for k in (0..6).rev() {
        let s: f64 = (k + 1..6).map(|j| m[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / m[k][k];
    }
    Some(x)
}

#[cfg(test)]
mod tests;
