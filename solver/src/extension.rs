//! Which phase owns each MAC face, and one phase's velocity continued across its interfaces.
//!
//! A single velocity field is discontinuous at an interface: its normal component is
//! continuous, but the tangential ones jump (air slips past a falling drop). Interpolating
//! across the jump, as semi-Lagrangian advection and the tracker's backtrace do, hands the
//! light phase's velocity to the heavy one, and at 1000:1 that is a large momentum leak.
//! Each momentum group of phases (`phase::momentum_groups`: densities within 100×) therefore
//! gets its own field: its velocity on the faces it owns, continued outward a few faces by
//! averaging (the ghost velocity of two-velocity treatments, Rudman 1998; the velocity
//! extrapolation of free-surface solvers), so a stencil near the interface only ever reads one
//! group's motion. "Phase" below means such a group, named by its densest member.

use crate::layout::{idx, unidx, Layout};
use crate::mac::MacGrid;
use crate::phase::{face_density, CellMaterial};
use polyphase_grid::PhaseId;
use rayon::prelude::*;

/// Layer value of faces an extension did not reach.
pub(crate) const UNREACHED: u8 = u8::MAX;

/// Phase owning each face of component `a`: the phase holding most of the mass on the segment
/// between the face's two cell centres (the ghost-fluid split of [`crate::phase`]: θ·ρ_lo
/// against (1 − θ)·ρ_hi). That is the mass the projection moves with the face's velocity
/// (ρ_face = θ ρ_lo + (1 − θ) ρ_hi), so the face advects with that phase's momentum. Faces
/// with one cell (walls) take that cell's phase.
pub(crate) fn face_owners(m: &CellMaterial, layout: &Layout, a: usize) -> Vec<PhaseId> {
    let fd = layout.face_dims(a);
    (0..fd[0] * fd[1] * fd[2])
        .into_par_iter()
        .map(|f| {
            let p = unidx(fd, f);
            let cell = |i: usize| {
                let mut q = p;
                q[a] = i;
                idx(layout.n, q)
            };
            match (layout.cell_below(a, p[a]), layout.cell_above_node(a, p[a])) {
                (Some(lo), Some(hi)) => {
                    let (lo, hi) = (cell(lo), cell(hi));
                    if m.group[lo] == m.group[hi] {
                        return m.group[lo];
                    }
                    let s = m.phi[lo] + m.phi[hi];
                    let theta = if s > 0.0 {
                        (m.phi[lo] / s).clamp(0.0, 1.0)
                    } else {
                        0.5
                    };
                    if theta * m.rho[lo] >= (1.0 - theta) * m.rho[hi] {
                        m.group[lo]
                    } else {
                        m.group[hi]
                    }
                }
                (Some(lo), None) => m.group[cell(lo)],
                (None, Some(hi)) => m.group[cell(hi)],
                (None, None) => m.group[cell(0)],
            }
        })
        .collect()
}

/// Owners of all three components.
pub(crate) fn all_face_owners(m: &CellMaterial, layout: &Layout) -> [Vec<PhaseId>; 3] {
    [0, 1, 2].map(|a| face_owners(m, layout, a))
}

/// "No phase" in the seed pairs of [`seed_phases`].
pub(crate) const MIXED: PhaseId = PhaseId::MAX;

/// For each face of component `a`, the (up to two) phases whose velocity it carries,
/// interleaved as pairs: a face between two cells of one phase carries that phase's; a face
/// the interface crosses carries a phase's only where its inertia ρ_face (the ghost-fluid
/// blend of [`crate::phase`]) is at least half that phase's density. A lighter face is moved
/// by the other phase's pressure in the projection, so its value belongs to neither; a face
/// between two liquids of similar density carries both. Only these seed a phase's
/// extension. Faces at a wall carry their one cell's phase.
pub(crate) fn seed_phases(m: &CellMaterial, layout: &Layout, a: usize) -> Vec<PhaseId> {
    let fd = layout.face_dims(a);
    (0..fd[0] * fd[1] * fd[2])
        .into_par_iter()
        .flat_map_iter(|f| {
            let p = unidx(fd, f);
            let cell = |i: usize| {
                let mut q = p;
                q[a] = i;
                idx(layout.n, q)
            };
            let pair = match (layout.cell_below(a, p[a]), layout.cell_above_node(a, p[a])) {
                (Some(lo), Some(hi)) => {
                    let (lo, hi) = (cell(lo), cell(hi));
                    if m.group[lo] == m.group[hi] {
                        [m.group[lo], MIXED]
                    } else {
                        let rho = face_density(m, lo, hi);
                        let carries = |c: usize| {
                            if rho >= 0.5 * m.rho[c] {
                                m.group[c]
                            } else {
                                MIXED
                            }
                        };
                        [carries(lo), carries(hi)]
                    }
                }
                (Some(lo), None) => [m.group[cell(lo)], MIXED],
                (None, Some(hi)) => [m.group[cell(hi)], MIXED],
                (None, None) => [m.group[cell(0)], MIXED],
            };
            pair.into_iter()
        })
        .collect()
}

/// Seed pairs of all three components.
pub(crate) fn all_seed_phases(m: &CellMaterial, layout: &Layout) -> [Vec<PhaseId>; 3] {
    [0, 1, 2].map(|a| seed_phases(m, layout, a))
}

/// Whether face `f` of a seed-pair array carries `phase`.
#[inline]
pub(crate) fn carries(pairs: &[PhaseId], f: usize, phase: PhaseId) -> bool {
    pairs[2 * f] == phase || pairs[2 * f + 1] == phase
}

/// The phases named on at least one open face (owners or seed pairs), ascending.
pub(crate) fn owning_phases(owners: &[Vec<PhaseId>; 3], open: &[Vec<f64>; 3]) -> Vec<PhaseId> {
    let mut seen: Vec<PhaseId> = Vec::new();
    for (own, op) in owners.iter().zip(open) {
        let per_face = own.len() / op.len().max(1);
        for (i, &o) in own.iter().enumerate() {
            if op[i / per_face.max(1)] > 0.0 && o != MIXED && !seen.contains(&o) {
                seen.push(o);
            }
        }
    }
    seen.sort_unstable();
    seen
}

/// One phase's velocity continued across its interfaces, and how far each face is from the
/// phase: layer 0 on its own faces, k on the k-th ring outward (Chebyshev distance in faces,
/// so every face within k·h of the phase's faces is reached by layer k), [`UNREACHED`] beyond.
pub(crate) struct Extension {
    pub field: MacGrid,
    pub layer: [Vec<u8>; 3],
}

/// `vel` on the open `seed` faces (component, index), continued `layers` rings outward: each
/// new face takes the mean of its 26 neighbours already known (fixed order: deterministic).
/// Closed faces are neither read nor written; faces past the last ring keep `vel`'s values.
pub(crate) fn extend(
    vel: &MacGrid,
    open: &[Vec<f64>; 3],
    seed: &(dyn Fn(usize, usize) -> bool + Sync),
    layers: u8,
) -> Extension {
    let layers = layers.min(UNREACHED - 1);
    let mut field = vel.clone();
    let layer = [0, 1, 2].map(|a| {
        let fd = vel.layout.face_dims(a);
        let (values, layer) = extend_component(
            fd,
            vel.layout.periodic,
            &vel.comps[a],
            &open[a],
            &|f| seed(a, f),
            layers,
        );
        field.comps[a] = values;
        layer
    });
    Extension { field, layer }
}

/// The 26 neighbours of face `p` in a box of `dims`, wrapping along periodic axes.
fn neighbours(dims: [usize; 3], periodic: [bool; 3], p: [usize; 3]) -> impl Iterator<Item = usize> {
    let step = move |d: usize, o: isize| -> Option<usize> {
        let i = p[d] as isize + o;
        let n = dims[d] as isize;
        if (0..n).contains(&i) {
            Some(i as usize)
        } else if periodic[d] && n > 1 {
            Some(i.rem_euclid(n) as usize)
        } else {
            None
        }
    };
    (-1isize..=1).flat_map(move |dk| {
        (-1isize..=1).flat_map(move |dj| {
            (-1isize..=1).filter_map(move |di| {
                if di == 0 && dj == 0 && dk == 0 {
                    return None;
                }
                let q = [step(0, di)?, step(1, dj)?, step(2, dk)?];
                Some(idx(dims, q))
            })
        })
    })
}

/// `mask` grown by one face in every direction, diagonals included (the 26 neighbours of
/// [`neighbours`], wrapping the same way), as three passes along the axes instead of 26 reads
/// per face: the extension's first ring is every owned face next to an unreached one, and
/// most faces are owned.
fn dilate(dims: [usize; 3], periodic: [bool; 3], mut mask: Vec<bool>) -> Vec<bool> {
    let strides = [1, dims[0], dims[0] * dims[1]];
    for d in 0..3 {
        let n = dims[d];
        if n < 2 {
            continue;
        }
        let wrap = periodic[d];
        let grown: Vec<bool> = (0..mask.len())
            .into_par_iter()
            .map(|f| {
                let i = (f / strides[d]) % n;
                let at = |j: usize| mask[f - i * strides[d] + j * strides[d]];
                let below = if i > 0 { at(i - 1) } else { wrap && at(n - 1) };
                let above = if i + 1 < n { at(i + 1) } else { wrap && at(0) };
                mask[f] || below || above
            })
            .collect();
        mask = grown;
    }
    mask
}

/// [`extend`] for one component: ring by ring from the phase's own faces, visiting only the
/// faces next to the previous ring.
fn extend_component(
    dims: [usize; 3],
    periodic: [bool; 3],
    comp: &[f64],
    open: &[f64],
    seed: &(dyn Fn(usize) -> bool + Sync),
    layers: u8,
) -> (Vec<f64>, Vec<u8>) {
    let mut values = comp.to_vec();
    let mut layer: Vec<u8> = (0..comp.len())
        .into_par_iter()
        .map(|f| {
            if open[f] > 0.0 && seed(f) {
                0
            } else {
                UNREACHED
            }
        })
        .collect();
    let near = |f: usize| neighbours(dims, periodic, unidx(dims, f));
    let open_unreached: Vec<bool> = (0..comp.len())
        .into_par_iter()
        .map(|f| layer[f] == UNREACHED && open[f] > 0.0)
        .collect();
    let next_to_unreached = dilate(dims, periodic, open_unreached);
    let mut ring: Vec<usize> = (0..comp.len())
        .into_par_iter()
        .filter(|&f| layer[f] == 0 && next_to_unreached[f])
        .collect();
    for k in 1..=layers {
        let mut next: Vec<usize> = ring
            .par_iter()
            .flat_map_iter(|&f| near(f).filter(|&n| layer[n] == UNREACHED && open[n] > 0.0))
            .collect();
        next.par_sort_unstable();
        next.dedup();
        let averaged: Vec<f64> = next
            .par_iter()
            .map(|&f| {
                let (mut sum, mut count) = (0.0, 0u32);
                for n in near(f) {
                    if layer[n] < k {
                        sum += values[n];
                        count += 1;
                    }
                }
                sum / f64::from(count.max(1))
            })
            .collect();
        for (&f, v) in next.iter().zip(averaged) {
            values[f] = v;
            layer[f] = k;
        }
        if next.is_empty() {
            break;
        }
        ring = next;
    }
    (values, layer)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_grow_by_chebyshev_distance_and_average_known_neighbours() {
        // One owned face in the middle of a 7³ box of ones: ring k is the shell at Chebyshev
        // distance k, and every extended value is the owned value (a constant propagates).
        let dims = [7, 7, 7];
        let n = 343;
        let mut owners = vec![1; n];
        owners[idx(dims, [3, 3, 3])] = 0;
        let mut comp = vec![-1.0; n];
        comp[idx(dims, [3, 3, 3])] = 2.5;
        let seed = |f: usize| owners[f] == 0;
        let (values, layer) = extend_component(dims, [false; 3], &comp, &vec![1.0; n], &seed, 2);
        for f in 0..n {
            let p = unidx(dims, f);
            let cheb = p.iter().map(|&c| c.abs_diff(3)).max().unwrap_or(0);
            if cheb <= 2 {
                assert_eq!(layer[f], cheb as u8, "{p:?}");
                assert_eq!(values[f], 2.5, "{p:?}");
            } else {
                assert_eq!(layer[f], UNREACHED, "{p:?}");
                assert_eq!(values[f], -1.0, "{p:?}");
            }
        }
    }

    #[test]
    fn dilation_marks_exactly_the_faces_next_to_the_mask() {
        // Against the 26-neighbour definition on boxes that wrap (also across two and one
        // faces) and that do not, with a scrambled sparse mask.
        for (dims, periodic) in [
            ([5, 4, 3], [false; 3]),
            ([5, 2, 3], [true, true, false]),
            ([4, 3, 1], [false, true, true]),
        ] {
            let n = dims[0] * dims[1] * dims[2];
            let mask: Vec<bool> = (0..n).map(|f| (f * 7 + 3) % 11 == 0).collect();
            let grown = dilate(dims, periodic, mask.clone());
            for f in 0..n {
                let near = neighbours(dims, periodic, unidx(dims, f)).any(|m| mask[m]);
                assert_eq!(grown[f], mask[f] || near, "{dims:?} {periodic:?} face {f}");
            }
        }
    }

    #[test]
    fn closed_faces_are_neither_read_nor_written() {
        // On a line of three faces the closed middle one keeps its value, is never averaged
        // in, and so cuts the far face off from the owned one.
        let dims = [3, 1, 1];
        let owners = [0, 1, 1];
        let open = vec![1.0, 0.0, 1.0];
        let comp = vec![4.0, 100.0, 0.0];
        let seed = |f: usize| owners[f] == 0;
        let (values, layer) = extend_component(dims, [false; 3], &comp, &open, &seed, 3);
        assert_eq!(values, vec![4.0, 100.0, 0.0]);
        assert_eq!(layer, vec![0, UNREACHED, UNREACHED]);
    }
}
