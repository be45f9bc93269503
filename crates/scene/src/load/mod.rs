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

use crate::{Result, Scene, SceneError, builtin};

mod gltf;
mod gltf_accessor;
mod gltf_anim;
mod gltf_material;
mod gltf_source;
mod image_decode;
mod obj;
mod ply;
mod uri;

pub use crate::scene::AnimationInfo;

impl Scene {
    /// A built-in scene by name, or a scene file (.gltf, .glb, .obj, .ply) by path, or
    /// `room:<file>` (also `room-mirror:`, `room-glass:`): the file staged in the built-in
    /// secondary-ray room ([`crate::builtin::room`]).
    pub fn load(name_or_path: &str) -> Result<Scene> {
        if let Some(scene) = builtin::by_name(name_or_path) {
            return Ok(scene);
        }
        if let Some((finish, file)) = builtin::room::parse(name_or_path) {
            let model = Self::load(file)?;
            return builtin::room::stage(model, finish).map_err(|message| SceneError::Invalid {
                path: file.into(),
                message,
            });
        }
        let path = Path::new(name_or_path);
        if path.extension().is_none() && !path.exists() {
            return Err(SceneError::UnknownScene {
                name: name_or_path.to_string(),
                known: builtin::NAMES.join(", "),
            });
        }
        load_file(path)
    }
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
