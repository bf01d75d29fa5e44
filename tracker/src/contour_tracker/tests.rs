//! The departure sampler's bounded answers against its full ones, and φ read off the mesh.

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId, VelocityField};

use super::{ContourTracker, Departure, PHI_REACH_CELLS};
use crate::contour::PhaseSampler;
use crate::sampling::SplitMix64;
use crate::tracker::InterfaceTracker;
use crate::volume_correction::VolumeShift;

/// Enright's deformation field (time-independent here): it stretches and folds.
struct Enright;

impl VelocityField for Enright {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        let s = |a: f64| (PI * a).sin();
        let s2 = |a: f64| (2.0 * PI * a).sin();
        DVec3::new(
            2.0 * s(x.x).powi(2) * s2(x.y) * s2(x.z),
            -s2(x.x) * s(x.y).powi(2) * s2(x.z),
            -s2(x.x) * s2(x.y) * s(x.z).powi(2),
        )
    }
}

/// A ball of phase 1 cut by the plane z = 0.4 into phase 2 below, in phase 0.
fn cut_ball(x: DVec3) -> (f64, PhaseId) {
    let d = (x - DVec3::new(0.35, 0.35, 0.35)).length() - 0.15;
    let z = x.z - 0.4;
    if d >= 0.0 {
        return (d, 0);
    }
    (d.abs().min(z.abs()), if z > 0.0 { 1 } else { 2 })
}

/// Wherever the full answer's φ is below the reach, `sample_near` gives it to the bit;
/// elsewhere the same χ and a φ between the reach and the full one: the contract the tree's
/// build relies on, for the curved query and with the volume correction's shifts, through a
/// stretching flow (a step of eight cells), at reaches from half a cell to three root blocks.
#[test]
fn far_samples_keep_the_phase_and_bound_the_distance() {
    let grid = GridSpec {
        origin: DVec3::ZERO,
        h: 1.0 / 24.0,
        dims: [24; 3],
    };
    let (tracker, _) = ContourTracker::new(grid, &cut_ball, 3, 0);
    let bad = AtomicBool::new(false);
    let targets: Vec<f64> = tracker
        .component_targets()
        .iter()
        .map(|t| 1.02 * t)
        .collect();
    let shifted = VolumeShift::new(
        &tracker.mesh,
        &tracker.components,
        &targets,
        0.25 * grid.h,
        0.0,
    );
    for shift in [None, Some(shifted)] {
        let departure = Departure {
            previous: &tracker.query,
            previous_tree: &tracker.tree,
            h: grid.h,
            velocity: &Enright,
            lo: grid.origin,
            hi: grid.upper(),
            t: 0.0,
            dt: 8.0 * grid.h,
            bad: &bad,
            shift,
        };
        let mut rng = SplitMix64(7);
        let mut bounded = 0;
        for _ in 0..4000 {
            let x = rng.point(grid.origin, grid.upper());
            let (phi, chi) = departure.sample(x);
            for cells in [0.5, 3.0, 12.0, 48.0] {
                let reach = cells * grid.h;
                let (p, c) = departure.sample_near(x, reach);
                assert_eq!(c, chi, "phase at {x} (reach {cells} h)");
                if phi < reach {
                    assert_eq!(p.to_bits(), phi.to_bits(), "φ at {x} (reach {cells} h)");
                } else {
                    assert!(reach <= p && p <= phi, "φ {p} for {phi} (reach {cells} h)");
                    bounded += usize::from(p < phi);
                }
            }
        }
        assert!(bounded > 1000, "{bounded} bounded answers");
    }
    assert!(!bad.into_inner());
}

/// After a step through a stretching flow, φ is the exact distance to the new mesh wherever
/// that is within the reach (to the bit: the bounded search finds the same nearest point),
/// and at least the reach elsewhere; χ is the mesh's own phase wherever the query is exact
/// far enough from the interface that no fold or tie decides it (the tree's χ came from the
/// same mesh through the departure points, so they agree beyond a cell).
#[test]
fn phi_is_exact_within_the_reach_and_bounded_beyond() {
    let grid = GridSpec {
        origin: DVec3::ZERO,
        h: 1.0 / 24.0,
        dims: [24; 3],
    };
    let (mut tracker, _) = ContourTracker::new(grid, &cut_ball, 3, 0);
    tracker.advance(&Enright, 0.0, 4.0 * grid.h).unwrap();
    let reach = PHI_REACH_CELLS * grid.h;
    let mut rng = SplitMix64(11);
    let (mut near, mut far) = (0, 0);
    for _ in 0..4000 {
        let x = rng.point(grid.origin, grid.upper());
        let (phi, chi) = tracker.phi_chi(x);
        let exact = tracker.query.query(x);
        if exact.distance < reach {
            assert_eq!(phi.to_bits(), exact.distance.to_bits(), "φ at {x}");
            near += 1;
        } else {
            assert!(phi >= reach, "φ {phi} at {x}, beyond the reach");
            far += 1;
        }
        if exact.distance > grid.h {
            assert_eq!(chi, exact.phase, "χ at {x}");
        }
    }
    assert!(near > 500 && far > 500, "{near} near, {far} far");
}
