//! The explicit multimaterial front tracker of paper 000 (`tracker = "front"`): the labeled mesh
//! itself moves with the flow and is kept free of self-intersections by exact continuous
//! collision detection and collision-safe remeshing.

pub mod broadphase;
pub mod ccd;
pub mod collision;
pub mod connectivity;
pub mod flow;
pub mod front_tracker;
pub mod intersection;
mod least_squares;
pub mod params;
pub mod predicates;
pub mod remesh;
pub mod response;
pub mod topology;
