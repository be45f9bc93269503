//! Typed errors of the scene layer. Every message names the file and the problem.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read file: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The file is not valid for its format (truncated, malformed, ...).
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    /// The file parsed but its content is unusable (NaN positions, indices out of range, ...).
    #[error("{path}: invalid scene data: {message}")]
    Invalid { path: PathBuf, message: String },
    /// A referenced file lies outside the scene's folder or does not exist.
    #[error("{path}: bad reference {uri:?}: {message}")]
    BadReference {
        path: PathBuf,
        uri: String,
        message: String,
    },
    #[error("unknown scene {name:?}; built-in scenes: {known}")]
    UnknownScene { name: String, known: String },
    #[error("unsupported scene file {path}: expected .gltf, .glb, .obj or .ply")]
    UnsupportedFormat { path: PathBuf },
    #[error("invalid camera: {0}")]
    Camera(String),
}

pub type Result<T, E = SceneError> = std::result::Result<T, E>;

/// Why an animation cannot be made or applied.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AnimationError {
    #[error("animated object {index} out of range ({count} objects)")]
    NoSuchObject { index: usize, count: usize },
    #[error("object {0:?} has vertices beyond the mesh")]
    VerticesOutOfRange(String),
    #[error("animation made for {expected} vertices applied to a mesh with {given}")]
    WrongMesh { expected: usize, given: usize },
    #[error("the pose at t = {t} s puts vertex {vertex} at a non-finite position")]
    NonFinite { t: f32, vertex: usize },
}
