//! glTF 2.0 loader (.gltf with external or data-URI buffers, .glb).
//!
//! The document is parsed and validated by `gltf-json` ([`super::gltf_source`]), but buffers,
//! images and accessors are resolved here and not by `gltf::import`: every external reference
//! goes through [`super::uri::resolve`] (no file outside the scene folder is read) and every
//! accessor byte range is checked ([`super::gltf_accessor`]). The default scene's node hierarchy is walked
//! (glTF 2.0 spec §3.5 "Nodes and hierarchy"): each mesh primitive instance becomes one
//! [`ObjectRange`] of world-space triangles. Skins and animation clips are loaded into
//! [`Scene::gltf_animation`] ([`super::gltf_anim`]); skinned primitives are posed in their rest
//! skeleton pose. Morph targets are not applied. Skins and animations are also listed in
//! [`Scene::animations`].

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::mesh::{Mode, Semantic};

use super::AnimationInfo;
use super::gltf_accessor::{read_indices, read_vec};
use super::gltf_anim::{PrimInstance, load_animation};
use super::gltf_material::convert_materials;
use super::gltf_source::{load_buffers, parse_document, split_glb};
use crate::{CameraDesc, Light, Material, NamedCamera, ObjectRange, Result, Scene, SceneError};

/// Most triangles (and vertices) one scene may expand to, node instancing included.
pub(crate) const MAX_TRIANGLES: usize = 1 << 27;

/// Loads a .gltf or .glb file whose bytes are `bytes` (GLB is recognised by its magic).
pub(crate) fn load(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let parse = |message: String| SceneError::Parse {
        path: path.to_path_buf(),
        message,
    };
    let is_glb_name = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    let (json, blob) = if bytes.starts_with(b"glTF") {
        split_glb(bytes).map_err(parse)?
    } else if is_glb_name {
        return Err(parse(format!(
            "not a binary glTF: the 'glTF' magic is missing ({} bytes; truncated or wrong format)",
            bytes.len()
        )));
    } else {
        (bytes, None)
    };
    let doc = parse_document(json).map_err(parse)?;
    let buffers = load_buffers(&doc, blob, path)?;
    let (materials, textures) = convert_materials(&doc, &buffers, path)?;
    let mut b = Builder {
        path,
        doc: &doc,
        buffers: &buffers,
        scene: Scene {
            name: super::uri::file_stem(path),
            materials,
            textures,
            ..Scene::default()
        },
        default_material: None,
        instances: Vec::new(),
    };
    b.walk()?;
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    if let Some(anim) = load_animation(&doc, &buffers, &b.instances, b.scene.mesh.vertex_count())
        .map_err(invalid)?
    {
        anim.apply_rest(&mut b.scene.mesh)
            .map_err(|e| invalid(e.to_string()))?;
        b.scene.gltf_animation = Some(std::sync::Arc::new(anim));
    }
    for a in doc.animations() {
        b.scene.animations.push(AnimationInfo {
            name: a.name().unwrap_or("").to_string(),
            channels: a.channels().count(),
            is_skin: false,
        });
    }
    for s in doc.skins() {
        b.scene.animations.push(AnimationInfo {
            name: s.name().unwrap_or("").to_string(),
            channels: s.joints().count(),
            is_skin: true,
        });
    }
    b.scene.validate().map_err(|message| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(b.scene)
}

struct Builder<'a> {
    path: &'a Path,
    doc: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    scene: Scene,
    /// Index of the appended default material, once a primitive without material needs it.
    default_material: Option<u32>,
    /// Every primitive instance emitted, for [`load_animation`].
    instances: Vec<PrimInstance>,
}

impl Builder<'_> {
    fn invalid(&self, message: String) -> SceneError {
        SceneError::Invalid {
            path: self.path.to_path_buf(),
            message,
        }
    }

    /// Walks the default scene (or the first, or every parentless node) depth first, children in
    /// document order, with an explicit stack and a visited mark per node: a cycle or a node
    /// with two parents (both invalid glTF) is an error instead of a hang.
    fn walk(&mut self) -> Result<()> {
        let doc = self.doc;
        let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().collect(),
            None => {
                let mut is_child = vec![false; doc.nodes().len()];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                doc.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let mut visited = vec![false; doc.nodes().len()];
        let mut stack: Vec<(gltf::Node, Mat4)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, Mat4::IDENTITY))
            .collect();
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut visited[node.index()], true) {
                return Err(self.invalid(format!(
                    "node {} is reached twice in the hierarchy (cycle or shared child)",
                    node.index()
                )));
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if let Some(mesh) = node.mesh() {
                let many = mesh.primitives().len() > 1;
                for prim in mesh.primitives() {
                    let base = mesh
                        .name()
                        .or(node.name())
                        .map(str::to_string)
                        .unwrap_or_else(|| format!("mesh{}", mesh.index()));
                    let name = if many {
                        format!("{base}#{}", prim.index())
                    } else {
                        base
                    };
                    self.add_primitive(&mesh, &prim, world, name, node.index())?;
                }
            }
            if let Some(cam) = node.camera() {
                self.add_camera(&node, &cam, world)?;
            }
            if let Some(light) = node.light() {
                self.add_light(&light, world)?;
            }
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world)));
        }
        Ok(())
    }

    fn add_primitive(
        &mut self,
        mesh: &gltf::Mesh,
        prim: &gltf::Primitive,
        world: Mat4,
        name: String,
        node: usize,
    ) -> Result<()> {
        // Points and lines carry no surface: skipped by design.
        if !matches!(
            prim.mode(),
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            return Ok(());
        }
        let Some(pos_acc) = prim.get(&Semantic::Positions) else {
            return Ok(());
        };
        let what = format!("mesh {} ({name}) primitive {}", mesh.index(), prim.index());
        let err = |m: String| self.invalid(format!("{what}: {m}"));
        let positions = read_vec::<3>(&pos_acc, self.buffers, false).map_err(err)?;
        let n = positions.len();
        if let Some((i, p)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(err(format!("vertex {i} has a non-finite position {p:?}")));
        }
        let attr = |sem: Semantic, label: &str| -> Result<Option<Vec<[f32; 3]>>> {
            let Some(acc) = prim.get(&sem) else {
                return Ok(None);
            };
            let v = read_vec::<3>(&acc, self.buffers, false).map_err(err)?;
            if v.len() != n {
                return Err(err(format!("{} {label} for {n} positions", v.len())));
            }
            Ok(Some(v))
        };
        let normals = attr(Semantic::Normals, "normals")?;
        let uvs = match prim.get(&Semantic::TexCoords(0)) {
            Some(acc) => {
                let v = read_vec::<2>(&acc, self.buffers, true).map_err(err)?;
                if v.len() != n {
                    return Err(err(format!(
                        "{} texture coordinates for {n} positions",
                        v.len()
                    )));
                }
                Some(v)
            }
            None => None,
        };
        let index_list = match prim.indices() {
            Some(acc) => read_indices(&acc, self.buffers).map_err(err)?,
            None if n <= u32::MAX as usize => (0..n as u32).collect(),
            None => return Err(err("too many vertices".into())),
        };
        if let Some((i, v)) = index_list
            .iter()
            .enumerate()
            .find(|&(_, &v)| v as usize >= n)
        {
            return Err(err(format!(
                "index {v} (element {i} of the index accessor) is out of range: {n} vertices"
            )));
        }
        let tris = assemble(prim.mode(), &index_list);
        if self.scene.mesh.positions.len() + n > MAX_TRIANGLES
            || self.scene.mesh.indices.len() + tris.len() > MAX_TRIANGLES
        {
            return Err(err(format!(
                "the scene expands to more than {MAX_TRIANGLES} vertices or triangles"
            )));
        }
        let material = match prim.material().index() {
            Some(i) => i as u32,
            None => *self.default_material.get_or_insert_with(|| {
                self.scene.materials.push(Material::default());
                self.scene.materials.len() as u32 - 1
            }),
        };
        let mesh_out = &mut self.scene.mesh;

        // Normals transform by the inverse transpose of the linear part; a mirroring transform
        // (negative determinant) reverses the winding, which is flipped back.
        let lin = Mat3::from_mat4(world);
        let det = lin.determinant();
        let nmat = if det.is_finite() && det.abs() > 1e-30 {
            lin.inverse().transpose()
        } else {
            Mat3::ZERO
        };
        let v0 = mesh_out.positions.len() as u32;
        let t0 = mesh_out.indices.len() as u32;
        mesh_out.positions.extend(
            positions
                .iter()
                .map(|p| world.transform_point3(Vec3::from(*p))),
        );
        match normals {
            Some(ns) => mesh_out.normals.extend(ns.iter().map(|nrm| {
                let v = Vec3::from(*nrm);
                if v.is_finite() {
                    (nmat * v).normalize_or_zero()
                } else {
                    Vec3::ZERO
                }
            })),
            None => mesh_out
                .normals
                .resize(mesh_out.positions.len(), Vec3::ZERO),
        }
        match uvs {
            Some(uv) => mesh_out.uvs.extend(uv.iter().map(|t| {
                let t = Vec2::from(*t);
                if t.is_finite() { t } else { Vec2::ZERO }
            })),
            None => mesh_out.uvs.resize(mesh_out.positions.len(), Vec2::ZERO),
        }
        let flip = det < 0.0;
        mesh_out.indices.extend(tris.iter().map(|&[a, b, c]| {
            if flip {
                [a + v0, c + v0, b + v0]
            } else {
                [a + v0, b + v0, c + v0]
            }
        }));
        mesh_out
            .material_ids
            .resize(mesh_out.indices.len(), material);
        self.instances.push(PrimInstance {
            node,
            mesh: mesh.index(),
            prim: prim.index(),
            object: mesh_out.objects.len(),
            first_vertex: v0,
            vertex_count: n as u32,
        });
        mesh_out.objects.push(ObjectRange {
            name,
            first_triangle: t0,
            triangle_count: tris.len() as u32,
            first_vertex: v0,
            vertex_count: n as u32,
        });
        Ok(())
    }

    /// A perspective camera node: eye at the node origin, looking down the node's -Z with +Y up
    /// (glTF spec §3.10). Orthographic cameras are skipped.
    fn add_camera(&mut self, node: &gltf::Node, cam: &gltf::Camera, world: Mat4) -> Result<()> {
        // From the JSON: `gltf::Camera::projection` unwraps a `perspective` object that
        // validation does not require for `"type": "perspective"`.
        let json = &self.doc.as_json().cameras[cam.index()];
        let (
            gltf::json::validation::Checked::Valid(gltf::json::camera::Type::Perspective),
            Some(p),
        ) = (&json.type_, &json.perspective)
        else {
            return Ok(());
        };
        let eye = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
        let name = cam
            .name()
            .or(node.name())
            .map(str::to_string)
            .unwrap_or_else(|| format!("camera{}", cam.index()));
        let desc = CameraDesc::new(eye, eye + forward, up, p.yfov.to_degrees());
        desc.validate()
            .map_err(|e| self.invalid(format!("camera {name:?}: {e}")))?;
        self.scene.cameras.push(NamedCamera { name, desc });
        Ok(())
    }

    /// KHR_lights_punctual: point/spot intensity is in candela (lm/sr), used as W/sr; directional
    /// intensity is in lux (lm/m^2), used as W/m^2. Lights shine down the node's -Z.
    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4) -> Result<()> {
        use gltf::khr_lights_punctual::Kind;
        let power = Vec3::from(light.color()) * light.intensity();
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
        if !(power.is_finite() && position.is_finite()) || direction == Vec3::ZERO {
            return Err(self.invalid(format!(
                "light {} has a non-finite intensity or a degenerate transform",
                light.index()
            )));
        }
        self.scene.lights.push(match light.kind() {
            Kind::Point => Light::Point {
                position,
                intensity: power,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => Light::Spot {
                position,
                direction,
                intensity: power,
                inner_angle: inner_cone_angle,
                outer_angle: outer_cone_angle,
            },
            Kind::Directional => Light::Directional {
                direction,
                irradiance: power,
            },
        });
        Ok(())
    }
}

/// Triangles of a primitive in its own vertex numbering (glTF spec §3.7.2.1 "Topology types"):
/// lists take consecutive triples; strips take `(i, i+1+i%2, i+2-i%2)`; fans `(i+1, i+2, 0)`.
fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    let n = idx.len();
    match mode {
        Mode::Triangles => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        Mode::TriangleStrip => (0..n.saturating_sub(2))
            .map(|i| [idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..n.saturating_sub(2))
            .map(|i| [idx[i + 1], idx[i + 2], idx[0]])
            .collect(),
        _ => Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_a_consistent_winding() {
        let idx = [0, 1, 2, 3, 4];
        assert_eq!(
            assemble(Mode::TriangleStrip, &idx),
            vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]
        );
        assert_eq!(
            assemble(Mode::TriangleFan, &idx),
            vec![[1, 2, 0], [2, 3, 0], [3, 4, 0]]
        );
        assert_eq!(assemble(Mode::Triangles, &idx), vec![[0, 1, 2]]);
        assert!(assemble(Mode::Lines, &idx).is_empty());
    }
}
