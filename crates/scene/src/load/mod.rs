//! Scene file loaders: glTF 2.0 (`gltf` crate), OBJ + MTL (`tobj`), PLY (`ply-rs-bw`).
//!
//! Every loader validates what it returns ([`crate::Scene::validate`]) and reports problems as
//! [`crate::SceneError`] naming the file and the problem; malformed input never panics.

use std::path::Path;

use crate::{Result, Scene, SceneError};

/// A glTF animation or skin, parsed for later use (the animation issue).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationInfo {
    pub name: String,
    /// Number of channels (animation) or joints (skin).
    pub channels: usize,
    pub is_skin: bool,
}

/// Loads a scene file by extension.
pub fn load_file(path: &Path) -> Result<Scene> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        _ => Err(SceneError::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }
}
