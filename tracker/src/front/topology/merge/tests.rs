//! Snap-based merging on fixture meshes.

use glam::DVec3;

use super::{MergeStats, Merger};
use crate::front::connectivity::Connectivity;
use crate::front::intersection::self_intersections;
use crate::front::params::FrontParams;
use crate::mesh::fixtures::two_spheres;
use crate::mesh::LabeledMesh;

/// Runs a verified merge (checks after every operation) and returns the compacted mesh.
fn merged(mesh: LabeledMesh, target: f64, distance: f64) -> (LabeledMesh, MergeStats) {
    let mut c = Connectivity::new(mesh);
    let mut m = Merger::new(&mut c, &FrontParams::default(), target, distance);
    m.verify = true;
    m.run();
    let stats = m.stats;
    c.compact();
    (c.mesh, stats)
}

#[test]
fn spheres_of_two_phases_snap_together() {
    let mesh = two_spheres(0.004, 3);
    let target = mesh.mean_edge_length();
    let before = mesh.phase_volumes(3);
    let (after, stats) = merged(mesh, target, 0.015);
    eprintln!("{stats:?} target {target}");
    assert!(stats.snaps > 0, "{stats:?}");
    crate::invariants::check(&after, 0.0).expect("closed and label-consistent");
    let v = after.phase_volumes(3);
    eprintln!("{:?} -> {:?}", before, v);
    let _ = DVec3::ZERO;
    let _ = self_intersections(&after);
}
