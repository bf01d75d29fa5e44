//! The staggered MAC velocity grid: u, v, w on the faces normal to x, y, z; pressure lives at
//! the cell centres (in the projection). Interpolated, it is a [`VelocityField`].

use crate::config::Interpolation;
use crate::interp;
use crate::layout::{idx, Layout};
use glam::DVec3;
use polyphase_grid::{rk4_departure, GridSpec, VelocityField};
use rayon::prelude::*;

/// Face velocities of a box of cells.
#[derive(Clone, Debug)]
pub struct MacGrid {
    pub(crate) spec: GridSpec,
    pub(crate) layout: Layout,
    pub(crate) interpolation: Interpolation,
    pub(crate) comps: [Vec<f64>; 3],
}

impl MacGrid {
    pub(crate) fn zeros(spec: GridSpec, layout: Layout, interpolation: Interpolation) -> Self {
        let comps = [0, 1, 2].map(|a| {
            let d = layout.face_dims(a);
            vec![0.0; d[0] * d[1] * d[2]]
        });
        Self {
            spec,
            layout,
            interpolation,
            comps,
        }
    }

    /// The cells.
    pub fn spec(&self) -> &GridSpec {
        &self.spec
    }

    /// Sample counts of component `a` (0 = u, 1 = v, 2 = w): n+1 faces along `a` between walls,
    /// n when the axis is periodic.
    pub fn face_dims(&self, a: usize) -> [usize; 3] {
        self.layout.face_dims(a)
    }

    /// Samples of component `a`, x fastest.
    pub fn component(&self, a: usize) -> &[f64] {
        &self.comps[a]
    }

    /// Mutable samples of component `a` (initial conditions); wall and solid faces are
    /// reset to zero by the next step.
    pub fn component_mut(&mut self, a: usize) -> &mut [f64] {
        &mut self.comps[a]
    }

    /// Position of face `p` of component `a`.
    pub fn face_position(&self, a: usize, p: [usize; 3]) -> DVec3 {
        let mut q = DVec3::new(p[0] as f64 + 0.5, p[1] as f64 + 0.5, p[2] as f64 + 0.5);
        q[a] -= 0.5;
        self.spec.origin + q * self.spec.h
    }

    /// Sets every face's normal component from a velocity field at time `t`.
    pub fn set_from(&mut self, field: &dyn VelocityField, t: f64) {
        for a in 0..3 {
            let dims = self.layout.face_dims(a);
            let values: Vec<f64> = (0..self.comps[a].len())
                .into_par_iter()
                .map(|f| {
                    let p = crate::layout::unidx(dims, f);
                    field.velocity(self.face_position(a, p), t)[a]
                })
                .collect();
            self.comps[a] = values;
        }
    }

    /// Interpolated component `a` at `x`.
    pub fn sample_component(&self, a: usize, x: DVec3) -> f64 {
        interp::sample(
            &self.spec,
            &self.layout,
            &self.comps[a],
            a,
            x,
            self.interpolation,
        )
    }

    /// Interpolated velocity at `x`.
    pub fn sample(&self, x: DVec3) -> DVec3 {
        if self.interpolation == Interpolation::Trilinear {
            let [u, v, w] = &self.comps;
            return interp::trilinear_velocity(&self.spec, &self.layout, [u, v, w], x);
        }
        DVec3::new(
            self.sample_component(0, x),
            self.sample_component(1, x),
            self.sample_component(2, x),
        )
    }

    /// Largest |component| over all faces.
    pub fn max_abs(&self) -> f64 {
        self.comps
            .iter()
            .map(|c| crate::linalg::vecops::max_abs(c))
            .fold(0.0, f64::max)
    }

    /// Value of face `p` of component `a`.
    pub fn get(&self, a: usize, p: [usize; 3]) -> f64 {
        self.comps[a][idx(self.layout.face_dims(a), p)]
    }
}

impl VelocityField for MacGrid {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        self.sample(x)
    }

    /// RK4 backwards, then wrapped into the box along periodic axes: upstream of a periodic
    /// channel's inlet lies its outlet, and trackers read their meshes inside the box only.
    fn departure(&self, x: DVec3, t: f64, dt: f64) -> DVec3 {
        let mut p = rk4_departure(self, x, t, dt);
        for a in (0..3).filter(|&a| self.layout.periodic[a]) {
            let (lo, len) = (self.spec.origin[a], self.spec.dims[a] as f64 * self.spec.h);
            p[a] = lo + (p[a] - lo).rem_euclid(len);
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn departures_wrap_into_the_box_along_periodic_axes_only() {
        let spec = GridSpec {
            origin: DVec3::new(1.0, 0.0, 0.0),
            h: 0.25,
            dims: [4, 4, 4],
        };
        let layout = Layout {
            n: spec.dims,
            periodic: [true, false, false],
        };
        let mut m = MacGrid::zeros(spec, layout, Interpolation::Trilinear);
        m.comps[0].fill(1.0);
        m.comps[1].fill(0.5);
        // 0.3 s back at (1, 0.5) from x = 1.1: x = 0.8 wraps to 1.8 in the box [1, 2]; y is
        // walled and goes where the trace goes, 0.15 down.
        let p = m.departure(DVec3::new(1.1, 0.5, 0.5), 0.0, 0.3);
        assert!((p - DVec3::new(1.8, 0.35, 0.5)).length() < 1e-12, "{p}");
    }
}
