//! The grids polyphase writes per frame, from its own data: φ and χ of a [`PhaseField`],
//! and velocity sampled from any [`VelocityField`] at the cell centres.

use super::VdbGrid;
use crate::{GridSpec, PhaseField, VelocityField, OUTSIDE};

/// Grids "phi" (unsigned distance to the nearest interface) and "chi" (phase id as a
/// float) of `field`. φ's background is the domain diagonal, the value a [`PhaseField`]
/// holds where there is no interface; χ's is [`OUTSIDE`], the pseudo-phase beyond the
/// domain boundary.
pub fn phase_field_grids(field: &PhaseField) -> [VdbGrid; 2] {
    let diagonal = field.grid.diagonal() as f32;
    let phi = field.phi.iter().map(|&d| d as f32).collect();
    let chi = field.chi.iter().map(|&c| f32::from(c)).collect();
    [
        VdbGrid::scalar("phi", phi, diagonal),
        VdbGrid::scalar("chi", chi, f32::from(OUTSIDE)),
    ]
}

/// Grid "v": the velocity of `field` at time `t` at the cell centres of `grid`,
/// with background zero (cells at rest are inactive).
pub fn velocity_grid(grid: &GridSpec, field: &dyn VelocityField, t: f64) -> VdbGrid {
    let [nx, ny, nz] = grid.dims;
    let values = (0..nz)
        .flat_map(|k| (0..ny).flat_map(move |j| (0..nx).map(move |i| (i, j, k))))
        .map(|(i, j, k)| {
            field
                .velocity(grid.cell_center(i, j, k), t)
                .as_vec3()
                .to_array()
        })
        .collect();
    VdbGrid::vector("v", values, [0.0; 3])
}
