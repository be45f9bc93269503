//! glTF materials and base-colour textures -> [`Material`], [`Texture`].
//!
//! | glTF                                       | parallax                                  |
//! |--------------------------------------------|-------------------------------------------|
//! | `pbrMetallicRoughness.baseColorFactor`     | `base_color` (linear RGB), `alpha`        |
//! | `pbrMetallicRoughness.baseColorTexture`    | `base_color_texture` (sRGB -> linear)     |
//! | `metallicFactor`, `roughnessFactor`        | `metallic`, `roughness`                   |
//! | `emissiveFactor` x `KHR_materials_emissive_strength` | `emissive`                      |
//! | `extras.mitsuba_bsdf` = `*dielectric`      | `MaterialKind::Dielectric` (ior from `KHR_materials_ior`, default 1.5) |
//! | `extras.mitsuba_bsdf` = `*conductor`       | `metallic = 1` (roughness kept)           |
//! | `alphaMode`, `alphaCutoff`                 | `alpha_mode` (`Mask { cutoff }`, default 0.5) |
//! | `KHR_materials_transmission.transmissionFactor` | `transmission`                       |
//!
//! Not used: metallic-roughness, normal, occlusion, emissive and transmission textures, the
//! alpha channel of base-colour textures, texture transforms, texture coordinate sets other
//! than 0.

use std::path::Path;

use glam::Vec3;
use gltf::texture::WrappingMode;

use super::image_decode::decode_texture;
use super::uri::{Resolved, resolve};
use crate::{AlphaMode, Material, MaterialKind, Result, SceneError, Texture, WrapMode};

/// Converts all materials of `doc` (in document order) and the textures they use as base colour.
pub(crate) fn convert_materials(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    path: &Path,
) -> Result<(Vec<Material>, Vec<Texture>)> {
    let mut textures = Vec::new();
    let mut texel_budget = 0u64;
    // glTF texture index -> index into `textures`, decoded on first use.
    let mut texture_map: Vec<Option<u32>> = vec![None; doc.textures().len()];
    let mut materials = Vec::with_capacity(doc.materials().len());
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let [r, g, b, a] = pbr.base_color_factor();
        let mut mat = Material {
            name: m
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("material{}", m.index().unwrap_or(0))),
            kind: MaterialKind::Standard,
            base_color: Vec3::new(r, g, b),
            base_color_texture: None,
            roughness: pbr.roughness_factor().clamp(0.0, 1.0),
            metallic: pbr.metallic_factor().clamp(0.0, 1.0),
            emissive: Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask {
                    cutoff: m.alpha_cutoff().unwrap_or(0.5),
                },
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha: a.clamp(0.0, 1.0),
            transmission: m
                .transmission()
                .map_or(0.0, |t| t.transmission_factor().clamp(0.0, 1.0)),
        };
        if let Some(info) = pbr.base_color_texture() {
            let t = info.texture();
            let slot = &mut texture_map[t.index()];
            if slot.is_none() {
                textures.push(load_texture(doc, &t, buffers, path, &mut texel_budget)?);
                *slot = Some(textures.len() as u32 - 1);
            }
            mat.base_color_texture = *slot;
        }
        match mitsuba_bsdf(&m).as_deref() {
            Some(b) if b.ends_with("dielectric") => {
                mat.kind = MaterialKind::Dielectric {
                    ior: m.ior().unwrap_or(1.5),
                };
            }
            Some(b) if b.ends_with("conductor") => mat.metallic = 1.0,
            _ => {}
        }
        if !(mat.base_color.is_finite()
            && mat.emissive.is_finite()
            && mat.roughness.is_finite()
            && mat.alpha.is_finite()
            && mat.transmission.is_finite())
        {
            return Err(SceneError::Invalid {
                path: path.to_path_buf(),
                message: format!("material {:?} has non-finite factors", mat.name),
            });
        }
        materials.push(mat);
    }
    Ok((materials, textures))
}

/// `extras.mitsuba_bsdf` of a material converted from Mitsuba (see `../shared/scenes/*/SOURCE.txt`).
fn mitsuba_bsdf(m: &gltf::Material) -> Option<String> {
    let raw = m.extras().as_ref()?;
    let v: serde_json::Value = serde_json::from_str(raw.get()).ok()?;
    v.get("mitsuba_bsdf")?.as_str().map(str::to_string)
}

fn wrap(m: WrappingMode) -> WrapMode {
    match m {
        WrappingMode::Repeat => WrapMode::Repeat,
        WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
        WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
    }
}

fn load_texture(
    doc: &gltf::Document,
    t: &gltf::Texture,
    buffers: &[Vec<u8>],
    path: &Path,
    budget: &mut u64,
) -> Result<Texture> {
    let image = t.source();
    let name = t
        .name()
        .or(image.name())
        .map(str::to_string)
        .unwrap_or_else(|| format!("image{}", image.index()));
    let parse_err = |message: String| SceneError::Parse {
        path: path.to_path_buf(),
        message,
    };
    // The JSON is read directly: `gltf::Image::source` unwraps fields that validation does not
    // check (an image with neither `bufferView` nor `uri`, or no `mimeType` beside a view).
    let json = &doc.as_json().images[image.index()];
    let owned;
    let bytes: &[u8] = match (&json.buffer_view, &json.uri) {
        (Some(v), _) => {
            let view = doc
                .views()
                .nth(v.value())
                .ok_or_else(|| parse_err(format!("image {} has no buffer view", image.index())))?;
            let data = &buffers[view.buffer().index()];
            view.offset()
                .checked_add(view.length())
                .and_then(|end| data.get(view.offset()..end))
                .ok_or_else(|| {
                    parse_err(format!(
                        "image {} lies outside buffer {}",
                        image.index(),
                        view.buffer().index()
                    ))
                })?
        }
        (None, Some(uri)) => {
            owned = match resolve(path, uri)? {
                Resolved::Data(d) => d,
                Resolved::File(f) => std::fs::read(&f).map_err(|source| SceneError::Io {
                    path: f.clone(),
                    source,
                })?,
            };
            &owned
        }
        (None, None) => {
            return Err(parse_err(format!(
                "image {} has neither a bufferView nor a uri",
                image.index()
            )));
        }
    };
    let s = t.sampler();
    decode_texture(bytes, &name, wrap(s.wrap_s()), wrap(s.wrap_t()), budget).map_err(parse_err)
}
