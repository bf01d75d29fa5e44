//! The semi-Lagrangian contouring tracker's spatial part (paper 004 §5–§6): the adaptive
//! multiphase distance (MD) tree, multiphase marching tetrahedra with bisection, and the
//! closure of the mesh at the domain boundary.
//!
//! One step: [`MdTree::build`] with a [`PhaseSampler`] (backtrace + exact mesh query), then
//! [`MdTree::contour`] with the same sampler; [`MdTree::sample`] then serves χ away from the
//! interface (and φ as built). §6.4's redistancing is replaced by exact reads off the new
//! mesh where φ is asked for ([`crate::ContourTracker::phi_chi`]).
//!
//! Decisions (details in each file):
//! - `nodes`: φ, χ live in one open-addressing table keyed by the linear lattice node id
//!   (every sampled point, centres included, is a lattice node); cells keep their corners'
//!   slots, so only the build hashes.
//! - `tree`: a forest of root blocks (largest power of two ≤ 16 dividing all dims, or divided
//!   by a thin one), refined level by level with the §6.2 rule; each level's new points are
//!   deduplicated, sorted and evaluated in parallel. A conformity pass protects watertightness
//!   when φ over-estimates. A cell spans an axis thinner than its size (a slab's two cells in
//!   z) and splits in the other two only, so a slab's tree is a quadtree of columns down to
//!   size 2 (issue 16: 2-cell root blocks had every node of a slab sampled). Near the
//!   interface the cells are those of the cubic tree, so the contour is the same.
//! - `stencils`: Kuhn 6-tet split of every cube; the Fig. 5 stencils, oriented from nominal
//!   positions so the mesh is closed and label-consistent by construction.
//! - `bisect`: edge crossings by safeguarded regula falsi on brackets tightened with φ; triple
//!   points by intersecting interface lines (the paper's corner-replacement iteration is the
//!   fallback, and gives the quadruple points), then kept inside the triangle of their face's
//!   edge crossings (`extract`), so the sheets around a triple line keep the order their
//!   labels assume (no fold; tested).
//! - `triple_choice`, `untangle`: where a crossing collapses onto a node (an interface through
//!   lattice nodes), the triple point is chosen by sampling the face, and taken back where it
//!   tangles the mesh.
//! - `closure`: the domain boundary, conforming to hanging nodes of coarse leaves.
//! - `extract`: keys sorted before positions are computed, so the output is identical for any
//!   thread count.
//! - `persist`: an exact byte image of the tree, so a checkpointed tracker restarts bit for bit.

mod bisect;
mod closure;
mod extract;
pub(crate) mod nodes;
mod persist;
mod sampler;
mod stencils;
pub(crate) mod tree;
mod triple_choice;
mod untangle;

#[cfg(test)]
mod tests;

pub use persist::TreeDecodeError;
pub use sampler::PhaseSampler;
pub use tree::MdTree;
pub use triple_choice::TriplePoints;
