//! Typed errors of the rasterizer and the captures.

/// Errors of the rasterizer and the captures.
#[derive(Debug, thiserror::Error)]
pub enum RasterError {
    #[error("invalid view size: {0}")]
    Size(parallax_core::CoreError),
    #[error("invalid view: {0}")]
    InvalidView(String),
    #[error("invalid options: {0}")]
    InvalidOptions(String),
    #[error("invalid mesh: {0}")]
    InvalidMesh(String),
}
