//! Interpolation of one staggered velocity component (or, trilinear, all three at once) at an
//! arbitrary point: trilinear, or a tensor product of 1D monotone cubic Hermite interpolants
//! (Fritsch–Carlson slope limiting), which never leaves the range of the samples it uses.
//! Clamped at walls, wrapped when periodic.

use crate::config::Interpolation;
use crate::layout::{idx, Layout};
use glam::DVec3;
use polyphase_grid::GridSpec;

/// Sample index along one axis: wrapped when periodic, clamped otherwise.
#[inline]
fn axis_index(i: isize, m: usize, periodic: bool) -> usize {
    if periodic {
        i.rem_euclid(m as isize) as usize
    } else {
        i.clamp(0, m as isize - 1) as usize
    }
}

/// Base index and fraction along one axis for grid coordinate `g` over `m` samples.
#[inline]
fn axis_coord(g: f64, m: usize, periodic: bool) -> (isize, f64) {
    if periodic {
        let i0 = g.floor();
        (i0 as isize, g - i0)
    } else if m < 2 {
        (0, 0.0)
    } else {
        let gc = g.clamp(0.0, (m - 1) as f64);
        let i0 = gc.floor().min((m - 2) as f64);
        (i0 as isize, gc - i0)
    }
}

/// Monotone cubic Hermite through f[1]..f[2] at fraction t, slopes from neighbours, limited.
#[inline]
fn mono_cubic(f: [f64; 4], t: f64) -> f64 {
    let delta = f[2] - f[1];
    let mut d0 = 0.5 * (f[2] - f[0]);
    let mut d1 = 0.5 * (f[3] - f[1]);
    if delta == 0.0 {
        d0 = 0.0;
        d1 = 0.0;
    } else {
        if d0 * delta <= 0.0 {
            d0 = 0.0;
        }
        if d1 * delta <= 0.0 {
            d1 = 0.0;
        }
        let (a, b) = (d0 / delta, d1 / delta);
        let s = a * a + b * b;
        if s > 9.0 {
            let tau = 3.0 / s.sqrt();
            d0 *= tau;
            d1 *= tau;
        }
    }
    let t2 = t * t;
    let t3 = t2 * t;
    f[1] * (2.0 * t3 - 3.0 * t2 + 1.0)
        + d0 * (t3 - 2.0 * t2 + t)
        + f[2] * (3.0 * t2 - 2.0 * t3)
        + d1 * (t3 - t2)
}

/// Grid coordinates of `x` in the sample lattice of component `a`, plus the sample counts.
#[inline]
fn lattice(spec: &GridSpec, layout: &Layout, a: usize, x: DVec3) -> ([f64; 3], [usize; 3]) {
    let dims = layout.face_dims(a);
    let q = (x - spec.origin) / spec.h;
    let mut g = [q.x, q.y, q.z];
    for (d, gd) in g.iter_mut().enumerate() {
        if d != a {
            *gd -= 0.5;
        }
    }
    (g, dims)
}

/// Value of component `a` (samples `data`) at `x`.
pub(crate) fn sample(
    spec: &GridSpec,
    layout: &Layout,
    data: &[f64],
    a: usize,
    x: DVec3,
    scheme: Interpolation,
) -> f64 {
    match scheme {
        Interpolation::Trilinear => trilinear(spec, layout, data, a, x),
        Interpolation::MonotoneCubic => monotone_cubic(spec, layout, data, a, x),
        Interpolation::DivergenceFree => crate::div_free::sample(spec, layout, data, a, x),
    }
}

/// Tensor-product monotone cubic value of component `a` at `x` (4³ samples).
fn monotone_cubic(spec: &GridSpec, layout: &Layout, data: &[f64], a: usize, x: DVec3) -> f64 {
    let (g, dims) = lattice(spec, layout, a, x);
    let mut base = [0isize; 3];
    let mut frac = [0.0; 3];
    for d in 0..3 {
        (base[d], frac[d]) = axis_coord(g[d], dims[d], layout.periodic[d]);
    }
    // The stencil reaches one sample below the base and two above.
    let inside = (0..3).all(|d| base[d] >= 1 && base[d] + 2 < dims[d] as isize);
    let (s1, s2) = (dims[0] as isize, (dims[0] * dims[1]) as isize);
    let origin = base[0] + s1 * base[1] + s2 * base[2];
    let at = |di: isize, dj: isize, dk: isize| {
        if inside {
            // No wrap or clamp anywhere in the stencil: plain strided access.
            return data[(origin + di + s1 * dj + s2 * dk) as usize];
        }
        let p = [
            axis_index(base[0] + di, dims[0], layout.periodic[0]),
            axis_index(base[1] + dj, dims[1], layout.periodic[1]),
            axis_index(base[2] + dk, dims[2], layout.periodic[2]),
        ];
        data[idx(dims, p)]
    };
    let mut planes = [0.0; 4];
    for (kk, plane) in planes.iter_mut().enumerate() {
        let mut lines = [0.0; 4];
        for (jj, line) in lines.iter_mut().enumerate() {
            let dj = jj as isize - 1;
            let dk = kk as isize - 1;
            let f = [at(-1, dj, dk), at(0, dj, dk), at(1, dj, dk), at(2, dj, dk)];
            *line = mono_cubic(f, frac[0]);
        }
        *plane = mono_cubic(lines, frac[1]);
    }
    mono_cubic(planes, frac[2])
}

/// The two samples around lattice coordinate `g` along one axis of `m` samples (wrapped when
/// periodic, clamped otherwise) and the weight of the upper one: the general path's
/// arithmetic in its order (so the same bits). Off a periodic axis the clamped coordinate is
/// non-negative, so truncation is its floor (`floor` is a library call on baseline x86-64,
/// and interpolation is most of a coupled step's backtraces).
#[inline]
fn axis_pair(g: f64, m: usize, periodic: bool) -> ([usize; 2], f64) {
    if periodic {
        let i0 = g.floor();
        let i = i0 as isize;
        ([axis_index(i, m, true), axis_index(i + 1, m, true)], g - i0)
    } else if m < 2 {
        ([0, 0], 0.0)
    } else {
        let gc = g.clamp(0.0, (m - 1) as f64);
        let i0 = (gc as usize).min(m - 2);
        ([i0, i0 + 1], gc - i0 as f64)
    }
}

/// Σ wᵢ wⱼ wₖ · sample over the eight samples of `axes` (per axis: indices and upper weight)
/// in an array of `dims`. Plain loops: `array::map` here is not inlined and costs more than
/// the interpolation.
#[inline(always)]
fn weighted_sum(data: &[f64], dims: [usize; 3], axes: &[([usize; 2], f64); 3]) -> f64 {
    let strides = [1, dims[0], dims[0] * dims[1]];
    let mut offsets = [[0usize; 2]; 3];
    let mut frac = [0.0; 3];
    for d in 0..3 {
        offsets[d] = [axes[d].0[0] * strides[d], axes[d].0[1] * strides[d]];
        frac[d] = axes[d].1;
    }
    let mut s = 0.0;
    for dk in 0..2 {
        let wk = if dk == 0 { 1.0 - frac[2] } else { frac[2] };
        for dj in 0..2 {
            let wj = if dj == 0 { 1.0 - frac[1] } else { frac[1] };
            let row = offsets[2][dk] + offsets[1][dj];
            for di in 0..2 {
                let wi = if di == 0 { 1.0 - frac[0] } else { frac[0] };
                s += wi * wj * wk * data[row + offsets[0][di]];
            }
        }
    }
    s
}

/// Trilinear value of component `a` at `x`, with each axis's two sample offsets found once
/// instead of per read.
#[inline]
fn trilinear(spec: &GridSpec, layout: &Layout, data: &[f64], a: usize, x: DVec3) -> f64 {
    let (g, dims) = lattice(spec, layout, a, x);
    let mut axes = [([0; 2], 0.0); 3];
    for d in 0..3 {
        axes[d] = axis_pair(g[d], dims[d], layout.periodic[d]);
    }
    weighted_sum(data, dims, &axes)
}

/// Trilinear values of the three components at `x`, the same bits as three calls of
/// [`trilinear`]: along each axis a component samples either at nodes (its own axis) or at
/// cell centres (the other two), so six axis lookups serve all three instead of nine, and
/// the lattice coordinates are computed once. Backtraces spend most of their time here.
pub(crate) fn trilinear_velocity(
    spec: &GridSpec,
    layout: &Layout,
    comps: [&[f64]; 3],
    x: DVec3,
) -> DVec3 {
    let q = ((x - spec.origin) / spec.h).to_array();
    let mut node = [([0; 2], 0.0); 3];
    let mut centre = [([0; 2], 0.0); 3];
    for d in 0..3 {
        node[d] = axis_pair(q[d], layout.nodes(d), layout.periodic[d]);
        centre[d] = axis_pair(q[d] - 0.5, layout.n[d], layout.periodic[d]);
    }
    let mut v = [0.0; 3];
    for a in 0..3 {
        let mut axes = centre;
        axes[a] = node[a];
        v[a] = weighted_sum(comps[a], layout.face_dims(a), &axes);
    }
    DVec3::from_array(v)
}

/// Minimum and maximum of the eight trilinear samples of component `a` around `x`: the
/// range a MacCormack-corrected value must stay in.
pub(crate) fn stencil_range(
    spec: &GridSpec,
    layout: &Layout,
    data: &[f64],
    a: usize,
    x: DVec3,
) -> (f64, f64) {
    let (g, dims) = lattice(spec, layout, a, x);
    let mut base = [0isize; 3];
    for d in 0..3 {
        base[d] = axis_coord(g[d], dims[d], layout.periodic[d]).0;
    }
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for dk in 0..2 {
        for dj in 0..2 {
            for di in 0..2 {
                let p = [
                    axis_index(base[0] + di, dims[0], layout.periodic[0]),
                    axis_index(base[1] + dj, dims[1], layout.periodic[1]),
                    axis_index(base[2] + dk, dims[2], layout.periodic[2]),
                ];
                let v = data[idx(dims, p)];
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trilinear interpolation reproduces linear data exactly (to rounding, 1e-12 here) inside
    /// the samples, holds the end samples beyond a wall, and blends the last and first samples
    /// across a periodic wrap.
    #[test]
    fn trilinear_is_exact_for_linear_data_clamps_at_walls_and_wraps() {
        let spec = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0,
            dims: [4, 3, 2],
        };
        let layout = Layout {
            n: spec.dims,
            periodic: [true, false, false],
        };
        // Component v: samples at x = i + ½, y = j, z = k + ½.
        let dims = layout.face_dims(1);
        assert_eq!(dims, [4, 4, 2]);
        let data: Vec<f64> = (0..dims[0] * dims[1] * dims[2])
            .map(|f| {
                let [i, j, k] = crate::layout::unidx(dims, f);
                i as f64 + 10.0 * j as f64 + 100.0 * k as f64
            })
            .collect();
        let v = |x: f64, y: f64, z: f64| {
            sample(
                &spec,
                &layout,
                &data,
                1,
                DVec3::new(x, y, z),
                Interpolation::Trilinear,
            )
        };
        // Inside: (1.25, 1.25, 0.4) in sample coordinates.
        assert!((v(1.75, 1.25, 0.9) - 53.75).abs() < 1e-12);
        // x = 0.25 lies between the last sample (i = 3, weight ¼) and the first (¾).
        assert!((v(0.25, 1.0, 0.5) - (0.75 + 10.0)).abs() < 1e-12);
        // Below the floor and above the top z sample: the end samples.
        assert!((v(1.5, -0.5, 1.9) - (1.0 + 100.0)).abs() < 1e-12);
    }

    /// The three-component path shares each axis's lookups between components and must give
    /// each component's value to the bit, inside, outside and across a periodic wrap, and on
    /// an axis of a single cell.
    #[test]
    fn velocity_at_once_matches_each_component_to_the_bit() {
        let spec = GridSpec {
            origin: DVec3::new(-0.3, 0.1, 2.0),
            h: 0.7,
            dims: [5, 3, 1],
        };
        for periodic in [[true, false, false], [false, true, true], [false; 3]] {
            let layout = Layout {
                n: spec.dims,
                periodic,
            };
            let comps: Vec<Vec<f64>> = (0..3)
                .map(|a| {
                    let [i, j, k] = layout.face_dims(a);
                    (0..i * j * k)
                        .map(|f| ((f * 37 + a * 11) % 23) as f64 / 7.0 - 1.3)
                        .collect()
                })
                .collect();
            let comps = [&comps[0][..], &comps[1][..], &comps[2][..]];
            for s in 0..500 {
                // Points from 1.5 cells below the box to 1.5 above, on a fixed scramble.
                let u = |m: usize| ((s * m + 17) % 101) as f64 / 100.0;
                let x = spec.origin
                    + DVec3::new(
                        (u(13) * 8.0 - 1.5) * spec.h,
                        (u(29) * 6.0 - 1.5) * spec.h,
                        (u(53) * 4.0 - 1.5) * spec.h,
                    );
                let all = trilinear_velocity(&spec, &layout, comps, x);
                for a in 0..3 {
                    let one = sample(&spec, &layout, comps[a], a, x, Interpolation::Trilinear);
                    assert_eq!(all[a].to_bits(), one.to_bits(), "{periodic:?} {x} comp {a}");
                }
            }
        }
    }
}
