//! Scene file loaders against the real models in `../shared/scenes` (triangle counts from their
//! SOURCE.txt, bounds recomputed independently from the glTF JSON) and against small files
//! written to a temporary folder (node transforms, materials, lights, cameras, and one test per
//! error case, each asserting that the message names the problem).
//! OBJ and PLY files: `loaders_obj_ply.rs`.

use glam::{Mat4, Quat, Vec3};
use parallax_scene::load::load_file;
use parallax_scene::{AlphaMode, Light, MaterialKind, Scene, SceneError, WrapMode};
use serde_json::{Value, json};

#[path = "common/files.rs"]
mod files;
use files::{load, load_err, scenes, tmp, write};

// ---- expected bounds from the glTF JSON, independently of the loader ----

fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

fn node_matrix(n: &Value) -> Mat4 {
    let f = |k: &str, d: &[f32]| -> Vec<f32> {
        n.get(k).map_or(d.to_vec(), |v| {
            v.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap() as f32)
                .collect()
        })
    };
    if n.get("matrix").is_some() {
        return Mat4::from_cols_slice(&f("matrix", &[]));
    }
    let (t, r, s) = (
        f("translation", &[0.0; 3]),
        f("rotation", &[0.0, 0.0, 0.0, 1.0]),
        f("scale", &[1.0; 3]),
    );
    Mat4::from_scale_rotation_translation(
        Vec3::from_slice(&s),
        Quat::from_slice(&r),
        Vec3::from_slice(&t),
    )
}

/// Union over mesh instances of the 8 corners of each POSITION accessor's min/max box, moved by
/// the node's world matrix.
fn expected_bounds(j: &Value) -> (Vec3, Vec3) {
    fn visit(j: &Value, node: usize, parent: Mat4, b: &mut (Vec3, Vec3)) {
        let n = &j["nodes"][node];
        let world = parent * node_matrix(n);
        if let Some(m) = n.get("mesh") {
            for p in j["meshes"][m.as_u64().unwrap() as usize]["primitives"]
                .as_array()
                .unwrap()
            {
                let acc = &j["accessors"][p["attributes"]["POSITION"].as_u64().unwrap() as usize];
                let v = |k: &str| {
                    let a: Vec<f32> = acc[k]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap() as f32)
                        .collect();
                    Vec3::from_slice(&a)
                };
                let (lo, hi) = (v("min"), v("max"));
                for c in 0..8 {
                    let corner = Vec3::new(
                        if c & 1 == 0 { lo.x } else { hi.x },
                        if c & 2 == 0 { lo.y } else { hi.y },
                        if c & 4 == 0 { lo.z } else { hi.z },
                    );
                    let w = world.transform_point3(corner);
                    b.0 = b.0.min(w);
                    b.1 = b.1.max(w);
                }
            }
        }
        for c in n
            .get("children")
            .and_then(Value::as_array)
            .unwrap_or(&vec![])
        {
            visit(j, c.as_u64().unwrap() as usize, world, b);
        }
    }
    let mut b = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let scene = j.get("scene").and_then(Value::as_u64).unwrap_or(0) as usize;
    for r in j["scenes"][scene]["nodes"].as_array().unwrap() {
        visit(j, r.as_u64().unwrap() as usize, Mat4::IDENTITY, &mut b);
    }
    b
}

fn assert_bounds(s: &Scene, (lo, hi): (Vec3, Vec3)) {
    let b = s.bounds();
    let tol = 1e-5 * (hi - lo).max_element().max(1.0);
    assert!(
        b.min.abs_diff_eq(lo, tol) && b.max.abs_diff_eq(hi, tol),
        "{}: bounds {:?}..{:?}, expected {lo}..{hi}",
        s.name,
        b.min,
        b.max
    );
}

/// Shading normals agree with the triangle winding (checks normal transform + winding flip).
fn assert_normals_match_winding(s: &Scene) {
    let m = &s.mesh;
    for i in 0..m.triangle_count() {
        let g = m.geometric_normal(i);
        let n = m.shading_normal(i, 1.0 / 3.0, 1.0 / 3.0);
        assert!(
            g.dot(n) > 0.99,
            "{}: triangle {i}: geometric {g} vs shading {n}",
            s.name
        );
    }
}

// ---- the real models ----

#[test]
fn box_textured_gltf_and_glb_give_identical_meshes() {
    let dir = scenes().join("box_textured");
    let gltf = load(&dir.join("BoxTextured.gltf"));
    let glb = load(&dir.join("BoxTextured.glb"));
    assert_eq!(gltf.name, "BoxTextured");
    assert_eq!(
        (gltf.mesh.triangle_count(), gltf.mesh.vertex_count()),
        (12, 24)
    );
    assert_eq!(gltf.mesh, glb.mesh);
    assert_eq!(gltf.materials, glb.materials);
    assert_eq!(gltf.textures, glb.textures);
    let t = &gltf.textures[0];
    assert_eq!((gltf.textures.len(), t.width, t.height), (1, 211, 211));
    assert_eq!((t.wrap_s, t.wrap_t), (WrapMode::Repeat, WrapMode::Repeat));
    assert_eq!(gltf.materials[0].base_color_texture, Some(0));
    assert!(
        gltf.mesh.uvs.iter().any(|uv| uv.x > 5.9),
        "texcoords up to u = 6"
    );
    let text = std::fs::read_to_string(dir.join("BoxTextured.gltf")).unwrap();
    assert_bounds(
        &gltf,
        expected_bounds(&serde_json::from_str(&text).unwrap()),
    );
    assert_normals_match_winding(&gltf);
    // The root's rotation matrix (+Y -> -Z, +Z -> +Y) keeps the box axis-aligned: every normal
    // is a unit axis and each of the six directions belongs to one 4-vertex face.
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        for sign in [1.0, -1.0] {
            assert_eq!(
                gltf.mesh
                    .normals
                    .iter()
                    .filter(|n| n.abs_diff_eq(axis * sign, 1e-6))
                    .count(),
                4
            );
        }
    }
}

#[test]
fn box_textured_loads_with_an_upper_case_extension() {
    let folder = tmp("upper");
    let d = folder.path();
    let p = d.join("BOX.GLTF");
    std::fs::copy(scenes().join("box_textured/BoxTextured.gltf"), &p).unwrap();
    assert_eq!(load(&p).mesh.triangle_count(), 12);
}

fn check_glb(rel: &str, triangles: usize, objects: usize, materials: usize, textures: usize) {
    let p = scenes().join(rel);
    let t0 = std::time::Instant::now();
    let s = load(&p);
    eprintln!("{rel}: loaded in {:.2?}", t0.elapsed());
    assert_eq!(s.mesh.triangle_count(), triangles, "{rel}");
    assert_eq!(s.mesh.objects.len(), objects, "{rel}");
    assert_eq!(s.materials.len(), materials, "{rel}");
    assert_eq!(s.textures.len(), textures, "{rel}");
    let covered: u32 = s.mesh.objects.iter().map(|o| o.triangle_count).sum();
    assert_eq!(covered as usize, triangles);
    assert_bounds(&s, expected_bounds(&glb_json(&std::fs::read(&p).unwrap())));
}

#[test]
fn japanese_classroom_loads() {
    check_glb(
        "japanese_classroom/japanese_classroom.glb",
        103_832,
        79,
        44,
        3,
    );
    let s = load(&scenes().join("japanese_classroom/japanese_classroom.glb"));
    // 14 meshes are textured (SOURCE.txt).
    let textured = s
        .mesh
        .objects
        .iter()
        .filter(|o| {
            let m = s.mesh.material_ids[o.first_triangle as usize];
            s.materials[m as usize].base_color_texture.is_some()
        })
        .count();
    assert_eq!(textured, 14);
    let chair = s
        .materials
        .iter()
        .find(|m| m.name == "ChairStainless")
        .unwrap();
    assert_eq!(chair.metallic, 1.0);
    assert!(
        s.mesh.normals.contains(&Vec3::ZERO),
        "flat shapes have no normals"
    );
}

#[test]
fn sponza_loads() {
    check_glb("sponza_dabrovic/sponza_dabrovic.glb", 66_445, 37, 19, 10);
}

#[test]
fn stanford_bunny_ply_equals_its_glb_conversion() {
    let dir = scenes().join("stanford_bunny");
    let ply = load(&dir.join("bun_zipper.ply"));
    let glb = load(&dir.join("bunny.glb"));
    assert_eq!(
        (ply.mesh.triangle_count(), ply.mesh.vertex_count()),
        (69_451, 35_947)
    );
    assert_eq!(glb.mesh.triangle_count(), 69_451);
    assert_eq!(ply.name, "bun_zipper");
    // SOURCE.txt: "positions unchanged" by the conversion.
    assert_eq!(ply.mesh.positions, glb.mesh.positions);
    assert_eq!(ply.mesh.indices, glb.mesh.indices);
    assert!(ply.mesh.normals.iter().all(|n| *n == Vec3::ZERO));
    assert!(
        glb.mesh
            .normals
            .iter()
            .all(|n| (n.length() - 1.0).abs() < 1e-4)
    );
    assert_eq!(ply.materials.len(), 1);
    assert_bounds(
        &glb,
        expected_bounds(&glb_json(&std::fs::read(dir.join("bunny.glb")).unwrap())),
    );
}

// ---- small generated glTF files ----

fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = c
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | (b as u32) << (16 - 8 * i));
        for i in 0..4 {
            s.push(if i <= c.len() {
                A[(n >> (18 - 6 * i)) as usize & 63] as char
            } else {
                '='
            });
        }
    }
    s
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A one-triangle glTF whose buffer `uri` is given; returns (json, bin).
fn triangle_gltf(positions: [[f32; 3]; 3], indices: [u16; 3], uri: &str) -> (Value, Vec<u8>) {
    let mut bin = f32s(positions.as_flattened());
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    bin.extend([0, 0]);
    let json = json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "tri"}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": uri, "byteLength": 44}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    });
    (json, bin)
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn external_bin_and_data_uri_buffers_load_the_same_triangle() {
    let folder = tmp("external");
    let d = folder.path();
    let (json, bin) = triangle_gltf(TRI, [0, 1, 2], "sub/../tri data.bin");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    write(d, "tri data.bin", &bin);
    let ext = load(&write(d, "ext.gltf", json.to_string()));
    let uri = format!("data:application/octet-stream;base64,{}", base64(&bin));
    let (json, _) = triangle_gltf(TRI, [0, 1, 2], &uri);
    let inline = load(&write(d, "inline.gltf", json.to_string()));
    assert_eq!(ext.mesh, inline.mesh);
    assert_eq!(ext.mesh.positions, TRI.map(Vec3::from).to_vec());
    assert_eq!(ext.mesh.indices, vec![[0, 1, 2]]);
    // No material -> one default material; no normals -> zero (flat) normals.
    assert_eq!(ext.materials.len(), 1);
    assert_eq!(ext.mesh.normals, vec![Vec3::ZERO; 3]);
    // Percent-encoded file names resolve too.
    let (json, _) = triangle_gltf(TRI, [0, 1, 2], "tri%20data.bin");
    assert_eq!(load(&write(d, "pct.gltf", json.to_string())).mesh, ext.mesh);
}

/// The glTF of `node_transforms_materials_cameras_and_lights` (json, h.bin).
fn hierarchy_gltf() -> (Value, Vec<u8>) {
    let mut bin = f32s(&[0., 0., 0., 1., 0., 0., 0., 1., 0., 1., 1., 0.]); // 0: positions
    bin.extend(f32s(&[0., 0., 1.].repeat(4))); // 48: normals
    bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes())); // 96: list (+pad)
    bin.extend([0u16, 1, 2, 3].iter().flat_map(|i| i.to_le_bytes())); // 104: strip
    bin.extend(f32s(&[0., 1.])); // 112: times
    bin.extend(f32s(&[0., 0., 0., 0., 1., 0.])); // 120: translations
    assert_eq!(bin.len(), 144);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let json = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 0.5, 0.25], "intensity": 100.0}
        ]}},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "root", "translation": [10, 0, 0], "children": [1, 2, 3, 4]},
            {"name": "mirrored", "mesh": 0, "scale": [-1, 1, 1]},
            {"name": "turned", "mesh": 1, "rotation": [0, h, 0, h]},
            {"name": "cam", "camera": 0, "translation": [0, 0, 5]},
            {"name": "lamp", "translation": [0, 3, 0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "cameras": [{"name": "main", "type": "perspective",
                     "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [
            {"name": "list", "primitives": [
                {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]},
            {"name": "strip", "primitives": [
                {"attributes": {"POSITION": 0}, "mode": 0},
                {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 3, "mode": 5}]}
        ],
        "materials": [
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1],
              "metallicFactor": 0.25, "roughnessFactor": 0.75},
             "emissiveFactor": [1, 1, 1],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5.0}},
             "alphaMode": "MASK", "alphaCutoff": 0.3},
            {"name": "glass", "extras": {"mitsuba_bsdf": "dielectric"}, "alphaMode": "BLEND",
             "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.1]},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8}}}
        ],
        "animations": [{"name": "bob", "samplers": [{"input": 4, "output": 5}],
                        "channels": [{"sampler": 0, "target": {"node": 2, "path": "translation"}}]}],
        "skins": [{"name": "rig", "joints": [1, 2]}],
        "buffers": [{"uri": "h.bin", "byteLength": 144}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 6},
            {"buffer": 0, "byteOffset": 104, "byteLength": 8},
            {"buffer": 0, "byteOffset": 112, "byteLength": 8},
            {"buffer": 0, "byteOffset": 120, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 3, "componentType": 5123, "count": 4, "type": "SCALAR"},
            {"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0], "max": [1]},
            {"bufferView": 5, "componentType": 5126, "count": 2, "type": "VEC3"}
        ]
    });
    (json, bin)
}

/// Node hierarchy with TRS and a mirroring scale, a triangle strip, a skipped points primitive,
/// materials (emissive strength, Mitsuba dielectric), a camera, a point light, an animation and
/// a skin.
#[test]
fn node_transforms_materials_cameras_and_lights() {
    let folder = tmp("hierarchy");
    let d = folder.path();
    let (json, bin) = hierarchy_gltf();
    write(d, "h.bin", &bin);
    let s = load(&write(d, "h.gltf", json.to_string()));
    let m = &s.mesh;
    // 1 list triangle + 2 strip triangles; the points primitive is skipped.
    assert_eq!(m.triangle_count(), 3);
    let names: Vec<_> = m.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["list", "strip#1"]);
    assert_eq!(m.objects[1].first_triangle, 1);
    assert_eq!(m.objects[1].first_vertex, 4);
    // Mirrored instance: x negated then moved by the root.
    assert!(m.positions[1].abs_diff_eq(Vec3::new(9.0, 0.0, 0.0), 1e-6));
    // Turned instance: 90 degrees about +Y maps +X to -Z.
    assert!(m.positions[5].abs_diff_eq(Vec3::new(10.0, 0.0, -1.0), 1e-6));
    assert!(m.normals[5].abs_diff_eq(Vec3::X, 1e-6));
    assert_normals_match_winding(&s);
    assert!(
        m.geometric_normal(0).abs_diff_eq(Vec3::Z, 1e-6),
        "mirror flips the winding back"
    );
    // Materials: the strip has none -> a default appended after the two file materials.
    assert_eq!(m.material_ids, vec![0, 2, 2]);
    assert_eq!(s.materials.len(), 3);
    let red = &s.materials[0];
    assert_eq!(
        (red.base_color, red.metallic, red.roughness),
        (Vec3::X, 0.25, 0.75)
    );
    assert_eq!(red.emissive, Vec3::splat(5.0));
    assert_eq!(s.materials[1].kind, MaterialKind::Dielectric { ior: 1.5 });
    assert_eq!(red.alpha_mode, AlphaMode::Mask { cutoff: 0.3 });
    let glass = &s.materials[1];
    assert_eq!(
        (glass.alpha_mode, glass.alpha, glass.transmission),
        (AlphaMode::Blend, 0.1, 0.8)
    );
    assert!(glass.is_glass() && !red.is_glass());
    assert_eq!(s.materials[2].alpha_mode, AlphaMode::Opaque);
    // Camera at the node, looking down its -Z.
    let cam = s.camera(Some("main")).unwrap();
    assert!(cam.eye.abs_diff_eq(Vec3::new(10.0, 0.0, 5.0), 1e-6));
    assert!(cam.target.abs_diff_eq(Vec3::new(10.0, 0.0, 4.0), 1e-6));
    assert!(cam.up.abs_diff_eq(Vec3::Y, 1e-6));
    assert!((cam.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!(
        s.lights,
        vec![Light::Point {
            position: Vec3::new(10.0, 3.0, 0.0),
            intensity: Vec3::new(100.0, 50.0, 25.0)
        }]
    );
    let anims: Vec<_> = s
        .animations
        .iter()
        .map(|a| (a.name.as_str(), a.channels, a.is_skin))
        .collect();
    assert_eq!(anims, [("bob", 1, false), ("rig", 2, true)]);
}

// ---- error cases ----

#[test]
fn truncated_glb_is_a_parse_error() {
    let folder = tmp("truncated");
    let d = folder.path();
    let full = std::fs::read(scenes().join("box_textured/BoxTextured.glb")).unwrap();
    for n in [0, 7, 11, 20, 1000, full.len() - 1] {
        let (e, msg) = load_err(&write(d, "cut.glb", &full[..n]));
        assert!(matches!(e, SceneError::Parse { .. }), "{n} bytes: {msg}");
        assert!(msg.contains("truncated"), "{n} bytes: {msg}");
    }
    // Many more prefixes (every header and chunk-header byte, then a stride through the
    // chunks; file writes cost milliseconds here): a parse error, never a panic.
    for n in (0..64).chain((64..full.len()).step_by(61)) {
        match load_file(&write(d, "cut.glb", &full[..n])) {
            Err(SceneError::Parse { message, .. }) => {
                assert!(message.contains("truncated"), "{n} bytes: {message}")
            }
            other => panic!("{n} bytes: {other:?}"),
        }
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// Random byte changes anywhere in a GLB (JSON, accessor data, PNG) give an error or a valid
    /// scene, never a panic.
    #[test]
    fn corrupted_glb_never_panics(
        flips in proptest::collection::vec((0usize..1 << 16, proptest::prelude::any::<u8>()), 1..6)
    ) {
        let folder = tmp("corrupt");
        let d = folder.path();
        let mut bytes = std::fs::read(scenes().join("box_textured/BoxTextured.glb")).unwrap();
        let n = bytes.len();
        for (i, b) in flips {
            bytes[i % n] = b;
        }
        if let Ok(s) = load_file(&write(d, "c.glb", &bytes)) {
            proptest::prop_assert!(s.validate().is_ok());
        }
    }

    /// Changing digits of the glTF JSON re-targets indices (nodes, cameras, lights, accessors,
    /// views, samplers) and sizes: an error or a valid scene, never a panic.
    #[test]
    fn gltf_with_changed_numbers_never_panics(
        edits in proptest::collection::vec((0usize..1 << 16, 0u8..10), 1..4)
    ) {
        let folder = tmp("digits");
        let d = folder.path();
        let (json, bin) = hierarchy_gltf();
        write(d, "h.bin", &bin);
        let mut text = json.to_string().into_bytes();
        let digits: Vec<usize> = (0..text.len()).filter(|&i| text[i].is_ascii_digit()).collect();
        for (i, v) in edits {
            text[digits[i % digits.len()]] = b'0' + v;
        }
        if let Ok(s) = load_file(&write(d, "h.gltf", &text)) {
            proptest::prop_assert!(s.validate().is_ok());
        }
    }
}

#[test]
fn missing_bin_names_the_file() {
    let folder = tmp("missing");
    let d = folder.path();
    let (json, _) = triangle_gltf(TRI, [0, 1, 2], "missing.bin");
    let (e, msg) = load_err(&write(d, "m.gltf", json.to_string()));
    assert!(matches!(e, SceneError::BadReference { .. }), "{msg}");
    assert!(
        msg.contains("missing.bin") && msg.contains("cannot open"),
        "{msg}"
    );
}

#[test]
fn nan_position_is_invalid() {
    let folder = tmp("nan");
    let d = folder.path();
    let (json, bin) = triangle_gltf(
        [[0.0; 3], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [0, 1, 2],
        "n.bin",
    );
    write(d, "n.bin", &bin);
    let (e, msg) = load_err(&write(d, "n.gltf", json.to_string()));
    assert!(matches!(e, SceneError::Invalid { .. }), "{msg}");
    assert!(
        msg.contains("non-finite") && msg.contains("vertex 1") && msg.contains("tri"),
        "{msg}"
    );
}

#[test]
fn out_of_range_index_is_invalid() {
    let folder = tmp("range");
    let d = folder.path();
    let (json, bin) = triangle_gltf(TRI, [0, 1, 7], "r.bin");
    write(d, "r.bin", &bin);
    let (e, msg) = load_err(&write(d, "r.gltf", json.to_string()));
    assert!(matches!(e, SceneError::Invalid { .. }), "{msg}");
    assert!(
        msg.contains("index 7") && msg.contains("out of range") && msg.contains("mesh 0"),
        "{msg}"
    );
}

#[test]
fn accessor_past_the_buffer_end_is_invalid() {
    let folder = tmp("overrun");
    let d = folder.path();
    let (mut json, bin) = triangle_gltf(TRI, [0, 1, 2], "o.bin");
    json["accessors"][0]["count"] = json!(1000);
    write(d, "o.bin", &bin);
    let (e, msg) = load_err(&write(d, "o.gltf", json.to_string()));
    assert!(matches!(e, SceneError::Invalid { .. }), "{msg}");
    assert!(msg.contains("do not fit"), "{msg}");
}

#[test]
fn references_escaping_the_scene_folder_are_refused() {
    let folder = tmp("escape");
    let d = folder.path();
    let inner = d.join("scene");
    std::fs::create_dir_all(&inner).unwrap();
    let (_, bin) = triangle_gltf(TRI, [0, 1, 2], "");
    let secret = write(d, "secret.bin", &bin); // exists, so only the check can refuse it
    for (uri, what) in [
        ("../secret.bin".to_string(), "climbs out"),
        (secret.display().to_string(), "absolute"),
        (format!("file://{}", secret.display()), "not allowed"),
    ] {
        let (json, _) = triangle_gltf(TRI, [0, 1, 2], &uri);
        let (e, msg) = load_err(&write(&inner, "x.gltf", json.to_string()));
        assert!(matches!(e, SceneError::BadReference { .. }), "{uri}: {msg}");
        assert!(msg.contains(&uri) && msg.contains(what), "{uri}: {msg}");
    }
}

#[test]
fn unsupported_extension_and_missing_file() {
    let folder = tmp("ext");
    let d = folder.path();
    let (e, msg) = load_err(&write(d, "scene.fbx", "x"));
    assert!(matches!(e, SceneError::UnsupportedFormat { .. }), "{msg}");
    assert!(msg.contains("scene.fbx"), "{msg}");
    let (e, msg) = load_err(&d.join("absent.glb"));
    assert!(
        matches!(e, SceneError::Io { .. }) && msg.contains("absent.glb"),
        "{msg}"
    );
}
