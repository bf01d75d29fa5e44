//! The T2 process end to end (paper 000 §5.2, Fig. 13): in `mcf_t2` a small cell on the
//! triple line of three larger ones shrinks under mean-curvature flow and vanishes, the mesh
//! checked after every step (closed, label-consistent, intersection-free).

mod common;

use common::run_checked;

/// The small cell (phase 3, "small") is gone at the end and it was the only region lost.
#[test]
fn mcf_t2_small_cell_vanishes() {
    let (tracker, before, after) = run_checked("mcf_t2", 16, None);
    assert_eq!(before - after, 1, "regions {before} -> {after}");
    let mesh = tracker.mesh();
    assert!(
        mesh.labels.iter().all(|l| !l.contains(&3)),
        "a face of the small cell is left"
    );
    let volumes = mesh.phase_volumes(4);
    assert_eq!(volumes[3], 0.0, "{volumes:?}");
}
