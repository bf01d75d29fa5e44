//! Scene errors: each names the problem and where it is.

use thiserror::Error;

/// Why a scene could not be loaded.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: cannot read scene file: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// Not valid TOML, or a field is missing, unknown or of the wrong type.
    #[error("{origin}: {message}")]
    Parse { origin: String, message: String },
    /// Well-formed but inconsistent or out of range: `place` is the field's path.
    #[error("{origin}: {place}: {message}")]
    Invalid {
        origin: String,
        place: String,
        message: String,
    },
    /// Neither a built-in scene name nor an existing file.
    #[error("no built-in scene or file named '{name}' (built-in scenes: {known})")]
    Unknown { name: String, known: String },
}
