//! The explicit multimaterial front tracker of paper 000 (`tracker = "front"`): the labeled mesh
//! itself moves with the flow and is kept free of self-intersections by exact continuous
//! collision detection and collision-safe remeshing.
