//! Wavefront OBJ + MTL loader (`tobj`, triangulated, one index per vertex).
//!
//! One [`ObjectRange`] per OBJ model (object/group/material run). OBJ texture coordinates have
//! v = 0 at the bottom of the image; they are flipped to the glTF convention (v = 0 at the top)
//! that [`crate::Texture::sample`] uses. MTL colours are taken as linear RGB.
//!
//! | MTL             | parallax                                                              |
//! |-----------------|-----------------------------------------------------------------------|
//! | `Kd`            | `base_color` (default 0.8 grey)                                       |
//! | `map_Kd`        | `base_color_texture` (path relative to the .obj folder, sRGB)         |
//! | `Ns`            | `roughness = (2 / (Ns + 2))^(1/4)`: the Phong-exponent <-> Beckmann   |
//! |                 | width match `alpha = sqrt(2 / (Ns + 2))` (Walter et al. 2007, §5.2),  |
//! |                 | with `alpha = roughness^2`; no `Ns` -> roughness 1                    |
//! | `Ke`            | `emissive`                                                            |
//! | `illum` 3, 5    | `MaterialKind::Mirror` tinted by `Ks` (by `Kd` without `Ks`)          |
//! | `illum` 4,6,7,9 | `MaterialKind::Dielectric` with `ior = Ni` (1.5 if absent or < 1)     |
//!
//! A missing or unreadable MTL file falls back to the default material (no error); an MTL or
//! texture reference that leaves the .obj folder is a [`SceneError::BadReference`].

use std::cell::RefCell;
use std::collections::HashMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::image_decode::decode_texture;
use super::uri::{RefError, resolve_relative};
use crate::{Material, MaterialKind, ObjectRange, Result, Scene, SceneError, WrapMode};

pub(crate) fn load(path: &Path) -> Result<Scene> {
    let file = File::open(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let forbidden: RefCell<Option<SceneError>> = RefCell::new(None);
    // tobj 4.0 overflows on some out-of-range relative indices (`f 1/-11`: found by
    // parallax-fuzz, crates/fuzz/regressions/panic-obj-01.obj): its panic becomes a parse
    // error here, and in release builds (wrapping arithmetic) its answer is still checked
    // below (indices in range, finite positions).
    let parse = std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut BufReader::new(file), &opts, |mtl| {
            let rel = mtl.to_string_lossy();
            match resolve_relative(path, &rel) {
                Ok(p) => tobj::load_mtl(p),
                Err(RefError::Missing(_)) => Err(tobj::LoadError::OpenFileFailed),
                Err(RefError::Forbidden(message)) => {
                    forbidden.replace(Some(SceneError::BadReference {
                        path: path.to_path_buf(),
                        uri: rel.into_owned(),
                        message,
                    }));
                    Err(tobj::LoadError::OpenFileFailed)
                }
            }
        })
    });
    let loaded = std::panic::catch_unwind(parse).map_err(|_| SceneError::Parse {
        path: path.to_path_buf(),
        message: "malformed OBJ: a face index is out of range (the OBJ parser overflowed)".into(),
    })?;
    if let Some(e) = forbidden.into_inner() {
        return Err(e);
    }
    let (models, mtl) = loaded.map_err(|e| SceneError::Parse {
        path: path.to_path_buf(),
        message: format!("malformed OBJ: {e}"),
    })?;
    let mtl = mtl.unwrap_or_default();

    let mut scene = Scene {
        name: super::uri::file_stem(path),
        ..Scene::default()
    };
    let mut texture_of: HashMap<PathBuf, u32> = HashMap::new();
    let mut texel_budget = 0u64;
    for m in &mtl {
        let mut mat = convert_material(m);
        if let Some(tex) = m.diffuse_texture.as_deref() {
            // `map_Kd [-options] file`: the file name is the last word.
            let rel = tex.split_whitespace().last().unwrap_or("");
            let bad = |message: String| SceneError::BadReference {
                path: path.to_path_buf(),
                uri: rel.to_string(),
                message,
            };
            let file = resolve_relative(path, rel).map_err(|e| bad(e.to_string()))?;
            let id = match texture_of.get(&file) {
                Some(&id) => id,
                None => {
                    let bytes = std::fs::read(&file).map_err(|e| bad(e.to_string()))?;
                    let t = decode_texture(
                        &bytes,
                        rel,
                        WrapMode::Repeat,
                        WrapMode::Repeat,
                        &mut texel_budget,
                    )
                    .map_err(|message| SceneError::Parse {
                        path: path.to_path_buf(),
                        message,
                    })?;
                    scene.textures.push(t);
                    let id = scene.textures.len() as u32 - 1;
                    texture_of.insert(file, id);
                    id
                }
            };
            mat.base_color_texture = Some(id);
        }
        scene.materials.push(mat);
    }

    let mut default_material = None;
    for model in &models {
        let m = &model.mesh;
        let invalid = |message: String| SceneError::Invalid {
            path: path.to_path_buf(),
            message: format!("object {:?}: {message}", model.name),
        };
        let n = m.positions.len() / 3;
        let out = &scene.mesh;
        let (v0, t0) = (out.positions.len(), out.indices.len());
        if v0 + n > super::gltf::MAX_TRIANGLES {
            return Err(invalid("too many vertices".into()));
        }
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(Vec3::from_slice).collect();
        if let Some((i, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(invalid(format!("vertex {i} has a non-finite position {p}")));
        }
        let tris: Vec<[u32; 3]> = m
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        if let Some(t) = tris.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(invalid(format!("face {t:?} out of range ({n} vertices)")));
        }
        let material = match m.material_id.filter(|&i| i < scene.materials.len()) {
            Some(i) => i as u32,
            None => *default_material.get_or_insert_with(|| {
                scene.materials.push(Material::default());
                scene.materials.len() as u32 - 1
            }),
        };
        let out = &mut scene.mesh;
        out.positions.extend_from_slice(&positions);
        if m.normals.len() == m.positions.len() {
            out.normals.extend(m.normals.chunks_exact(3).map(|c| {
                let v = Vec3::from_slice(c).normalize_or_zero();
                if v.is_finite() { v } else { Vec3::ZERO }
            }));
        } else {
            out.normals.resize(v0 + n, Vec3::ZERO);
        }
        if m.texcoords.len() == 2 * n {
            out.uvs.extend(m.texcoords.chunks_exact(2).map(|c| {
                let t = Vec2::new(c[0], 1.0 - c[1]);
                if t.is_finite() { t } else { Vec2::ZERO }
            }));
        } else {
            out.uvs.resize(v0 + n, Vec2::ZERO);
        }
        out.indices
            .extend(tris.iter().map(|t| t.map(|i| i + v0 as u32)));
        out.material_ids.resize(out.indices.len(), material);
        out.objects.push(ObjectRange {
            name: model.name.clone(),
            first_triangle: t0 as u32,
            triangle_count: tris.len() as u32,
            first_vertex: v0 as u32,
            vertex_count: n as u32,
        });
    }
    scene.validate().map_err(|message| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(scene)
}

/// MTL parameters -> material (table in the module docs).
fn convert_material(m: &tobj::Material) -> Material {
    let kd = m.diffuse.map(Vec3::from).unwrap_or(Vec3::splat(0.8));
    let ks = m.specular.map(Vec3::from);
    let roughness = m
        .shininess
        .map(|ns| (2.0 / (ns.max(0.0) + 2.0)).powf(0.25))
        .unwrap_or(1.0);
    let mut mat = Material {
        name: m.name.clone(),
        kind: MaterialKind::Standard,
        base_color: kd,
        base_color_texture: None,
        roughness,
        metallic: 0.0,
        emissive: m.emissive.map(Vec3::from).unwrap_or(Vec3::ZERO),
        ..Material::default()
    };
    match m.illumination_model {
        Some(3 | 5) => {
            mat.kind = MaterialKind::Mirror;
            mat.base_color = ks.filter(|s| s.max_element() > 0.0).unwrap_or(kd);
        }
        Some(4 | 6 | 7 | 9) => {
            let ior = m.optical_density.filter(|&n| n >= 1.0 && n.is_finite());
            mat.kind = MaterialKind::Dielectric {
                ior: ior.unwrap_or(1.5),
            };
        }
        _ => {}
    }
    // Non-finite MTL numbers become the defaults rather than poisoning the renderer.
    if !mat.base_color.is_finite() {
        mat.base_color = Vec3::splat(0.8);
    }
    if !mat.emissive.is_finite() {
        mat.emissive = Vec3::ZERO;
    }
    if !mat.roughness.is_finite() {
        mat.roughness = 1.0;
    }
    mat
}
