//! Scenes (ARCHITECTURE.md "The parts", `scenes/`): the TOML format, validation with errors
//! that name the problem and its place, initial shapes, analytic velocity fields and the
//! built-in scenes.
#![deny(unsafe_code)]

pub mod builtin;
pub mod error;
pub mod format;
pub mod measure;
pub mod mesh_file;
pub mod mesh_sdf;
pub mod obj;
pub mod overlap;
pub mod scene;
pub mod shapes;
pub mod tension;
pub mod velocity;
pub mod volume;
pub mod voronoi;

pub use builtin::{builtin, load, BUILTIN, DEFAULT_SCENE};
pub use error::SceneError;
pub use format::{
    BoundaryKind, BoundarySpec, PreconditionerSpec, SceneFile, SolverSpec, TensionSpec,
    TrackerKind, TrackerSpec, WALLS,
};
pub use measure::{Measure, MeasureKind};
pub use scene::Scene;
pub use shapes::InitialPhases;
pub use tension::Tension;
pub use velocity::AnalyticVelocity;
