//! What can go wrong in a reprojection run: options out of range (the message names the flag),
//! the path tracer's own errors, scene and camera errors, and the reference cache's I/O.

use crate::error::PathError;

/// Errors of the reprojection (library side; the CLI reports them with context).
#[derive(Debug, thiserror::Error)]
pub enum ReprojectError {
    /// An option is out of its range; the message names the flag and the range.
    #[error("{0}")]
    Option(String),
    #[error(transparent)]
    Path(#[from] PathError),
    #[error(transparent)]
    Scene(#[from] parallax_scene::SceneError),
    #[error("building the BVH: {0}")]
    Bvh(String),
    /// A per-frame consumer (writing frames, scoring) failed.
    #[error("{0}")]
    Consumer(String),
    #[error("reference cache {path}: {source}")]
    Io {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
}

pub type Result<T, E = ReprojectError> = std::result::Result<T, E>;

/// An [`ReprojectError::Option`].
pub(crate) fn option_error<T>(message: impl Into<String>) -> Result<T> {
    Err(ReprojectError::Option(message.into()))
}
