//! Topology changes of the labeled mesh (paper 000 §5 and §6): snap-based merging of
//! surfaces that come within the merge distance, T1 processes (vertex separation of
//! irregular vertices) and T2 processes (removal of degenerate and vanishing regions). Each
//! operation is atomic and collision-safe like the remeshing operations, so the mesh stays
//! closed, label-consistent and intersection-free.

pub mod degenerate;
pub mod merge;
pub mod needle;
pub mod region_graph;
pub mod regions;
pub mod separate;
pub mod vanish;

/// Compacts a copy of `c`, asserts it is closed, label-consistent and intersection-free, and
/// returns the compacted mesh (the topology tests' check after every operation).
#[cfg(test)]
pub(crate) fn clean(c: &super::connectivity::Connectivity) -> crate::mesh::LabeledMesh {
    let mut d = c.clone();
    d.compact();
    crate::invariants::check(&d.mesh, 0.0).expect("closed and label-consistent");
    let hits = super::intersection::self_intersections(&d.mesh);
    assert!(hits.is_empty(), "intersections {hits:?}");
    d.mesh
}
