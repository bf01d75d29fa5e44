//! Mean-curvature flow (paper 000 §8.4): the gradient flow of the total interface area with
//! the cotangent discretisation of Meyer et al. 2002 summed over every incident triangle, so
//! it holds unchanged at non-manifold curves (a triple curve feels the pull of its three
//! sheets). Domain walls (`OUTSIDE` faces) carry no tension. Steps are backward Euler (the
//! implicit fairing of Desbrun et al. 1999, which paper 000 cites): explicit steps must stay
//! below ℓ²/8 for the shortest edge ℓ, and one sliver at a wall or junction made `mcf_t1`
//! take 533 substeps per frame.

use glam::DVec3;
use polyphase_grid::OUTSIDE;
use rayon::prelude::*;

use crate::front::connectivity::Connectivity;

/// Velocity of every vertex: −rate · ∇ₓA / Aᵥ, the area gradient over the vertex's
/// barycentric area Aᵥ (a third of its incident triangles' area). On a sphere of radius r
/// this is the mean-curvature normal 2/r pointing inward, so r² = r0² − 4·rate·t.
pub(super) fn velocities(c: &Connectivity, rate: f64) -> Vec<DVec3> {
    (0..c.mesh.vertices.len() as u32)
        .into_par_iter()
        .map(|v| {
            let x = c.position(v);
            let (mut gradient, mut area) = (DVec3::ZERO, 0.0);
            for &t in c.vertex_triangles(v) {
                if c.labels(t).contains(&OUTSIDE) {
                    continue;
                }
                let tri = c.triangle(t);
                let k = tri.iter().position(|&u| u == v).unwrap_or(0);
                let p = c.position(tri[(k + 1) % 3]);
                let q = c.position(tri[(k + 2) % 3]);
                let (g, a) = area_gradient(x, p, q);
                gradient += g;
                area += a;
            }
            if area > 0.0 {
                -rate * gradient / (area / 3.0)
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

/// Velocities of one backward-Euler step of length `h`: the positions x solve
/// (M + h·rate·K) x = M x₀, with M the barycentric vertex areas and K the cotangent stiffness
/// (whose action on x is the area gradient), each coordinate on its own (the three in
/// parallel); coordinates `fixed[v][k]` (a wall the vertex slides on) and vertices on no
/// interface keep their value. Returned as (x − x₀)/h. The solve starts from x₀ + h·`earlier`
/// when an earlier try's velocities are given (the displacement is nearly proportional to
/// the step), else from x₀.
pub(super) fn implicit_velocities(
    c: &Connectivity,
    rate: f64,
    h: f64,
    fixed: &[[bool; 3]],
    earlier: Option<&[DVec3]>,
) -> Vec<DVec3> {
    let system = System::assemble(c, h * rate);
    let x0 = &c.mesh.vertices;
    let solve = |k: usize| {
        let free: Vec<bool> = (0..x0.len())
            .map(|i| {
                system.mass[i] > 0.0
                    && system.diagonal[i] > 0.0
                    && !fixed.get(i).is_some_and(|f| f[k])
            })
            .collect();
        let start: Vec<f64> = x0.iter().map(|p| p[k]).collect();
        let guess: Vec<f64> = match earlier {
            Some(v) => (0..x0.len())
                .map(|i| start[i] + if free[i] { h * v[i][k] } else { 0.0 })
                .collect(),
            None => start.clone(),
        };
        let x = system.solve(&start, &guess, &free);
        x.iter().zip(&start).map(|(a, b)| (a - b) / h).collect()
    };
    let (dx, (dy, dz)): (Vec<f64>, (Vec<f64>, Vec<f64>)) =
        rayon::join(|| solve(0), || rayon::join(|| solve(1), || solve(2)));
    (0..x0.len())
        .map(|v| DVec3::new(dx[v], dy[v], dz[v]))
        .collect()
}

/// Relative residual at which the implicit solve stops; far below the remeshing's own
/// perturbations of the positions.
const TOLERANCE: f64 = 1e-10;

/// The matrix M + s·K of a backward-Euler step (s = step × rate), in compressed rows:
/// barycentric vertex areas, and per vertex the cotangent weights ½(cot α + cot β) to its
/// neighbours, summed over every interface triangle on the edge (non-manifold edges too).
struct System {
    mass: Vec<f64>,
    /// M + s·(row sum of K's weights): the diagonal, also the preconditioner.
    diagonal: Vec<f64>,
    /// Row `i`'s entries are `columns[rows[i]..rows[i + 1]]`, `weights[..]` the same.
    rows: Vec<usize>,
    columns: Vec<u32>,
    weights: Vec<f64>,
    /// s·K's scale.
    s: f64,
}

impl System {
    fn assemble(c: &Connectivity, s: f64) -> System {
        let n = c.mesh.vertices.len();
        let mut mass = vec![0.0; n];
        let mut stiffness: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        for (t, (&tri, labels)) in c.mesh.triangles.iter().zip(&c.mesh.labels).enumerate() {
            if !c.is_live(t as u32) || labels.contains(&OUTSIDE) {
                continue;
            }
            let p = tri.map(|v| c.position(v));
            let twice = (p[1] - p[0]).cross(p[2] - p[0]).length();
            if twice <= 0.0 {
                continue;
            }
            for k in 0..3 {
                mass[tri[k] as usize] += twice / 6.0;
                let (i, j) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let cot = (p[(k + 1) % 3] - p[k]).dot(p[(k + 2) % 3] - p[k]) / twice;
                stiffness[i as usize].push((j, 0.5 * cot));
                stiffness[j as usize].push((i, 0.5 * cot));
            }
        }
        let mut rows = Vec::with_capacity(n + 1);
        rows.push(0);
        let (mut columns, mut weights) = (Vec::new(), Vec::new());
        let mut diagonal = Vec::with_capacity(n);
        for (i, list) in stiffness.iter_mut().enumerate() {
            list.sort_by_key(|&(j, _)| j);
            list.dedup_by(|b, a| {
                if a.0 == b.0 {
                    a.1 += b.1;
                    true
                } else {
                    false
                }
            });
            diagonal.push(mass[i] + s * list.iter().map(|&(_, w)| w).sum::<f64>());
            columns.extend(list.iter().map(|&(j, _)| j));
            weights.extend(list.iter().map(|&(_, w)| w));
            rows.push(columns.len());
        }
        System {
            mass,
            diagonal,
            rows,
            columns,
            weights,
            s,
        }
    }

    /// y = (M + s·K) x on the free entries, zero elsewhere.
    fn apply(&self, x: &[f64], free: &[bool], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate() {
            *yi = if free[i] {
                let row = self.rows[i]..self.rows[i + 1];
                let k: f64 = self.columns[row.clone()]
                    .iter()
                    .zip(&self.weights[row])
                    .map(|(&j, w)| w * (x[i] - x[j as usize]))
                    .sum();
                self.mass[i] * x[i] + self.s * k
            } else {
                0.0
            };
        }
    }

    /// Solves (M + s·K) x = M x₀ on the `free` entries from x = `guess` (the others stay at
    /// x₀), by conjugate gradients with the diagonal as preconditioner, sequentially (the
    /// three coordinates run in parallel), so the result does not depend on the thread count.
    fn solve(&self, start: &[f64], guess: &[f64], free: &[bool]) -> Vec<f64> {
        let n = start.len();
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut x = guess.to_vec();
        let mut q = vec![0.0; n];
        self.apply(&x, free, &mut q);
        let b: Vec<f64> = (0..n)
            .map(|i| {
                if free[i] {
                    self.mass[i] * start[i]
                } else {
                    0.0
                }
            })
            .collect();
        let mut r: Vec<f64> = b.iter().zip(&q).map(|(b, a)| b - a).collect();
        let norm_b = dot(&b, &b).sqrt();
        let precondition = |r: &[f64], z: &mut [f64]| {
            for i in 0..n {
                z[i] = if free[i] {
                    r[i] / self.diagonal[i]
                } else {
                    0.0
                };
            }
        };
        let mut z = vec![0.0; n];
        precondition(&r, &mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        for _ in 0..n.clamp(50, 1000) {
            if dot(&r, &r).sqrt() <= TOLERANCE * norm_b {
                break;
            }
            self.apply(&p, free, &mut q);
            let pq = dot(&p, &q);
            if pq <= 0.0 {
                break;
            }
            let alpha = rz / pq;
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * q[i];
            }
            precondition(&r, &mut z);
            let rz_new = dot(&r, &z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                p[i] = z[i] + beta * p[i];
            }
        }
        x
    }
}

/// Gradient of the area of triangle (x, p, q) with respect to x, and the area: the
/// cotangent form ½[cot∠q (x − p) + cot∠p (x − q)] (Meyer et al. 2002, Eq. 4 per triangle).
fn area_gradient(x: DVec3, p: DVec3, q: DVec3) -> (DVec3, f64) {
    let cross = (p - x).cross(q - x);
    let twice = cross.length();
    if twice <= 0.0 {
        return (DVec3::ZERO, 0.0);
    }
    let cot = |at: DVec3, a: DVec3, b: DVec3| (a - at).dot(b - at) / twice;
    let cot_q = cot(q, x, p);
    let cot_p = cot(p, x, q);
    (0.5 * (cot_q * (x - p) + cot_p * (x - q)), 0.5 * twice)
}
