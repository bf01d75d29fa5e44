//! Sparse SPD linear algebra: deterministic vector kernels, 7-point stencil matrices,
//! MIC(0) and geometric-multigrid preconditioners, and preconditioned conjugate gradients.

pub(crate) mod mic0;
pub(crate) mod multigrid;
pub(crate) mod pcg;
pub(crate) mod stencil;
pub(crate) mod vecops;
