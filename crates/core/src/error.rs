//! Typed errors of the core layer.

use std::path::PathBuf;

/// Errors raised by core: image sizes, image IO.
#[derive(Debug, thiserror::Error)]
pub enum CoreError {
    /// An image size that is zero or too large to allocate safely.
    #[error("invalid image size {width}x{height}: {reason}")]
    InvalidSize {
        width: u64,
        height: u64,
        reason: &'static str,
    },
    /// Reading or writing an image file failed.
    #[error("{path}: {message}")]
    ImageIo { path: PathBuf, message: String },
    /// A file had an unexpected layout (missing channel, wrong size, ...).
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },
    /// Two images that must have the same size (e.g. for a metric) do not.
    #[error("image sizes differ: {a_width}x{a_height} vs {b_width}x{b_height}")]
    SizeMismatch {
        a_width: u32,
        a_height: u32,
        b_width: u32,
        b_height: u32,
    },
}

/// Result alias of the core layer.
pub type Result<T, E = CoreError> = std::result::Result<T, E>;
