//! Merging in the front tracker (paper 000 §6.2, §8.2) and the cyclic normal flow (Fig. 23),
//! each scene run at low resolution with the exact intersection checker and the shared
//! invariants after every step. The flows'
//! analytic references and T2 extinction are the tracker crate's `front::flow` tests; the T1
//! and T2 operations' own tests are in `front::topology`.

mod common;

use common::interface_vertices;
use common::run_checked as run;

/// Paper 000 Fig. 15: two expanding spheres of different liquids meet; the interface the
/// merge creates has speed 0, so it is a flat disk on the bisecting plane x = ½ (every vertex
/// within half an edge length of it, the bound: snapping places a vertex at the
/// midpoint of a pair at most the merge distance 0.3 L apart).
#[test]
fn merge2_makes_a_flat_interface_between_two_liquids() {
    let resolution = 16;
    let (tracker, before, after) = run("merge2", resolution, None);
    // Red, blue and the air around them; no pocket of air is left between them.
    assert_eq!((before, after), (3, 3));
    let disk = interface_vertices(tracker.mesh(), 1, 2);
    assert!(!disk.is_empty(), "no red–blue interface formed");
    let l = 1.0 / resolution as f64;
    let worst = disk.iter().map(|p| (p.x - 0.5).abs()).fold(0.0, f64::max);
    assert!(worst <= 0.5 * l, "red–blue vertex {worst} from x = ½");
}

/// Paper 000 §8.2, the reversed Fig. 15: the merged spheres shrink after the flow reverses
/// until both liquids are gone, every step closed, label-consistent and intersection-free.
/// A sphere shrinking alone would be gone at 1.3 s, 0.1 s before the end, so each liquid must
/// be below 1 % of its start volume (the volume bound for normal flow); measured at
/// 16³: red 0, blue 0.18 %.
#[test]
fn merge2_reverse_shrinks_both_liquids_away() {
    let (tracker, before, _) = run("merge2_reverse", 16, None);
    assert_eq!(before, 3);
    let start = 4.0 / 3.0 * std::f64::consts::PI * 0.14f64.powi(3);
    let volumes = tracker.phase_volumes();
    for (phase, name) in [(1, "red"), (2, "blue")] {
        assert!(
            volumes[phase] < 0.01 * start,
            "{name} keeps {} of {start}",
            volumes[phase]
        );
    }
}

/// Two expanding spheres of one liquid merge with no layer of air left between them: the
/// liquid is one region at the end (it was two), and the air is one region.
#[test]
fn merge_same_leaves_one_region_of_the_liquid() {
    let (_, before, after) = run("merge_same", 16, None);
    assert_eq!(before, 3, "two spheres in air");
    assert_eq!(after, 2, "one merged liquid in air");
}

/// Paper 000 Fig. 23: cyclic face-offsetting normal flow curls the material around the triple
/// curve; the first frames stay closed, label-consistent and intersection-free, and no region
/// is created or lost.
#[test]
fn cyclic_normal_flow_stays_valid() {
    let (_, before, after) = run("cyclic", 16, Some(3));
    assert_eq!((before, after), (3, 3));
}
