//! A divergence-free interpolant of a MAC velocity: wherever every cell's discrete divergence
//! is zero, so is the interpolated field's, at every point. A closed surface moved in it keeps
//! its volume up to the errors of its own discretisation. Componentwise trilinear (or cubic)
//! interpolation of the same field has sources of order h·|∇²u| between the samples, which a
//! front-tracked liquid integrates into a volume drift (measured on `balls` at 64 to
//! t = 1/3 s: the four balls still falling drifted by up to 0.43 % with trilinear sampling and
//! by at most 0.12 % with this one).
//!
//! Component a is interpolated along its own axis by Catmull–Rom (cubic, C¹) through its face
//! samples, S, and across the other two axes by H, the derivative of the Catmull–Rom
//! interpolant of its running sum over the cells (a quadratic that keeps every cell's mean).
//! Since d/dx S(f) = H(Δf) for any samples f, the divergence of the interpolant is
//! H⊗H⊗H applied to the cells' discrete divergences (the commuting diagram of tensor-product
//! splines): zero where they are. Along a wall the outermost cell's value is repeated
//! (the running sum extrapolated linearly); along a periodic axis the samples wrap.

use crate::layout::Layout;
use glam::DVec3;
use polyphase_grid::GridSpec;

/// Catmull–Rom weights of samples −1, 0, 1, 2 at fraction `t`, and their derivatives in `t`.
#[inline]
fn catmull_rom(t: f64) -> ([f64; 4], [f64; 4]) {
    let (t2, t3) = (t * t, t * t * t);
    (
        [
            0.5 * (-t + 2.0 * t2 - t3),
            0.5 * (2.0 - 5.0 * t2 + 3.0 * t3),
            0.5 * (t + 4.0 * t2 - 3.0 * t3),
            0.5 * (-t2 + t3),
        ],
        [
            0.5 * (-1.0 + 4.0 * t - 3.0 * t2),
            0.5 * (-10.0 * t + 9.0 * t2),
            0.5 * (1.0 + 8.0 * t - 9.0 * t2),
            0.5 * (-2.0 * t + 3.0 * t2),
        ],
    )
}

/// Base sample and fraction at lattice coordinate `g` over `m` samples: wrapped when
/// periodic, else clamped to the samples (the interpolant holds its end value beyond them).
#[inline]
fn base_and_fraction(g: f64, m: usize, periodic: bool) -> (isize, f64) {
    if periodic {
        let b = g.floor();
        (b as isize, g - b)
    } else {
        let gc = g.clamp(0.0, (m - 1) as f64);
        let b = gc.floor().min((m - 2) as f64);
        (b as isize, gc - b)
    }
}

/// Taps of one axis: sample indices and weights (unused taps weigh zero).
type Taps = ([usize; 4], [f64; 4]);

/// S: Catmull–Rom through `m` samples at lattice coordinate `g`; off a periodic axis the
/// neighbour missing beyond an end sample is extrapolated linearly, f(−1) = 2 f(0) − f(1),
/// and folded into the weights.
#[inline]
fn node_taps(g: f64, m: usize, periodic: bool) -> Taps {
    if m < 2 {
        return ([0; 4], [1.0, 0.0, 0.0, 0.0]);
    }
    let (base, t) = base_and_fraction(g, m, periodic);
    let (mut w, _) = catmull_rom(t);
    if periodic {
        let at = |d: isize| (base + d).rem_euclid(m as isize) as usize;
        return ([at(-1), at(0), at(1), at(2)], w);
    }
    let b = base as usize;
    let mut idx = [b, b, b + 1, b + 1];
    if b == 0 {
        (w[1], w[2], w[0]) = (w[1] + 2.0 * w[0], w[2] - w[0], 0.0);
    } else {
        idx[0] = b - 1;
    }
    if b + 2 == m {
        (w[2], w[1], w[3]) = (w[2] + 2.0 * w[3], w[1] - w[3], 0.0);
    } else {
        idx[3] = b + 2;
    }
    (idx, w)
}

/// H: the derivative of S over the running sum of `n` cell values, at coordinate `s` on the
/// lattice of the cells' faces. With F(j + 1) − F(j) = cell j, Σ F(b − 1 + m)·S′ₘ weighs cells
/// b − 1, b, b + 1 by −S′₀, S′₂ + S′₃, S′₃ (the S′ sum to zero). The wall extrapolation of F
/// repeats the end cell; periodic cells wrap.
#[inline]
fn cell_taps(s: f64, n: usize, periodic: bool) -> Taps {
    let nodes = n + usize::from(!periodic);
    if nodes < 2 {
        return ([0; 4], [1.0, 0.0, 0.0, 0.0]);
    }
    let (base, t) = base_and_fraction(s, nodes, periodic);
    let (_, dw) = catmull_rom(t);
    let cell = |d: isize| match periodic {
        true => (base + d).rem_euclid(n as isize) as usize,
        false => (base + d).clamp(0, n as isize - 1) as usize,
    };
    (
        [cell(-1), cell(0), cell(1), cell(1)],
        [-dw[0], dw[2] + dw[3], dw[3], 0.0],
    )
}

/// Value of component `a` (samples `data`, x fastest) at `x`.
pub(crate) fn sample(spec: &GridSpec, layout: &Layout, data: &[f64], a: usize, x: DVec3) -> f64 {
    let dims = layout.face_dims(a);
    let q = (x - spec.origin) / spec.h;
    let taps = [0, 1, 2].map(|d| match d == a {
        true => node_taps(q[d], dims[d], layout.periodic[d]),
        false => cell_taps(q[d], dims[d], layout.periodic[d]),
    });
    let mut s = 0.0;
    for (&k, &wk) in taps[2].0.iter().zip(&taps[2].1) {
        for (&j, &wj) in taps[1].0.iter().zip(&taps[1].1) {
            let row = dims[0] * (j + dims[1] * k);
            let line: f64 = (taps[0].0.iter().zip(&taps[0].1))
                .map(|(&i, &wi)| wi * data[row + i])
                .sum();
            s += wj * wk * line;
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Interpolation;
    use crate::layout::{idx, unidx};
    use crate::mac::MacGrid;
    use polyphase_grid::VelocityField;
    use std::f64::consts::PI;

    /// A smooth vector potential on the unit cube, periodic along every axis, whose
    /// tangential components vanish on the walls of the non-periodic axes, so its curl has no
    /// flux through them.
    fn potential(x: DVec3, periodic: [bool; 3]) -> DVec3 {
        let mut out = DVec3::new(
            (2.0 * PI * x.y).sin() * (1.0 + 0.5 * (2.0 * PI * x.z).cos()),
            (2.0 * PI * x.z).cos() + (PI * x.x).sin().powi(2),
            (2.0 * PI * (x.x + x.y)).sin(),
        );
        for d in 0..3 {
            for e in (0..3).filter(|&e| e != d && !periodic[e]) {
                out[d] *= (PI * x[e]).sin();
            }
        }
        out
    }

    /// The field on `n`³ cells whose face fluxes are the circulations of [`potential`]
    /// sampled at the edges' midpoints: discretely divergence-free to rounding.
    fn field(n: usize, periodic: [bool; 3], interpolation: Interpolation) -> MacGrid {
        let h = 1.0 / n as f64;
        let spec = GridSpec {
            origin: DVec3::ZERO,
            h,
            dims: [n; 3],
        };
        let layout = Layout {
            n: [n; 3],
            periodic,
        };
        let mut m = MacGrid::zeros(spec, layout, interpolation);
        let psi = |p: DVec3| potential(p, periodic);
        for a in 0..3 {
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let dims = layout.face_dims(a);
            for f in 0..m.comps[a].len() {
                let x = m.face_position(a, unidx(dims, f));
                let (eb, ec) = (DVec3::AXES[b] * 0.5 * h, DVec3::AXES[c] * 0.5 * h);
                m.comps[a][f] =
                    (psi(x + eb)[c] - psi(x - eb)[c] - psi(x + ec)[b] + psi(x - ec)[b]) / h;
            }
        }
        m
    }

    /// The curl of [`potential`], by central differences far finer than any grid here.
    fn exact(x: DVec3, periodic: [bool; 3]) -> DVec3 {
        let e = 1e-5;
        let d = |axis: usize, comp: usize| {
            let s = DVec3::AXES[axis] * e;
            (potential(x + s, periodic)[comp] - potential(x - s, periodic)[comp]) / (2.0 * e)
        };
        DVec3::new(d(1, 2) - d(2, 1), d(2, 0) - d(0, 2), d(0, 1) - d(1, 0))
    }

    /// Points of the unit cube from a Weyl sequence (deterministic, evenly spread).
    fn points(count: usize) -> impl Iterator<Item = DVec3> {
        let g = [0.754_877_666_2, 0.569_840_290_9, 0.430_159_709_0];
        (1..=count).map(move |i| DVec3::from_array(g.map(|a| (i as f64 * a).fract())))
    }

    /// Central-difference divergence of `v` at `x` with step `e`.
    fn divergence(v: &MacGrid, x: DVec3, e: f64) -> f64 {
        (0..3)
            .map(|a| {
                let s = DVec3::AXES[a] * e;
                (v.velocity(x + s, 0.0)[a] - v.velocity(x - s, 0.0)[a]) / (2.0 * e)
            })
            .sum()
    }

    /// Whether `x` lies within `e` of a plane where the pieces of either interpolant meet
    /// (the faces' planes and the cell centres' planes): a difference across one measures a
    /// kink, not a divergence.
    fn near_a_seam(x: DVec3, h: f64, e: f64) -> bool {
        (0..3).any(|d| {
            let g = 2.0 * x[d] / h;
            (g - g.round()).abs() * 0.5 * h < 2.0 * e
        })
    }

    #[test]
    fn a_divergence_free_mac_field_interpolates_without_sources_anywhere() {
        for periodic in [[false; 3], [true, false, true], [true; 3]] {
            let n = 12;
            let h = 1.0 / n as f64;
            let exact = field(n, periodic, Interpolation::DivergenceFree);
            let trilinear = field(n, periodic, Interpolation::Trilinear);
            let scale = exact.max_abs() / h;
            let e = 1e-4 * h;
            let (mut worst, mut worst_trilinear) = (0.0f64, 0.0f64);
            for x in points(4000).filter(|&x| !near_a_seam(x, h, e)) {
                worst = worst.max(divergence(&exact, x, e).abs() / scale);
                worst_trilinear = worst_trilinear.max(divergence(&trilinear, x, e).abs() / scale);
            }
            // Between seams the interpolant is a polynomial, so the difference is exact to
            // its O(e²) truncation and rounding (|u| / e · 1e-16 = 1e-12 |u| / h; measured
            // up to 1.3e-9): a real source would show at the trilinear one's scale (measured
            // 0.16).
            assert!(worst < 1e-8, "{periodic:?}: divergence {worst:.1e} |u| / h");
            assert!(
                worst_trilinear > 1e-2,
                "{periodic:?}: {worst_trilinear:.1e}"
            );
        }
    }

    #[test]
    fn a_smooth_flow_is_reproduced_to_second_order() {
        let periodic = [false, true, false];
        // Away from the walls, where both interpolants hold the end samples' values.
        let inner = |x: &DVec3| x.min_element() > 0.2 && x.max_element() < 0.8;
        let error = |n: usize, interpolation| {
            let v = field(n, periodic, interpolation);
            points(2000)
                .filter(inner)
                .map(|x| (v.velocity(x, 0.0) - exact(x, periodic)).length())
                .fold(0.0f64, f64::max)
        };
        let (coarse, fine) = (
            error(16, Interpolation::DivergenceFree),
            error(32, Interpolation::DivergenceFree),
        );
        // Second order: the error falls about 4× when h halves (measured 0.48 → 0.11).
        assert!(coarse / fine > 3.5, "{coarse:.3e} → {fine:.3e}");
        // And no worse than trilinear's at the same cells (measured 0.14).
        let trilinear = error(32, Interpolation::Trilinear);
        assert!(
            fine <= trilinear,
            "{fine:.3e} against trilinear {trilinear:.3e}"
        );
    }

    #[test]
    fn a_rigid_rotation_is_exact_off_the_walls() {
        let n = 10;
        let spec = GridSpec {
            origin: DVec3::new(-0.5, -0.5, 0.0),
            h: 0.1,
            dims: [n; 3],
        };
        let layout = Layout {
            n: [n; 3],
            periodic: [false; 3],
        };
        let mut mac = MacGrid::zeros(spec, layout, Interpolation::DivergenceFree);
        let rotation = |x: DVec3| DVec3::new(-x.y, x.x, 0.0);
        for a in 0..2 {
            let dims = layout.face_dims(a);
            for f in 0..mac.comps[a].len() {
                mac.comps[a][f] = rotation(mac.face_position(a, unidx(dims, f)))[a];
            }
        }
        // S reproduces quadratics and H linear cell data: exact wherever the stencils stay
        // off the walls' extrapolation (two cells in).
        for x in points(500).map(|p| spec.origin + DVec3::splat(0.2) + 0.6 * p) {
            let err = (mac.velocity(x, 0.0) - rotation(x)).length();
            assert!(err < 1e-12, "{x}: {err:.1e}");
        }
        // A face's own sample is returned at the face (S interpolates, H of a linear field
        // is exact).
        let f = idx(layout.face_dims(0), [3, 4, 5]);
        let at = mac.face_position(0, [3, 4, 5]);
        assert!((mac.velocity(at, 0.0).x - mac.comps[0][f]).abs() < 1e-12);
    }
}
