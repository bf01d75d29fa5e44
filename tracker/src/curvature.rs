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
    /// The axis a 2D scene's slab is extruded along, if any (see [`Self::extruded_along`]).
    extrusion: Option<usize>,
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
        CurvatureSampler {
            radius,
            extrusion: None,
            surfaces,
        }
    }

    /// The same sampler for a 2D scene run as a slab extruded along `axis` (0–2): κ is the
    /// curvature of the section's curve, fitted as `h = a u² + d u + f` over every vertex
    /// within `radius` of the foot point in the section's plane. A slab is two cells thick, so
    /// a surface fit there sees a band of ±1 cell across: the fitted curvature along the
    /// extrusion, zero in truth, was the largest part of the noise that drove a static drop's
    /// spurious currents (`validation/laplace2`).
    pub fn extruded_along(mut self, axis: usize) -> CurvatureSampler {
        self.extrusion = (axis < 3).then_some(axis);
        self
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
            .mean_curvature(foot, seed, self.radius, self.extrusion)
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
    /// area normals weighted like the fit; with an `extrusion` axis, offsets and normals lose
    /// their component along it and the fit is the section's curve.
    fn mean_curvature(
        &self,
        foot: DVec3,
        seed: usize,
        radius: f64,
        extrusion: Option<usize>,
    ) -> Option<f64> {
        let flat = |mut d: DVec3| {
            if let Some(axis) = extrusion {
                d[axis] = 0.0;
            }
            d
        };
        let vertices = self.neighbourhood(foot, seed, radius, flat);
        if vertices.len() < MIN_POINTS {
            return None;
        }
        let offsets: Vec<DVec3> = vertices
            .iter()
            .map(|&v| flat(self.mesh.vertices[v as usize] - foot))
            .collect();
        let normal = vertices
            .iter()
            .zip(&offsets)
            .map(|(&v, &d)| weight(d, radius) * flat(self.area_normals[v as usize]))
            .sum::<DVec3>()
            .try_normalize()
            .or_else(|| flat(self.mesh.area_normal(seed)).try_normalize())?;
        match extrusion {
            Some(axis) => {
                let tangent = DVec3::AXES[axis].cross(normal);
                HeightFit::<3>::new(&offsets, radius, |d| {
                    let (u, h) = (d.dot(tangent), d.dot(normal));
                    ([u * u, u, 1.0], h)
                })
                .map(|fit| fit.curve_curvature())
            }
            None => {
                let (t1, t2) = normal.any_orthonormal_pair();
                HeightFit::<6>::new(&offsets, radius, |d| {
                    let (u, v, h) = (d.dot(t1), d.dot(t2), d.dot(normal));
                    ([u * u, u * v, v * v, u, v, 1.0], h)
                })
                .map(|fit| fit.surface_curvature())
            }
        }
    }

    /// The vertices whose offset from `foot`, as `flat` makes it, is within `radius`,
    /// connected to a corner of triangle `seed` through edges between such vertices.
    /// Following connectivity rather than taking everything within the radius keeps other
    /// sheets of the same pair (a thin film's far side, a drop about to touch) out of the fit.
    fn neighbourhood(
        &self,
        foot: DVec3,
        seed: usize,
        radius: f64,
        flat: impl Fn(DVec3) -> DVec3,
    ) -> Vec<u32> {
        let r2 = radius * radius;
        let within = |v: u32| flat(self.mesh.vertices[v as usize] - foot).length_squared() <= r2;
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

/// A height function fitted over the tangent plane (or the tangent line of a section) at a
/// foot point: `N` coefficients of the basis the caller gives.
struct HeightFit<const N: usize> {
    /// The coefficients, in units of the radius (u, v, h all divided by it, which keeps the
    /// normal equations well scaled).
    coef: [f64; N],
    radius: f64,
}

impl<const N: usize> HeightFit<N> {
    /// Weighted least-squares fit over `offsets` from the foot point; `basis` maps an offset
    /// (divided by the radius) to the basis functions' values there and the height. `None`
    /// when the points do not determine the coefficients.
    fn new(
        offsets: &[DVec3],
        radius: f64,
        basis: impl Fn(DVec3) -> ([f64; N], f64),
    ) -> Option<HeightFit<N>> {
        let mut ata = [[0.0; N]; N];
        let mut atb = [0.0; N];
        for &d in offsets {
            let w = weight(d, radius);
            let (row, h) = basis(d / radius);
            for i in 0..N {
                for j in 0..N {
                    ata[i][j] += w * row[i] * row[j];
                }
                atb[i] += w * row[i] * h;
            }
        }
        let coef = solve(ata, atb)?;
        Some(HeightFit { coef, radius })
    }
}

impl HeightFit<6> {
    /// `−∇·(∇h / √(1 + |∇h|²))` at u = v = 0 of `h = a u² + b uv + c v² + d u + e v + f`:
    /// positive where the surface bends away from the normal (convex on the side it points
    /// out of).
    fn surface_curvature(&self) -> f64 {
        let [a, b, c, d, e, _] = self.coef;
        let g2 = 1.0 + d * d + e * e;
        -((1.0 + e * e) * 2.0 * a - 2.0 * d * e * b + (1.0 + d * d) * 2.0 * c)
            / (g2 * g2.sqrt() * self.radius)
    }
}

impl HeightFit<3> {
    /// `−h'' / (1 + h'²)^{3/2}` at u = 0 of the curve `h = a u² + d u + f`, signed as
    /// [`HeightFit::surface_curvature`].
    fn curve_curvature(&self) -> f64 {
        let [a, d, _] = self.coef;
        let g2 = 1.0 + d * d;
        -2.0 * a / (g2 * g2.sqrt() * self.radius)
    }
}

/// Solves the symmetric system `m x = b` by Gaussian elimination with partial pivoting;
/// `None` when a pivot falls below 1e-12 of the largest diagonal entry (rank deficient).
fn solve<const N: usize>(mut m: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    let scale = (0..N).map(|i| m[i][i].abs()).fold(0.0, f64::max);
    for k in 0..N {
        let p = (k..N)
            .max_by(|&i, &j| m[i][k].abs().total_cmp(&m[j][k].abs()))
            .unwrap_or(k);
        let pivot = m[p][k].abs();
        if pivot.is_nan() || pivot <= 1e-12 * scale {
            return None;
        }
        m.swap(k, p);
        b.swap(k, p);
        let pivot_row = m[k];
        for i in k + 1..N {
            let f = m[i][k] / pivot_row[k];
            for (x, y) in m[i][k..].iter_mut().zip(&pivot_row[k..]) {
                *x -= f * y;
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; N];
    for k in (0..N).rev() {
        let s: f64 = (k + 1..N).map(|j| m[k][j] * x[j]).sum();
        x[k] = (b[k] - s) / m[k][k];
    }
    Some(x)
}

#[cfg(test)]
mod tests;
