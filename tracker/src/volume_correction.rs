//! Per-phase volume correction: a small offset of the interfaces along their normals that gives
//! every phase back the volume it is meant to hold.
//!
//! Paper 004 has no such step: each semi-Lagrangian resampling loses a little of the thin parts
//! (paper 004 §7.3 reports the loss on the Enright test), and coupled liquids lose a few percent
//! over a splash. Liquids must keep their volume, so each step the tracker offsets the previous
//! mesh's interfaces while it reads φ, χ off them at the departure points (a level-set offset
//! of the signed distance, so the new mesh is contoured clean; moving the mesh's vertices
//! instead folds the slivers contouring leaves). The offsets come from one "pressure" `p` per
//! phase: the interface between phases `a` and `b` moves by `p_a − p_b` towards `b`, so phase
//! `a` changes by `Σ_b A_ab (p_a − p_b)`, a weighted graph Laplacian of the phase adjacency with
//! the background phase held at `p = 0` (it absorbs the change; in a closed box it is the
//! complement of the others).
//!
//! The offset is applied to the previous mesh, and the step's resampling then loses again what
//! it loses (a shattered ball ~10 % per step), so aiming at the target would end each step one
//! loss short. Two controls close that gap: the loss of each step beyond what its offset aimed
//! for is carried into the next step's aim (feed-forward, [`carried_loss`]), and a step whose
//! mesh still misses a target by more than [`MISS_TOLERANCE`] (a sudden splash) is contoured
//! again with the aim moved by the miss ([`reaim`], at most [`MAX_RETRIES`] times).

use polyphase_grid::{PhaseId, OUTSIDE};

use crate::mesh::LabeledMesh;

/// The interface offsets that bring each phase of a mesh to its target volume.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeShift {
    pressures: Vec<f64>,
    cap: f64,
    /// Per phase, the volume the capped offsets give it to first order; `None` for a phase the
    /// correction leaves alone.
    aimed: Vec<Option<f64>>,
}

impl VolumeShift {
    /// Offsets for `mesh` towards `targets[phase]`. The background phase is not corrected (it
    /// takes up the difference); phases without an interface, or with a target of zero, are
    /// left alone; no interface moves more than `cap`, so a large loss is given back over
    /// several steps.
    pub fn new(mesh: &LabeledMesh, targets: &[f64], background: PhaseId, cap: f64) -> Self {
        let n = targets.len();
        let volumes = mesh.phase_volumes(n);
        let areas = interface_areas(mesh, n);
        let corrected: Vec<bool> = (0..n)
            .map(|i| {
                i != background as usize && targets[i] > 0.0 && areas[i].iter().sum::<f64>() > 0.0
            })
            .collect();
        let deficit: Vec<f64> = (0..n)
            .map(|i| {
                if corrected[i] {
                    targets[i] - volumes[i]
                } else {
                    0.0
                }
            })
            .collect();
        let mut shift = VolumeShift {
            pressures: solve_pressures(&areas, &deficit, &corrected),
            cap,
            aimed: Vec::new(),
        };
        shift.aimed = (0..n)
            .map(|a| {
                corrected[a].then(|| {
                    let change: f64 = (0..n)
                        .filter(|&b| b != a)
                        .map(|b| areas[a][b] * shift.shift(b as PhaseId, a as PhaseId))
                        .sum();
                    volumes[a] + change
                })
            })
            .collect();
        shift
    }

    /// The volume each phase is offset to, to first order in the offset and after the cap:
    /// the current volume plus `Σ_b A_ab · shift`. `None` for the background, for phases
    /// without an interface and for phases with a target of zero.
    pub fn aimed(&self) -> &[Option<f64>] {
        &self.aimed
    }

    /// How far the interface between `front` and `back` moves towards `front` (so `back`
    /// grows); negative moves it towards `back`.
    pub fn shift(&self, front: PhaseId, back: PhaseId) -> f64 {
        let p = |phase: PhaseId| self.pressures.get(phase as usize).copied().unwrap_or(0.0);
        (p(back) - p(front)).clamp(-self.cap, self.cap)
    }
}

/// The largest loss carried into the next step, as a fraction of the phase's target: a step
/// that tore a phase apart cannot make the next one inflate it by more (a shattered ball of the
/// built-in scenes loses up to ~14 % per step at their default resolutions).
pub const MAX_CARRIED_FRACTION: f64 = 0.2;

/// How far from its target a phase's aim may go on a step's retry, as a fraction of the target.
pub const MAX_AIM_FRACTION: f64 = 0.25;

/// A step whose mesh misses any corrected phase's target by more than this fraction of it is
/// contoured again, from the same previous mesh, with the aim moved by the miss.
pub const MISS_TOLERANCE: f64 = 0.01;

/// Retries a step may take (each costs one more build, contour and redistance).
pub const MAX_RETRIES: usize = 2;

/// The volumes a step's correction aims for: each phase's target plus the loss carried from the
/// step before ([`carried_loss`]).
pub fn first_aim(targets: &[f64], carried: &[f64]) -> Vec<f64> {
    targets
        .iter()
        .enumerate()
        .map(|(i, &t)| t + carried.get(i).copied().unwrap_or(0.0))
        .collect()
}

/// Feed-forward of the resampling loss: per phase, how much the step just taken fell short of
/// the volume its correction aimed for (`aimed − after`, see [`VolumeShift::aimed`]); the next
/// step adds it to the target so that it ends on the target rather than one step's loss short.
/// Clamped to ±[`MAX_CARRIED_FRACTION`] of the target; zero for phases the correction left
/// alone and for phases the step made vanish, so nothing is inflated from nothing.
pub fn carried_loss(aimed: &[Option<f64>], after: &[f64], targets: &[f64]) -> Vec<f64> {
    targets
        .iter()
        .enumerate()
        .map(|(i, &target)| match present(aimed, after, i) {
            Some((aim, v)) => {
                let bound = MAX_CARRIED_FRACTION * target;
                (aim - v).clamp(-bound, bound)
            }
            None => 0.0,
        })
        .collect()
}

/// Whether a phase the step corrected (and did not make vanish) ended further than
/// [`MISS_TOLERANCE`] of its target from it.
pub fn missed(aimed: &[Option<f64>], after: &[f64], targets: &[f64]) -> bool {
    targets.iter().enumerate().any(|(i, &target)| {
        present(aimed, after, i).is_some_and(|(_, v)| (v - target).abs() > MISS_TOLERANCE * target)
    })
}

/// Moves the aim of every phase the step corrected by what it missed its target by, for the
/// step's retry from the same mesh (the resampling loss changes little with the aim, so the
/// retry lands close to the target); the aim stays within ±[`MAX_AIM_FRACTION`] of the target.
pub fn reaim(aim: &mut [f64], aimed: &[Option<f64>], after: &[f64], targets: &[f64]) {
    for (i, (a, &target)) in aim.iter_mut().zip(targets).enumerate() {
        if let Some((_, v)) = present(aimed, after, i) {
            let bound = MAX_AIM_FRACTION * target;
            *a = (*a + target - v).clamp(target - bound, target + bound);
        }
    }
}

/// Phase `i`'s aimed and resulting volumes, if the correction moved it and it is still there.
fn present(aimed: &[Option<f64>], after: &[f64], i: usize) -> Option<(f64, f64)> {
    let aim = aimed.get(i).copied().flatten()?;
    let v = after.get(i).copied().filter(|&v| v > 0.0)?;
    Some((aim, v))
}

/// `A[a][b]`: area of the interface between phases `a` and `b` (symmetric; domain-boundary faces
/// excluded).
fn interface_areas(mesh: &LabeledMesh, n: usize) -> Vec<Vec<f64>> {
    let mut areas = vec![vec![0.0; n]; n];
    for (t, &[front, back]) in mesh.labels.iter().enumerate() {
        let (f, b) = (front as usize, back as usize);
        if front == OUTSIDE || back == OUTSIDE || f >= n || b >= n {
            continue;
        }
        let a = mesh.area(t);
        areas[f][b] += a;
        areas[b][f] += a;
    }
    areas
}

/// Solves `Σ_b A_ab (p_a − p_b) = deficit_a` for the corrected phases, `p = 0` for the others
/// (Gaussian elimination with partial pivoting; at most a few dozen phases). A corrected phase
/// cut off from every uncorrected one makes the system singular: its row then gets `p = 0`.
fn solve_pressures(areas: &[Vec<f64>], deficit: &[f64], corrected: &[bool]) -> Vec<f64> {
    let idx: Vec<usize> = (0..deficit.len()).filter(|&i| corrected[i]).collect();
    let m = idx.len();
    let mut a = vec![vec![0.0; m + 1]; m];
    for (r, &i) in idx.iter().enumerate() {
        a[r][r] = areas[i].iter().sum();
        for (c, &j) in idx.iter().enumerate() {
            if c != r {
                a[r][c] = -areas[i][j];
            }
        }
        a[r][m] = deficit[i];
    }
    let scale = a
        .iter()
        .map(|row| row[..m].iter().map(|v| v.abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    let mut solved = vec![true; m];
    for col in 0..m {
        let pivot = (col..m)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        if a[col][col].abs() <= 1e-12 * scale {
            solved[col] = false;
            continue;
        }
        let pivot_row = a[col].clone();
        for (r, row) in a.iter_mut().enumerate() {
            let f = row[col] / pivot_row[col];
            if r != col && f != 0.0 {
                for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                    *x -= f * p;
                }
            }
        }
    }
    let mut p = vec![0.0; deficit.len()];
    for (r, &i) in idx.iter().enumerate() {
        if solved[r] {
            p[i] = a[r][m] / a[r][r];
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contour_tracker::ContourTracker;
    use crate::mesh::fixtures::{icosphere, lattice_mesh};
    use crate::tracker::InterfaceTracker;
    use glam::DVec3;
    use polyphase_grid::{GridSpec, VelocityField};
    use std::f64::consts::PI;

    /// Two phases: the interface moves by exactly deficit / area (the only equation).
    #[test]
    fn two_phases_move_by_deficit_over_area() {
        let mesh = icosphere(DVec3::splat(0.5), 0.2, 3, 1, 0);
        let volume = mesh.phase_volumes(2)[1];
        let area: f64 = (0..mesh.triangle_count()).map(|t| mesh.area(t)).sum();
        let shift = VolumeShift::new(&mesh, &[0.0, volume + 1e-4], 0, 1.0);
        // The icosphere's normals point out, into phase 0 (front): phase 1 grows outwards.
        let expected = 1e-4 / area;
        assert!((shift.shift(0, 1) - expected).abs() < 1e-12 * expected.max(1.0));
        assert_eq!(shift.shift(1, 0), -shift.shift(0, 1));
        let capped = VolumeShift::new(&mesh, &[0.0, volume + 1e-4], 0, 0.1 * expected);
        assert_eq!(capped.shift(0, 1), 0.1 * expected);
    }

    /// Three phases in a box: the offsets solve the Laplacian, `Σ_b A_ab (p_a − p_b)` equals
    /// each corrected phase's deficit, and the background does not move on its own.
    #[test]
    fn offsets_solve_the_phase_laplacian() {
        let mesh = lattice_mesh(6, |i, j, _| match (i < 3, j < 3) {
            (true, true) => 1,
            (false, true) => 2,
            _ => 0,
        });
        let volumes = mesh.phase_volumes(3);
        let targets = [0.0, volumes[1] * 1.02, volumes[2] * 0.97];
        let shift = VolumeShift::new(&mesh, &targets, 0, f64::INFINITY);
        let areas = interface_areas(&mesh, 3);
        for a in 1..3u16 {
            let change: f64 = (0..3u16)
                .filter(|&b| b != a)
                .map(|b| areas[a as usize][b as usize] * shift.shift(b, a))
                .sum();
            let deficit = targets[a as usize] - volumes[a as usize];
            // Gaussian elimination on a 2×2 system: round-off only.
            assert!(
                (change - deficit).abs() < 1e-12,
                "{a}: {change} vs {deficit}"
            );
        }
    }

    /// A contouring tracker of a ball of radius 0.25 (phase 1) at the centre of a 32³ unit
    /// cube of phase 0, with its grid and the ball's centre.
    fn ball_tracker() -> (ContourTracker, GridSpec, DVec3) {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0 / 32.0,
            dims: [32, 32, 32],
        };
        let centre = DVec3::splat(0.5);
        let ball = |x: DVec3| {
            let d = (x - centre).length() - 0.25;
            (d.abs(), if d < 0.0 { 1 } else { 0 })
        };
        (ContourTracker::new(grid, &ball, 2, 0).0, grid, centre)
    }

    struct Still;
    impl VelocityField for Still {
        fn velocity(&self, _: DVec3, _: f64) -> DVec3 {
            DVec3::ZERO
        }
    }

    /// The tracker at rest with a target 6 % above its ball's volume: the ball grows to the
    /// target within a few steps, and stays a ball (every vertex near the target radius).
    #[test]
    fn tracker_grows_a_ball_to_its_target() {
        let (mut tracker, grid, centre) = ball_tracker();
        let start = tracker.phase_volumes()[1];
        let target = start * 1.06;
        tracker.set_volume_targets(Some(vec![0.0, target]));
        for s in 0..8 {
            tracker.advance(&Still, s as f64, 1.0).expect("still flow");
        }
        let v = tracker.phase_volumes()[1];
        // Each step closes the gap to the first order of the offset (h/4 cap ≫ the 1.1e-3 m
        // needed); what is left is contouring's own error at rest, ~1e-4 of the volume.
        assert!(
            ((v - target) / target).abs() < 2e-3,
            "volume {v}, target {target}"
        );
        let radius = (3.0 * target / (4.0 * PI)).cbrt();
        let mesh = tracker.mesh();
        let interface = (0..mesh.triangle_count()).filter(|&t| !mesh.labels[t].contains(&OUTSIDE));
        for x in interface.flat_map(|t| mesh.corners(t)) {
            let r = (x - centre).length();
            // Contouring a ball puts vertices within a small fraction of h of the sphere.
            assert!(
                (r - radius).abs() < 0.1 * grid.h,
                "vertex at r = {r}, want {radius}"
            );
        }
    }

    /// Uniform contraction towards `centre`: a region's volume shrinks by `e^{−3k·dt}` over a
    /// step, the same fraction every step (a resampling loss of known, fixed size).
    struct Shrink {
        centre: DVec3,
        k: f64,
    }
    impl VelocityField for Shrink {
        fn velocity(&self, x: DVec3, _: f64) -> DVec3 {
            -self.k * (x - self.centre)
        }
    }

    /// Each step of a contracting flow takes 4.9 % of the ball. Correcting to the target before
    /// the step alone would end every step one loss short (at 95.1 %); with the loss carried
    /// forward, and the first step (nothing carried yet) retried, every step ends on the target.
    #[test]
    fn a_fixed_loss_per_step_is_given_back_within_the_step() {
        let (mut tracker, _, centre) = ball_tracker();
        let target = tracker.volume_targets().expect("on by default")[1];
        let (dt, k): (f64, f64) = (1.0, 0.05 / 3.0);
        let loss = 1.0 - (-3.0 * k * dt).exp();
        let flow = Shrink { centre, k };
        for s in 0..5 {
            tracker.advance(&flow, s as f64, dt).expect("smooth flow");
            let v = tracker.phase_volumes()[1];
            // Contouring a ball of 8 cells' radius is exact to ~1e-4 of its volume and the
            // contraction loses the same fraction each step, so the carried loss (or, on the
            // first step, the retry) lands within a tenth of one step's loss of the target.
            assert!(
                (v - target).abs() < 0.1 * loss * target,
                "step {s}: volume {v}, target {target}, one loss {}",
                loss * target
            );
            let carried = tracker.carried_loss()[1] / target;
            // The step lost `loss` of what it aimed for, and it aimed about `loss` above the
            // target: the carried loss is `loss` of that aim, to a tenth.
            assert!(
                (carried - loss).abs() < 0.1 * loss,
                "step {s}: carried {carried}, loss {loss}"
            );
        }
    }

    /// The carried loss is clamped, zero for uncorrected or vanished phases; the retry's aim
    /// moves by the miss.
    #[test]
    fn carried_loss_and_reaim_rules() {
        let targets = [1.0, 1.0, 1.0, 1.0];
        let aimed = [Some(1.05), None, Some(1.0), Some(1.1)];
        let after = [0.95, 0.5, 0.0, 0.6];
        let carried = carried_loss(&aimed, &after, &targets);
        assert!((carried[0] - 0.1).abs() < 1e-15);
        assert_eq!(carried[1], 0.0, "uncorrected phase");
        assert_eq!(carried[2], 0.0, "vanished phase");
        assert_eq!(carried[3], MAX_CARRIED_FRACTION, "clamped");
        assert!(missed(&aimed, &after, &targets));
        assert!(!missed(&aimed, &[1.005, 0.5, 0.0, 0.995], &targets));
        let mut aim = first_aim(&targets, &[0.05, 0.0, 0.0, 0.1]);
        reaim(&mut aim, &aimed, &after, &targets);
        assert!((aim[0] - 1.1).abs() < 1e-15, "moved by the 5 % miss");
        assert_eq!(aim[1], 1.0, "uncorrected phase keeps its aim");
        assert_eq!(aim[3], 1.0 + MAX_AIM_FRACTION, "clamped");
    }
}
