//! Stanford PLY loader (`ply-rs-bw`; ASCII and binary).
//!
//! | PLY                                     | parallax                                      |
//! |-----------------------------------------|-----------------------------------------------|
//! | `vertex` `x y z` (any numeric type)     | positions                                     |
//! | `vertex` `nx ny nz` (optional)          | normals (zero = flat when absent)             |
//! | `face` `vertex_indices` / `vertex_index`| polygons, triangulated as fans `(0, i, i+1)`  |
//! | other elements and properties           | read and ignored (e.g. `confidence`)          |
//!
//! All faces use one grey (0.8) diffuse material; the scene has one object named after the file.
//! Faces with fewer than three vertices are skipped.

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

use crate::{Material, ObjectRange, Result, Scene, SceneError};

#[derive(Default)]
struct Vertex {
    p: [f32; 3],
    n: [f32; 3],
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            _ => return PropertyAccessResult::Ignored,
        };
        match property.to_f32_lossy() {
            Some(v) => {
                *slot = v;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

#[derive(Default)]
struct Face(Vec<u32>);

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        // Negative or non-integer indices are rejected by the parser with the property named.
        match property.to_u32_list() {
            Some(v) => {
                self.0 = v;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

/// An element of no interest: parsed (to stay in step with the file) and dropped.
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

pub(crate) fn load(path: &Path) -> Result<Scene> {
    let file = File::open(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let parse = |message: String| SceneError::Parse {
        path: path.to_path_buf(),
        message: format!("malformed PLY: {message}"),
    };
    let mut reader = Reader::new(BufReader::new(file));
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| parse(e.to_string()))?;
    let vdef = header
        .elements
        .get("vertex")
        .ok_or_else(|| parse("no `vertex` element".into()))?;
    for axis in ["x", "y", "z"] {
        if !vdef.properties.contains_key(axis) {
            return Err(parse(format!(
                "the vertex element has no `{axis}` property"
            )));
        }
    }
    let has_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|k| vdef.properties.contains_key(*k));

    let (mut verts, mut faces) = (Vec::new(), Vec::new());
    for (name, def) in &header.elements {
        let e = |e: ply_rs_bw::parser::ParseError| parse(format!("element `{name}`: {e}"));
        match name.as_str() {
            "vertex" => {
                verts = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(e)?
            }
            "face" => {
                faces = Parser::<Face>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(e)?
            }
            _ => {
                Parser::<Skip>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(e)?;
            }
        }
    }
    build(path, &verts, &faces, has_normals)
}

fn build(path: &Path, verts: &[Vertex], faces: &[Face], has_normals: bool) -> Result<Scene> {
    let invalid = |message: String| SceneError::Invalid {
        path: path.to_path_buf(),
        message,
    };
    let n = verts.len();
    if n > super::gltf::MAX_TRIANGLES {
        return Err(invalid(format!("{n} vertices is too many")));
    }
    let mut mesh = crate::TriangleMesh {
        positions: verts.iter().map(|v| Vec3::from(v.p)).collect(),
        ..Default::default()
    };
    if let Some((i, p)) = mesh
        .positions
        .iter()
        .enumerate()
        .find(|(_, p)| !p.is_finite())
    {
        return Err(invalid(format!("vertex {i} has a non-finite position {p}")));
    }
    mesh.normals = if has_normals {
        verts
            .iter()
            .map(|v| {
                let n = Vec3::from(v.n).normalize_or_zero();
                if n.is_finite() { n } else { Vec3::ZERO }
            })
            .collect()
    } else {
        vec![Vec3::ZERO; n]
    };
    mesh.uvs = vec![Vec2::ZERO; n];
    for (f, face) in faces.iter().enumerate() {
        if let Some(&v) = face.0.iter().find(|&&v| v as usize >= n) {
            return Err(invalid(format!(
                "face {f} uses vertex {v} but there are {n} vertices"
            )));
        }
        for i in 1..face.0.len().saturating_sub(1) {
            mesh.indices.push([face.0[0], face.0[i], face.0[i + 1]]);
        }
        if mesh.indices.len() > super::gltf::MAX_TRIANGLES {
            return Err(invalid("too many triangles".into()));
        }
    }
    if mesh.indices.is_empty() {
        return Err(invalid("no faces (point clouds are not supported)".into()));
    }
    mesh.material_ids = vec![0; mesh.indices.len()];
    let name = super::uri::file_stem(path);
    mesh.objects.push(ObjectRange {
        name: name.clone(),
        first_triangle: 0,
        triangle_count: mesh.indices.len() as u32,
        first_vertex: 0,
        vertex_count: n as u32,
    });
    let scene = Scene {
        name,
        mesh,
        materials: vec![Material::diffuse("grey", Vec3::splat(0.8))],
        ..Scene::default()
    };
    scene.validate().map_err(invalid)?;
    Ok(scene)
}
