//! Topology changes of the labeled mesh (paper 000 §5 and §6): snap-based merging of
//! surfaces that come within the merge distance, T1 processes (vertex separation of
//! irregular vertices) and T2 processes (removal of degenerate and vanishing regions). Each
//! operation is atomic and collision-safe like the remeshing operations, so the mesh stays
//! closed, label-consistent and intersection-free.

pub mod degenerate;
pub mod merge;
pub mod region_graph;
pub mod regions;
pub mod separate;
pub mod vanish;
