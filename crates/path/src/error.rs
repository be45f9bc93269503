//! What can go wrong before a path is traced: options out of range, lights that emit nothing,
//! a tracer that cannot be built.

/// Errors of the path tracer (library side; the CLI reports them with context).
#[derive(Debug, thiserror::Error)]
pub enum PathError {
    /// An option is out of its range; the message names the flag and the range.
    #[error("{0}")]
    Option(String),
    /// A light override is negative, NaN or infinite.
    #[error("{0}")]
    Light(String),
    /// Nothing emits light after the overrides (the image would be black).
    #[error("nothing emits light: {0}")]
    Unlit(String),
    /// `--tracer` names no known structure.
    #[error("unknown tracer {name:?}; expected one of {known}")]
    UnknownTracer { name: String, known: String },
    /// The tracer's structure could not be built for this scene and camera.
    #[error("building the {tracer} tracer: {message}")]
    Build { tracer: String, message: String },
    #[error(transparent)]
    Scene(#[from] parallax_scene::SceneError),
    #[error(transparent)]
    Core(#[from] parallax_core::CoreError),
    #[error("writing {path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}

pub type Result<T, E = PathError> = std::result::Result<T, E>;
