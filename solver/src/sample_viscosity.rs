//! Sharp viscosity at the stress samples of `viscosity.rs`: each sample's viscosity is a mean
//! of the phase viscosities weighted by the phases' fractions of the sample's control volume,
//! so a viscosity jump sits where φ puts the interface, not on the grid (control-volume
//! fractions as in Batty & Bridson 2008, "Accurate viscous free surfaces for buckling,
//! coiling, and rotating liquids", there for the liquid–air fraction).
//!
//! Fractions: phase k's signed distance at a cell centre is ψ_k = −φ where χ = k, +φ elsewhere
//! (exact for two phases; for more, +φ is the distance to the nearest interface, a lower bound
//! of the distance to k). A sample's ψ_k is that of its cell (cell samples) or the mean over the
//! two to four cells around it (edge samples: their centres are the corners of the edge's
//! control volume, so the mean is ψ at its centre when ψ is linear). The fraction is the 1D
//! fraction along the normal of a linear ψ across a control volume of width h,
//! θ_k = clamp(½ − ψ_k/h, 0, 1): exact for an axis-aligned plane, an estimate for oblique ones.
//! Only phases among the sample's cells (and, for a cell, its six face neighbours) count, and
//! the fractions are normalised to sum 1 (they already do for two phases).
//!
//! Means, for incompressible flow across a plane interface of normal n:
//! - cell centres carry the normal stresses τ_aa = 2μ ε_aa. Every ε_aa is continuous across
//!   the interface (the tangential ones because the velocity is, the normal one because it is
//!   minus their sum), so the stress averaged over the volume is 2 ε_aa Σ θ_k μ_k: the
//!   **arithmetic** mean.
//! - edges carry the shear γ_ab. With n in the (a, b) plane (layers sheared across, as in
//!   Couette and Poiseuille flow) the traction τ_ab is continuous and γ_ab jumps, so the
//!   velocity difference across the control volume is τ h Σ θ_k/μ_k: the **harmonic** mean,
//!   which makes two-layer Couette flow exact to round-off wherever the interface lies (solver
//!   test `two_layer_couette_flow_is_exact_with_the_interface_between_nodes`). With n along
//!   the edge both derivatives are tangential and the arithmetic mean would be exact; the
//!   harmonic one underestimates there, within one control volume of the interface.
//!
//! Cost: at extreme ratios the arithmetic cell mean leaves cells whose weight is far above
//! that of their edges, which the multigrid preconditioner handles poorly (`polyphase bench
//! solver`, a 1000:1 ball with μ 50 against 1.8e-5: at 64³, 51 multigrid-PCG iterations
//! against 10 with each cell's own μ and 12 with a harmonic cell mean); MIC(0) is not slowed
//! (13 against 16).
//!
//! Edges on a no-slip wall have a half control volume (wall to the first centres); their ψ is
//! still the mean of their two cells, so the fraction there is only approximate for an
//! interface within half a cell of the wall.

use crate::layout::{idx, par_fill, Layout};
use crate::phase::{CellMaterial, PhaseProps};
use crate::viscosity::PAIRS;
use polyphase_grid::PhaseId;

/// Most cells a sample looks at: a cell and its six face neighbours.
const MOST: usize = 7;

/// Viscosity per cell (arithmetic mean) and per edge of each family of `viscosity::PAIRS`
/// (harmonic mean), from the phases' fractions of each control volume; see the module doc.
pub(crate) struct SampleViscosity {
    /// μ per cell.
    pub cell: Vec<f64>,
    /// μ per edge of each family, laid out as `Layout::edge_dims` of the pair.
    pub edge: [Vec<f64>; 3],
}

impl SampleViscosity {
    /// Samples the viscosities of `m` on `layout` (cell size `h`), the phase table giving
    /// each phase's viscosity.
    pub fn new(m: &CellMaterial, phases: &[PhaseProps], layout: &Layout, h: f64) -> Self {
        let mut cell = vec![0.0; layout.cells()];
        par_fill(layout.n, &mut cell, |p| {
            let c = idx(layout.n, p);
            let mut cells = [c; MOST];
            let mut len = 1;
            for a in 0..3 {
                let below = layout.cell_below(a, p[a]);
                let above = (p[a] + 1 < layout.n[a] || layout.periodic[a])
                    .then(|| layout.node_above(a, p[a]));
                for q in [below, above].into_iter().flatten() {
                    let mut r = p;
                    r[a] = q;
                    cells[len] = idx(layout.n, r);
                    len += 1;
                }
            }
            let own = |k: PhaseId| signed(m, c, k);
            if let Some(t) = single_phase(&m.chi, &cells[..len], h, own) {
                // The general sum below with one term, in the same operations.
                return (t * mu(phases, m.chi[c])) / t;
            }
            let theta = fractions(&m.chi, &cells[..len], h, own);
            let (sum, weighted) = theta
                .iter()
                .fold((0.0, 0.0), |(s, w), &(k, t)| (s + t, w + t * mu(phases, k)));
            weighted / sum
        });
        let edge = PAIRS.map(|(a, b)| {
            let ed = layout.edge_dims(a, b);
            let mut w = vec![0.0; ed[0] * ed[1] * ed[2]];
            par_fill(ed, &mut w, |p| {
                let mut cells = [0; MOST];
                let mut len = 0;
                for ca in [layout.cell_below(a, p[a]), layout.cell_above_node(a, p[a])] {
                    for cb in [layout.cell_below(b, p[b]), layout.cell_above_node(b, p[b])] {
                        if let (Some(ca), Some(cb)) = (ca, cb) {
                            let mut q = p;
                            q[a] = ca;
                            q[b] = cb;
                            cells[len] = idx(layout.n, q);
                            len += 1;
                        }
                    }
                }
                if len == 0 {
                    return 0.0;
                }
                let around = &cells[..len];
                let mean =
                    |k: PhaseId| around.iter().map(|&c| signed(m, c, k)).sum::<f64>() / len as f64;
                if let Some(t) = single_phase(&m.chi, around, h, mean) {
                    let mu = mu(phases, m.chi[around[0]]);
                    return if mu <= 0.0 { 0.0 } else { t / (t / mu) };
                }
                let theta = fractions(&m.chi, around, h, mean);
                let (mut sum, mut inverse) = (0.0, 0.0);
                for &(k, t) in theta.iter().filter(|&&(_, t)| t > 0.0) {
                    let mu = mu(phases, k);
                    if mu <= 0.0 {
                        return 0.0;
                    }
                    sum += t;
                    inverse += t / mu;
                }
                sum / inverse
            });
            w
        });
        Self { cell, edge }
    }
}

/// Viscosity of phase `k` (validated by `cell_material`, so `k` is in the table).
#[inline]
fn mu(phases: &[PhaseProps], k: PhaseId) -> f64 {
    phases[usize::from(k)].viscosity
}

/// Signed distance of phase `k` at the centre of cell `c`: −φ inside k, +φ outside.
#[inline]
fn signed(m: &CellMaterial, c: usize, k: PhaseId) -> f64 {
    if m.chi[c] == k {
        -m.phi[c]
    } else {
        m.phi[c]
    }
}

/// Fraction of a control volume of width `h` held by a phase whose signed distance at its
/// centre is `psi` (see the module doc).
#[inline]
fn fraction(psi: f64, h: f64) -> f64 {
    (0.5 - psi / h).clamp(0.0, 1.0)
}

/// The fraction of the one phase of `cells` when they all hold the same one and it gets a
/// positive fraction (as [`fractions`] would give it); None otherwise. The common case away
/// from interfaces, without the general bookkeeping.
#[inline]
fn single_phase(
    chi: &[PhaseId],
    cells: &[usize],
    h: f64,
    psi: impl Fn(PhaseId) -> f64,
) -> Option<f64> {
    let k = chi[cells[0]];
    if cells.iter().any(|&c| chi[c] != k) {
        return None;
    }
    let t = fraction(psi(k), h);
    (t > 0.0).then_some(t)
}

/// (phase, fraction) of each distinct phase among `cells`, the fraction from the phase's
/// signed distance `psi` at the sample: clamp(½ − ψ/h, 0, 1). Should no phase get any (φ
/// inconsistent with χ), each gets its share of the cells instead.
fn fractions(chi: &[PhaseId], cells: &[usize], h: f64, psi: impl Fn(PhaseId) -> f64) -> Fractions {
    let mut out = Fractions {
        items: [(0, 0.0); MOST],
        len: 0,
    };
    for &c in cells {
        let k = chi[c];
        if !out.items[..out.len].iter().any(|&(q, _)| q == k) {
            out.items[out.len] = (k, fraction(psi(k), h));
            out.len += 1;
        }
    }
    if out.iter().all(|&(_, t)| t == 0.0) {
        for item in &mut out.items[..out.len] {
            item.1 = cells.iter().filter(|&&c| chi[c] == item.0).count() as f64;
        }
    }
    out
}

/// The phases of one sample with their (unnormalised) fractions; a fixed array, as this runs
/// once per cell and edge.
struct Fractions {
    items: [(PhaseId, f64); MOST],
    len: usize,
}

impl Fractions {
    /// The phases present and their fractions (some may be 0).
    fn iter(&self) -> std::slice::Iter<'_, (PhaseId, f64)> {
        self.items[..self.len].iter()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phase::cell_material;
    use glam::DVec3;
    use polyphase_grid::{GridSpec, PhaseField};

    /// Two cells stacked in y (x, z periodic, one cell each), phase 0 below the plane y = y_i
    /// and phase 1 above, with viscosities `mu`; the samples of that column.
    fn column(y_i: f64, mu: [f64; 2]) -> SampleViscosity {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0,
            dims: [1, 2, 1],
        };
        let centres = [0.5, 1.5];
        let field = PhaseField {
            grid,
            phi: centres.iter().map(|y| (y - y_i).abs()).collect(),
            chi: centres.iter().map(|&y| PhaseId::from(y > y_i)).collect(),
        };
        let phases = mu.map(|viscosity| PhaseProps {
            density: 1.0,
            viscosity,
        });
        let m = cell_material(&field, &phases).unwrap();
        let layout = Layout {
            n: [1, 2, 1],
            periodic: [true, false, true],
        };
        SampleViscosity::new(&m, &phases, &layout, 1.0)
    }

    #[test]
    fn a_plane_between_nodes_splits_cells_arithmetically_and_edges_harmonically() {
        let mu = [1.0, 10.0];
        // The plane 0.37 h above the middle node (y = 1): cell 1 (y ∈ [1, 2]) holds 0.37 of
        // phase 0, and the middle xy-edge's control segment (the centres, y ∈ [0.5, 1.5])
        // holds 0.87 of it.
        let s = column(1.37, mu);
        let arithmetic = 0.37 * mu[0] + 0.63 * mu[1];
        assert!((s.cell[1] - arithmetic).abs() < 1e-12, "{}", s.cell[1]);
        assert_eq!(s.cell[0], mu[0]);
        let harmonic = 1.0 / (0.87 / mu[0] + 0.13 / mu[1]);
        // Edge array of the (x, y) family: 1 × 3 × 1, the middle node at y = 1.
        let e = s.edge[0][1];
        assert!((e - harmonic).abs() < 1e-12, "{e} vs {harmonic}");
    }

    #[test]
    fn an_inviscid_share_makes_an_edge_stress_free_and_a_far_one_does_not() {
        // Inviscid phase 1 reaching 0.3 h below the middle node: the edge holds 0.2 of it.
        let s = column(0.7, [1.0, 0.0]);
        assert_eq!(s.edge[0][1], 0.0);
        // The plane 0.6 h above the middle node leaves that edge's segment in phase 0 alone.
        let s = column(1.6, [1.0, 0.0]);
        assert_eq!(s.edge[0][1], 1.0);
    }
}
