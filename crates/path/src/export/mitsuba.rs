//! Export for the Mitsuba 3 cross-check (`tools/mitsuba_check.py` builds a Mitsuba scene
//! dictionary from it): binary little-endian PLY meshes, one per (material, shading) group,
//! linear EXR base-colour textures, and `scene.json` with the camera, film, integrator
//! settings, lights and materials.
//!
//! | ours | `scene.json` | Mitsuba 3 |
//! |---|---|---|
//! | pinhole `eye, target, up, fov_y` | `camera` | `perspective`, `fov_axis = "y"`, `to_world = look_at` |
//! | box filter over the pixel | `film` | `hdrfilm` with `rfilter = box` |
//! | `max_depth`, `rr_depth`, `spp`, `seed` | `integrator` | `path` integrator, `independent` sampler |
//! | Lambert of base colour / texture (two-sided) | `shapes[].bsdf = diffuse` | `twosided(diffuse)` with `bitmap` (bilinear, wrap mode) |
//! | glass: thin dielectric, index 1.5 | `shapes[].bsdf = thindielectric` | `thindielectric`, `int_ior 1.5`, `ext_ior 1.0` |
//! | emissive triangles (front face) | `shapes[].emission` | `area` emitter, `radiance` |
//! | constant environment | `environment` | `constant`, `radiance` |
//! | point light, intensity W/sr | `lights[] point` | `point`, `intensity` |
//! | directional light, irradiance | `lights[] directional` | `directional`, `irradiance` |
//!
//! Vertex normals are written for groups whose vertices all carry one (Mitsuba then shades
//! with them, as we do); other triangles go into flat groups without normals. Texture
//! coordinates are written as stored (glTF convention: `v = 0` at the image's top row), which is
//! Mitsuba's bitmap convention for PLY meshes (`flip_tex_coords = false`).
//!
//! Mitsuba's bitmap has one wrap mode for both axes: the texture's `s` mode is written. A base
//! colour factor other than one is baked into the exported texels (the bitmap has no factor).
//!
//! Only `--materials diffuse` exports: our metallic-roughness GGX has no exact Mitsuba
//! counterpart, nor does KHR_lights_punctual's spot falloff (spot lights are refused).

use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use glam::{Vec2, Vec3};
use parallax_core::image::exr;
use parallax_render::bsdf::{MaterialMode, is_glass};
use parallax_scene::{CameraDesc, Light, Scene, WrapMode};
use serde_json::{Value, json};

use crate::error::{PathError, Result};
use crate::options::PathOptions;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> PathError + '_ {
    move |source| PathError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn v3(v: Vec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// Writes a binary little-endian PLY with positions, optional normals and uvs.
fn write_ply(
    path: &Path,
    positions: &[Vec3],
    normals: Option<&[Vec3]>,
    uvs: &[Vec2],
    faces: &[[u32; 3]],
) -> Result<()> {
    let mut out = Vec::with_capacity(positions.len() * 32 + faces.len() * 13 + 256);
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        positions.len()
    );
    if normals.is_some() {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    header += &format!(
        "property float u\nproperty float v\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        faces.len()
    );
    out.extend_from_slice(header.as_bytes());
    for (i, p) in positions.iter().enumerate() {
        let mut put = |v: f32| out.extend_from_slice(&v.to_le_bytes());
        put(p.x);
        put(p.y);
        put(p.z);
        if let Some(n) = normals {
            put(n[i].x);
            put(n[i].y);
            put(n[i].z);
        }
        put(uvs[i].x);
        put(uvs[i].y);
    }
    for f in faces {
        out.push(3);
        for &i in f {
            out.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    std::fs::File::create(path)
        .and_then(|mut f| f.write_all(&out))
        .map_err(io(path))
}

fn wrap_name(w: WrapMode) -> &'static str {
    match w {
        WrapMode::Repeat => "repeat",
        WrapMode::MirroredRepeat => "mirror",
        WrapMode::ClampToEdge => "clamp",
    }
}

/// Writes the export of `scene` seen through `camera` at `width x height` into `dir`.
pub fn export(
    dir: &Path,
    scene: &Scene,
    camera: &CameraDesc,
    width: u32,
    height: u32,
    opts: &PathOptions,
) -> Result<()> {
    if opts.materials != MaterialMode::Diffuse {
        return Err(PathError::Option(
            "the Mitsuba export needs --materials diffuse (the model both renderers share)".into(),
        ));
    }
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let mesh = &scene.mesh;
    // Group triangles by (material, has vertex normals).
    let mut groups: BTreeMap<(u32, bool), Vec<usize>> = BTreeMap::new();
    for (t, idx) in mesh.indices.iter().enumerate() {
        let smooth = idx
            .iter()
            .all(|&i| mesh.normals[i as usize].length_squared() > 0.0);
        groups
            .entry((mesh.material_ids[t], smooth))
            .or_default()
            .push(t);
    }
    let mut textures: BTreeMap<u64, String> = BTreeMap::new();
    let mut shapes = Vec::new();
    for ((mat_id, smooth), tris) in &groups {
        let m = &scene.materials[*mat_id as usize];
        // Compact the vertices this group uses.
        let mut remap: Vec<u32> = vec![u32::MAX; mesh.positions.len()];
        let (mut pos, mut nrm, mut uv, mut faces) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for &t in tris {
            let mut f = [0u32; 3];
            for (k, &i) in mesh.indices[t].iter().enumerate() {
                let i = i as usize;
                if remap[i] == u32::MAX {
                    remap[i] = pos.len() as u32;
                    pos.push(mesh.positions[i]);
                    nrm.push(mesh.normals[i].normalize_or_zero());
                    uv.push(mesh.uvs[i]);
                }
                f[k] = remap[i];
            }
            faces.push(f);
        }
        let file = format!(
            "mesh_{mat_id:04}_{}.ply",
            if *smooth { "smooth" } else { "flat" }
        );
        write_ply(
            &dir.join(&file),
            &pos,
            smooth.then_some(nrm.as_slice()),
            &uv,
            &faces,
        )?;
        let bsdf = if is_glass(m) {
            json!({"type": "thindielectric", "int_ior": parallax_render::bsdf::GLASS_IOR, "ext_ior": 1.0})
        } else {
            let mut b = json!({"type": "diffuse", "reflectance": v3(m.base_color)});
            if let Some(t) = m.base_color_texture {
                // Mitsuba's bitmap has no colour factor: a factor other than one is baked into
                // a texture file of its own.
                let tex = &scene.textures[t as usize];
                let factor = m.base_color;
                let key = if factor == Vec3::ONE {
                    t as u64
                } else {
                    (1 << 32) | *mat_id as u64
                };
                let name = match textures.get(&key) {
                    Some(n) => n.clone(),
                    None => {
                        let n = if factor == Vec3::ONE {
                            format!("texture_{t:04}.exr")
                        } else {
                            format!("texture_{t:04}_material_{mat_id:04}.exr")
                        };
                        let split = |c: usize| -> Vec<f32> {
                            tex.texels.iter().map(|v| v[c] * factor[c]).collect()
                        };
                        let (r, g, bl) = (split(0), split(1), split(2));
                        exr::write_exr(
                            dir.join(&n),
                            tex.width,
                            tex.height,
                            &[("R", &r), ("G", &g), ("B", &bl)],
                        )?;
                        textures.insert(key, n.clone());
                        n
                    }
                };
                b["texture"] = json!(name);
                b["wrap_mode"] = json!(wrap_name(tex.wrap_s));
            }
            b
        };
        let emission = m.is_emissive().then(|| v3(m.emissive));
        shapes.push(json!({
            "file": file,
            "material": m.name,
            "triangles": faces.len(),
            "face_normals": !smooth,
            "bsdf": bsdf,
            "emission": emission,
        }));
    }
    let mut lights = Vec::new();
    for l in &scene.lights {
        lights.push(match l {
            Light::Point {
                position,
                intensity,
            } => json!({"type": "point", "position": v3(*position), "intensity": v3(*intensity)}),
            Light::Directional {
                direction,
                irradiance,
            } => json!({"type": "directional", "direction": v3(*direction), "irradiance": v3(*irradiance)}),
            Light::Spot { .. } => {
                return Err(PathError::Option(
                    "the Mitsuba export refuses spot lights: Mitsuba's spot falloff differs from \
                     KHR_lights_punctual's; override the lights with --env / --point"
                        .into(),
                ));
            }
        });
    }
    let doc = json!({
        "scene": scene.name,
        "film": {"width": width, "height": height, "filter": "box"},
        "camera": {
            "type": "perspective",
            "eye": v3(camera.eye),
            "target": v3(camera.target),
            "up": v3(camera.up),
            "fov_y_deg": camera.fov_y_deg,
        },
        "integrator": {
            "type": "path",
            "max_depth": opts.max_depth,
            "rr_depth": opts.rr_depth,
            "spp": opts.spp,
            "seed": opts.seed,
        },
        "materials": opts.materials.name(),
        "environment": v3(scene.environment),
        "lights": lights,
        "shapes": shapes,
    });
    let p = dir.join("scene.json");
    let text = serde_json::to_string_pretty(&doc).expect("json values serialise");
    std::fs::write(&p, text).map_err(io(&p))
}
