//! The departure sampler's bounded answers against its full ones, and φ redistanced on demand.

use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId, VelocityField};

use super::{ContourTracker, Departure};
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

/// A step redistances nothing until φ is read; the first read redistances (its time then
/// reported once, as a deferred stage) and answers, to the bit, what redistancing the step's
/// tree eagerly to its mesh gives.
#[test]
fn phi_is_redistanced_on_the_first_read_as_eagerly() {
    let grid = GridSpec {
        origin: DVec3::ZERO,
        h: 1.0 / 24.0,
        dims: [24; 3],
    };
    let (mut tracker, _) = ContourTracker::new(grid, &cut_ball, 3, 0);
    let stats = tracker.advance(&Enright, 0.0, 4.0 * grid.h).unwrap();
    assert!(stats.stages.iter().all(|(name, _)| *name != "redistance"));
    assert!(
        tracker.take_deferred_stages().is_empty(),
        "nothing read φ yet"
    );
    let mut eager = tracker.tree.clone();
    eager.redistance(&|x| tracker.query.distance(x));
    let mut rng = SplitMix64(11);
    let mut from_tree = 0;
    for _ in 0..4000 {
        let x = rng.point(grid.origin, grid.upper());
        let (phi, chi) = tracker.phi_chi(x);
        if let Some((p, c)) = eager.sample(x) {
            assert_eq!((phi.to_bits(), chi), (p.to_bits(), c), "at {x}");
            from_tree += 1;
        }
    }
    assert!(from_tree > 3000, "{from_tree} answers off the tree");
    let deferred = tracker.take_deferred_stages();
    assert!(
        matches!(deferred[..], [("redistance", s)] if s > 0.0),
        "{deferred:?}"
    );
    assert_eq!(tracker.redistance(), 0.0, "redistanced once");
    assert!(tracker.take_deferred_stages().is_empty(), "reported once");
}
