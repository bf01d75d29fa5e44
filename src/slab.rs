//! The 2D picture of a slab scene's frame (issue 18): φ, χ, the velocity and, in coupled runs,
//! the pressure on one layer of cells through the slab, written by `slab_exr` and `slab_png`
//! as `frames/NNNN.exr` and `frames/NNNN.png`, so 2D figures need no renderer.

use anyhow::Result;
use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseField, VelocityField};
use polyphase_scenes::Scene;
use polyphase_tracker::InterfaceTracker;

use crate::output::RunFolder;
use crate::{slab_exr, slab_png};

/// One frame of a slab scene on a layer of cells (`field.grid.dims[2] == 1`), in cell order
/// (x fastest, y upwards).
pub struct SlabFrame {
    /// φ (m) and χ at the layer's cell centres; `field.grid.origin` is the layer's lower corner.
    pub field: PhaseField,
    /// In-plane velocity (x, y) at each cell centre (m/s).
    pub velocity: Vec<[f32; 2]>,
    /// Pressure at each cell centre (Pa); `None` for passive runs, which have no solver.
    pub pressure: Option<Vec<f32>>,
}

/// The layer of cells of the slab grid `grid` whose centres lie on the slab's mid-plane.
pub fn mid_plane(grid: &GridSpec) -> GridSpec {
    let z_mid = grid.origin.z + 0.5 * grid.dims[2] as f64 * grid.h;
    GridSpec {
        origin: DVec3::new(grid.origin.x, grid.origin.y, z_mid - 0.5 * grid.h),
        h: grid.h,
        dims: [grid.dims[0], grid.dims[1], 1],
    }
}

impl SlabFrame {
    /// A passive run's frame: the tracker read on the mid-plane of the tracker grid `grid`
    /// (there is no solver grid), and the scene's prescribed velocity at time `t` there.
    pub fn passive(
        tracker: &impl InterfaceTracker,
        grid: &GridSpec,
        velocity: &impl VelocityField,
        t: f64,
    ) -> SlabFrame {
        let plane = mid_plane(grid);
        let [nx, ny, _] = plane.dims;
        let velocity = (0..nx * ny)
            .map(|c| {
                let v = velocity.velocity(plane.cell_center(c % nx, c / nx, 0), t);
                [v.x as f32, v.y as f32]
            })
            .collect();
        SlabFrame {
            field: tracker.sample(&plane),
            velocity,
            pressure: None,
        }
    }

    /// A coupled run's frame: the first layer of cells of the solver's `field`, its per-cell
    /// `velocity` and `pressure`. A coupled slab is one solver cell thick, so this layer is the
    /// mid-plane, unless `[solver] resolution` equals the tracker's: then it is the lower of
    /// the two layers.
    pub fn coupled(field: &PhaseField, velocity: &[DVec3], pressure: &[f64]) -> SlabFrame {
        let [nx, ny, _] = field.grid.dims;
        let n = nx * ny;
        SlabFrame {
            field: PhaseField {
                grid: GridSpec {
                    dims: [nx, ny, 1],
                    ..field.grid
                },
                phi: field.phi[..n].to_vec(),
                chi: field.chi[..n].to_vec(),
            },
            velocity: velocity[..n]
                .iter()
                .map(|v| [v.x as f32, v.y as f32])
                .collect(),
            pressure: Some(pressure[..n].iter().map(|&p| p as f32).collect()),
        }
    }
}

/// Writes frame `n` (at `time`) of `scene` into `folder`: `frame` as `frames/NNNN.exr`, and the
/// phases of `picture` (a layer of cells) in their scene colours as `frames/NNNN.png`.
pub fn write_images(
    folder: &RunFolder,
    n: usize,
    scene: &Scene,
    time: f64,
    frame: &SlabFrame,
    picture: &PhaseField,
) -> Result<()> {
    let exr = slab_exr::encode(frame, &scene.phase_names(), time)?;
    let colors: Vec<[f64; 3]> = scene.file.phases.iter().map(|p| p.color).collect();
    let [nx, ny, _] = picture.grid.dims;
    let png = slab_png::encode(nx, ny, &picture.chi, &colors)?;
    folder.write_slab_images(n, &exr, &png)
}
