//! Pressure jumps at interfaces (the ghost-fluid jump condition, Liu, Fedkiw & Kang 2000):
//! across a face whose two cells hold different phases, the pressure may jump by J where the
//! interface crosses the face. Surface tension's Laplace jump σκ is one (ARCHITECTURE.md
//! "Surface tension"); the solver does not know where J comes from, only where it acts.
//!
//! With the interface at fraction θ of the face's segment from the lower cell a, pressure
//! continuous on each side up to J, and the normal flux continuous, the two half-segments act
//! in series as for the face density (`phase.rs`):
//! flux = (p_b − p_a − J) / (h·(θ ρ_a + (1−θ) ρ_b)), J = p_b − p_a at the interface. So the
//! projection's matrix is unchanged and J enters the right-hand side and the face update.

use crate::layout::{idx, unidx, Layout};
use crate::phase::crossing_fraction;
use glam::DVec3;
use polyphase_grid::{PhaseField, PhaseId};

/// A face of the solver grid that an interface crosses: its two cells hold different phases.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InterfaceFace {
    /// The face's axis (the velocity component it carries).
    pub axis: usize,
    /// Index of the face in that component's array.
    pub face: usize,
    /// Phase of the cell below (lower coordinate along `axis`).
    pub below: PhaseId,
    /// Phase of the cell above.
    pub above: PhaseId,
    /// Where the interface crosses the segment between the two cell centres (θ of the
    /// ghost-fluid face density, from φ).
    pub crossing: DVec3,
}

/// Jumps J = p_above − p_below (Pa) at interface faces; faces not listed have none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PressureJumps {
    /// (axis, face index, J).
    pub(crate) faces: Vec<(usize, usize, f64)>,
}

impl PressureJumps {
    /// The jump `j` (Pa, p_above − p_below) at each of `faces`.
    pub fn new(faces: impl IntoIterator<Item = (InterfaceFace, f64)>) -> PressureJumps {
        PressureJumps {
            faces: faces
                .into_iter()
                .filter(|(_, j)| *j != 0.0)
                .map(|(f, j)| (f.axis, f.face, j))
                .collect(),
        }
    }

    /// Per component, J on every face (0 where none), for the projection.
    pub(crate) fn dense(&self, layout: &Layout) -> [Vec<f64>; 3] {
        let mut out = [0, 1, 2].map(|a| {
            let d = layout.face_dims(a);
            vec![0.0; d[0] * d[1] * d[2]]
        });
        for &(a, f, j) in &self.faces {
            if let Some(v) = out[a].get_mut(f) {
                *v = j;
            }
        }
        out
    }
}

/// Every face between two cells of different phases of `field` (checked against the grid
/// already), in component then index order.
pub(crate) fn interface_faces(field: &PhaseField, layout: &Layout) -> Vec<InterfaceFace> {
    let (origin, h) = (field.grid.origin, field.grid.h);
    let centre =
        |p: [usize; 3]| origin + (DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) + 0.5) * h;
    let mut out = Vec::new();
    for axis in 0..3 {
        let fd = layout.face_dims(axis);
        for face in 0..fd[0] * fd[1] * fd[2] {
            let p = unidx(fd, face);
            let (Some(lo), Some(hi)) = (
                layout.cell_below(axis, p[axis]),
                layout.cell_above_node(axis, p[axis]),
            ) else {
                continue;
            };
            let (mut pl, mut ph) = (p, p);
            pl[axis] = lo;
            ph[axis] = hi;
            let (a, b) = (idx(layout.n, pl), idx(layout.n, ph));
            if field.chi[a] == field.chi[b] {
                continue;
            }
            // One h up from the centre below (unwrapped across a periodic seam).
            let mut step = DVec3::ZERO;
            step[axis] = h;
            out.push(InterfaceFace {
                axis,
                face,
                below: field.chi[a],
                above: field.chi[b],
                crossing: centre(pl) + crossing_fraction(field.phi[a], field.phi[b]) * step,
            });
        }
    }
    out
}
