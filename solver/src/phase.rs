//! Per-phase material properties, their validation against a [`PhaseField`], and the
//! sharp (ghost-fluid) face densities of the MAC grid.
//!
//! Face density (DESIGN.md "The solver", Liu–Fedkiw–Kang ghost-fluid method): on a face whose
//! two cells a, b hold different phases, the interface crosses the face's segment at fraction
//! θ = φ_a/(φ_a+φ_b) from a (φ is the unsigned distance at the centres). With the pressure
//! continuous and the normal flux (1/ρ)∂p/∂n continuous across it, the two half-segments act
//! in series: flux = (p_b − p_a)/(h·(θ ρ_a + (1−θ) ρ_b)), so ρ_face = θ ρ_a + (1−θ) ρ_b. This is
//! exact for layered 1D states, so stratified fluids at rest stay at rest (the hydrostatic
//! pressure is then the discrete solution to round-off).

use crate::error::SolverError;
use crate::layout::{idx, unidx, Layout};
use polyphase_grid::{PhaseField, PhaseId};
use rayon::prelude::*;

/// Material properties of one phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseProps {
    /// Density (kg/m³), > 0.
    pub density: f64,
    /// Dynamic viscosity (Pa·s), ≥ 0.
    pub viscosity: f64,
}

/// Per-cell density and viscosity plus φ, after validation.
pub(crate) struct CellMaterial {
    pub rho: Vec<f64>,
    pub mu: Vec<f64>,
    pub phi: Vec<f64>,
    pub chi: Vec<PhaseId>,
}

/// Checks the phase table and field and looks the properties up per cell.
pub(crate) fn cell_material(
    field: &PhaseField,
    phases: &[PhaseProps],
) -> Result<CellMaterial, SolverError> {
    for (i, p) in phases.iter().enumerate() {
        if !(p.density.is_finite() && p.density > 0.0) {
            return Err(SolverError::InvalidPhase {
                phase: i,
                reason: format!("density {} must be positive and finite", p.density),
            });
        }
        if !(p.viscosity.is_finite() && p.viscosity >= 0.0) {
            return Err(SolverError::InvalidPhase {
                phase: i,
                reason: format!("viscosity {} must be non-negative and finite", p.viscosity),
            });
        }
    }
    let n = field.grid.cell_count();
    if field.phi.len() != n || field.chi.len() != n {
        return Err(SolverError::GridMismatch {
            expected: format!("{n} samples"),
            found: format!(
                "{} phi and {} chi samples",
                field.phi.len(),
                field.chi.len()
            ),
        });
    }
    if let Some(index) = field
        .phi
        .par_iter()
        .position_first(|v| !v.is_finite() || *v < 0.0)
    {
        return Err(SolverError::NonFinite { what: "phi", index });
    }
    if let Some(cell) = field
        .chi
        .par_iter()
        .position_first(|&c| usize::from(c) >= phases.len())
    {
        return Err(SolverError::UnknownPhase {
            phase: field.chi[cell],
            cell,
            count: phases.len(),
        });
    }
    let rho = field
        .chi
        .par_iter()
        .map(|&c| phases[usize::from(c)].density)
        .collect();
    let mu = field
        .chi
        .par_iter()
        .map(|&c| phases[usize::from(c)].viscosity)
        .collect();
    Ok(CellMaterial {
        rho,
        mu,
        phi: field.phi.clone(),
        chi: field.chi.clone(),
    })
}

/// Ghost-fluid face density between cells `a` (below) and `b` (above); see the module doc.
#[inline]
pub(crate) fn face_density(m: &CellMaterial, a: usize, b: usize) -> f64 {
    if m.chi[a] == m.chi[b] {
        return 0.5 * (m.rho[a] + m.rho[b]);
    }
    let s = m.phi[a] + m.phi[b];
    let theta = if s > 0.0 {
        (m.phi[a] / s).clamp(0.0, 1.0)
    } else {
        0.5
    };
    theta * m.rho[a] + (1.0 - theta) * m.rho[b]
}

/// Face densities of component `a`; 0 on faces without two cells (walls).
pub(crate) fn face_densities(m: &CellMaterial, layout: &Layout, a: usize) -> Vec<f64> {
    let fd = layout.face_dims(a);
    (0..fd[0] * fd[1] * fd[2])
        .into_par_iter()
        .map(|f| {
            let p = unidx(fd, f);
            match (layout.cell_below(a, p[a]), layout.cell_above_node(a, p[a])) {
                (Some(lo), Some(hi)) => {
                    let mut pl = p;
                    pl[a] = lo;
                    let mut ph = p;
                    ph[a] = hi;
                    face_density(m, idx(layout.n, pl), idx(layout.n, ph))
                }
                _ => 0.0,
            }
        })
        .collect()
}
