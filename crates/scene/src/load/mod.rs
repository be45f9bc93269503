//! Scene file loaders: glTF 2.0 (`gltf` crate), OBJ + MTL (`tobj`), PLY (`ply-rs-bw`).
//!
//! Every loader validates what it returns ([`crate::Scene::validate`]) and reports problems as
//! [`crate::SceneError`] naming the file and the problem; malformed input never panics.
//!
//! | extension      | loader        | notes                                                   |
//! |----------------|---------------|---------------------------------------------------------|
//! | `.gltf` `.glb` | `gltf.rs`     | node transforms, PBR materials, lights, cameras, skins and animations (`gltf_anim.rs`) |
//! | `.obj`         | `obj.rs`      | MTL materials, `map_Kd` textures                        |
//! | `.ply`         | `ply.rs`      | positions, optional normals, polygon faces; one material |
//!
//! **Invariant:** no loader reads a file outside the folder of the scene file (`uri.rs`).

use std::path::Path;

use crate::{Result, Scene, SceneError};

mod gltf;
mod gltf_accessor;
mod gltf_anim;
mod gltf_material;
mod gltf_source;
mod image_decode;
mod obj;
mod ply;
mod uri;

/// A glTF animation or skin, parsed for later use (the animation issue).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationInfo {
    pub name: String,
    /// Number of channels (animation) or joints (skin).
    pub channels: usize,
    pub is_skin: bool,
}

/// Loads a scene file by extension (case-insensitive): `.gltf`, `.glb`, `.obj` or `.ply`.
pub fn load_file(path: &Path) -> Result<Scene> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let mut scene = match ext.as_deref() {
        Some("gltf" | "glb") => self::gltf::load(path, &read(path)?),
        Some("obj") => obj::load(path),
        Some("ply") => ply::load(path),
        _ => Err(SceneError::UnsupportedFormat {
            path: path.to_path_buf(),
        }),
    }?;
    scene.add_default_lighting_if_unlit();
    Ok(scene)
}

fn read(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The scene name: the file name without its extension.
fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
