//! Per-phase material properties, their validation against a [`PhaseField`], and the
//! sharp (ghost-fluid) face densities of the MAC grid.
//!
//! Face density (ARCHITECTURE.md "Inside Solver::step", Liu–Fedkiw–Kang ghost-fluid method):
//! on a face whose two cells a, b hold different phases, the interface crosses the face's
//! segment at fraction θ = φ_a/(φ_a+φ_b) from a (φ is the unsigned distance at the centres).
//! With the pressure continuous and the normal flux (1/ρ)∂p/∂n continuous across it, the two
//! half-segments act in series: flux = (p_b − p_a)/(h·(θ ρ_a + (1−θ) ρ_b)), so
//! ρ_face = θ ρ_a + (1−θ) ρ_b. This is exact for layered 1D states, so stratified fluids at
//! rest stay at rest (the hydrostatic pressure is then the discrete solution to round-off).

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
    /// The cell's momentum group (see [`momentum_groups`]).
    pub group: Vec<PhaseId>,
}

/// Phases whose densities differ by less than this factor share one velocity field. Measured
/// on both sides: water and air (1000:1) need a field each (a falling ball lost its shape to
/// the momentum a shared field leaks, issue 9), while Hysing et al.'s rising bubble (10:1,
/// `validation/bubble_rise2`) came out 2–3 % off with a field each (and drifted off its axis)
/// and within 1.1 % with one shared field; 100 sits between the two measured ratios.
pub(crate) const GROUP_RATIO: f64 = 100.0;

/// Each phase's momentum group: phases sorted by density and chained while neighbours differ
/// by less than [`GROUP_RATIO`], named by the densest member. One velocity field serves a
/// group, as in a one-fluid solver: the momentum a blended stencil hands across an interface
/// is then at most that factor off, and sharing keeps the normal velocity the projection
/// leaves on faces the interface crosses (two fields extended from each side's interior
/// slowed a 3:1 Rayleigh–Taylor wave by 11 %). Phases further apart (water and air) get a
/// field each (see `extension.rs`).
pub(crate) fn momentum_groups(phases: &[PhaseProps]) -> Vec<PhaseId> {
    let mut order: Vec<usize> = (0..phases.len()).collect();
    order.sort_by(|&a, &b| {
        phases[a]
            .density
            .total_cmp(&phases[b].density)
            .then(a.cmp(&b))
    });
    let mut group = vec![0; phases.len()];
    let mut start = 0;
    for i in 1..=order.len() {
        let split = i == order.len()
            || phases[order[i]].density >= GROUP_RATIO * phases[order[i - 1]].density;
        if split {
            let name = order[i - 1] as PhaseId;
            for &p in &order[start..i] {
                group[p] = name;
            }
            start = i;
        }
    }
    group
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
    let groups = momentum_groups(phases);
    let group = field
        .chi
        .par_iter()
        .map(|&c| groups[usize::from(c)])
        .collect();
    Ok(CellMaterial {
        rho,
        mu,
        phi: field.phi.clone(),
        chi: field.chi.clone(),
        group,
    })
}

/// Where the interface crosses the segment between two cell centres of different phases, as
/// the fraction θ = φ_a/(φ_a + φ_b) of it from a (½ when both φ are 0); see the module doc.
#[inline]
pub(crate) fn crossing_fraction(phi_a: f64, phi_b: f64) -> f64 {
    let s = phi_a + phi_b;
    if s > 0.0 {
        (phi_a / s).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// Ghost-fluid face density between cells `a` (below) and `b` (above); see the module doc.
#[inline]
pub(crate) fn face_density(m: &CellMaterial, a: usize, b: usize) -> f64 {
    if m.chi[a] == m.chi[b] {
        return 0.5 * (m.rho[a] + m.rho[b]);
    }
    let theta = crossing_fraction(m.phi[a], m.phi[b]);
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
