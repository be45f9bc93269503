//! glTF animation and skinning (glTF 2.0 spec §3.7.3, §3.11) on files the tests write: a
//! two-bone skinned strip with known weights and a rotation channel (STEP, LINEAR, CUBICSPLINE),
//! posed vertices and normals compared with values worked out by hand from the spec's formulas at
//! keyframes, between them and after looping; a rigid node animation (cubic translation with
//! tangents, slerped rotation under a scaled parent); malformed files give errors, never panics.

#[path = "common/gltf_build.rs"]
mod gltf_build;

use std::f32::consts::FRAC_PI_2;

use glam::{Quat, Vec3};
use gltf_build::{GltfBuf, tmp_dir, write};
use parallax_scene::animation::Animation;
use parallax_scene::load::load_file;
use parallax_scene::{Scene, SceneError};
use serde_json::{Value, json};

/// Keyframe angles (rad, about +Z) of the second bone at t = 0, 1, 2 s.
const ANGLES: [f32; 3] = [0.0, FRAC_PI_2, FRAC_PI_2 / 3.0];

/// How the strip stores its skin attributes.
#[derive(Clone, Copy, Debug)]
enum Weights {
    /// Float weights summing to 1, u16 joints.
    F32,
    /// Float weights summing to 2 (renormalised by the loader), u8 joints.
    F32Double,
    /// Normalised u8 weights (128 + 128 = 256/255 at the middle, renormalised), u8 joints.
    U8,
    /// Normalised u16 weights, u16 joints.
    U16,
}

/// A strip of 3 x 2 vertices `(x, y, 0)`, x in {0, 1, 2}, y in {0, 0.5} (vertex `2 col + row`),
/// normals +X, skinned to bone 0 (node 1, at the origin) and bone 1 (node 2, child of bone 0 at
/// x = 1, inverse bind = translate(-1, 0, 0)): column 0 fully bone 0, column 1 half and half,
/// column 2 fully bone 1. Bone 1 rotates about +Z through [`ANGLES`] with `interp`. The mesh
/// node is translated by (5, 0, 0), which skinning ignores (spec §3.7.3).
fn strip(interp: &str, weights: Weights) -> (GltfBuf, Value) {
    let mut b = GltfBuf::default();
    let pos: Vec<f32> = (0..6)
        .flat_map(|v| [(v / 2) as f32, 0.5 * (v % 2) as f32, 0.0])
        .collect();
    let p = b.floats(&pos, "VEC3");
    let n = b.floats(&[1.0, 0.0, 0.0].repeat(6), "VEC3");
    let idx = b.ints(&[0, 2, 1, 1, 2, 3, 2, 4, 3, 3, 4, 5], 5123, "SCALAR", false);
    let w_col = |c: usize, scale: f32| match c {
        0 => [scale, 0.0, 0.0, 0.0],
        1 => [0.5 * scale, 0.5 * scale, 0.0, 0.0],
        _ => [0.0, scale, 0.0, 0.0],
    };
    let joints: Vec<u32> = [0, 1, 0, 0].repeat(6);
    let (j, w) = match weights {
        Weights::F32 | Weights::F32Double => {
            let s = if matches!(weights, Weights::F32) {
                1.0
            } else {
                2.0
            };
            let w: Vec<f32> = (0..6).flat_map(|v| w_col(v / 2, s)).collect();
            let jc = if matches!(weights, Weights::F32) {
                5123
            } else {
                5121
            };
            (b.ints(&joints, jc, "VEC4", false), b.floats(&w, "VEC4"))
        }
        Weights::U8 | Weights::U16 => {
            let (full, half, jc) = if matches!(weights, Weights::U8) {
                (255, 128, 5121)
            } else {
                (65535, 32768, 5123)
            };
            let w: Vec<u32> = (0..6)
                .flat_map(|v| match v / 2 {
                    0 => [full, 0, 0, 0],
                    1 => [half, half, 0, 0],
                    _ => [0, full, 0, 0],
                })
                .collect();
            (
                b.ints(&joints, jc, "VEC4", false),
                b.ints(&w, jc, "VEC4", true),
            )
        }
    };
    let mut ibm = glam::Mat4::IDENTITY.to_cols_array().to_vec();
    ibm.extend(glam::Mat4::from_translation(-Vec3::X).to_cols_array());
    let ibm = b.floats(&ibm, "MAT4");
    let times = b.floats(&[0.0, 1.0, 2.0], "SCALAR");
    let quats: Vec<[f32; 4]> = ANGLES
        .iter()
        .map(|&a| Quat::from_rotation_z(a).to_array())
        .collect();
    let out: Vec<f32> = if interp == "CUBICSPLINE" {
        quats
            .iter()
            .flat_map(|q| [[0.0; 4], *q, [0.0; 4]])
            .flatten()
            .collect()
    } else {
        quats.concat()
    };
    let out = b.floats(&out, "VEC4");
    let doc = json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "skinned", "mesh": 0, "skin": 0, "translation": [5, 0, 0]},
            {"name": "bone0", "children": [2]},
            {"name": "bone1", "translation": [1, 0, 0]}
        ],
        "meshes": [{"name": "strip", "primitives": [{
            "attributes": {"POSITION": p, "NORMAL": n, "JOINTS_0": j, "WEIGHTS_0": w},
            "indices": idx}]}],
        "skins": [{"name": "rig", "joints": [1, 2], "inverseBindMatrices": ibm, "skeleton": 1}],
        "animations": [{"name": "bend",
            "samplers": [{"input": times, "output": out, "interpolation": interp}],
            "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]}]
    });
    (b, doc)
}

fn save_and_load(name: &str, b: &GltfBuf, doc: Value) -> Result<Scene, SceneError> {
    let folder = tmp_dir(name);
    let d = folder.path();
    load_file(&write(d, "a.gltf", &b.finish(doc)))
}

/// The bone-1 angle at `t` (looped over 2 s) for each interpolation, from the spec's formulas.
fn expected_angle(interp: &str, t: f32) -> f32 {
    let t = t.rem_euclid(2.0);
    let k = (t as usize).min(1);
    let s = t - k as f32;
    let (a0, a1) = (ANGLES[k], ANGLES[k + 1]);
    match interp {
        "STEP" => a0,
        // Slerp about one axis: the angle moves linearly.
        "LINEAR" => a0 + (a1 - a0) * s,
        // Zero tangents: normalize(h00 q0 + h01 q1) with the Hermite basis.
        _ => {
            let h00 = 2.0 * s * s * s - 3.0 * s * s + 1.0;
            let h01 = -2.0 * s * s * s + 3.0 * s * s;
            let (z, w) = (
                h00 * (a0 / 2.0).sin() + h01 * (a1 / 2.0).sin(),
                h00 * (a0 / 2.0).cos() + h01 * (a1 / 2.0).cos(),
            );
            2.0 * z.atan2(w)
        }
    }
}

/// Vertex `v` of the strip and its normal with bone 1 at angle `a`, worked out by hand: bone 1's
/// skinning matrix is translate(1,0,0) rot(a) translate(-1,0,0); the middle column blends it
/// half and half with the identity, and `I + R(a) = 2 cos(a/2) R(a/2)`, so its normal turns by
/// `a/2`.
fn expected_vertex(v: usize, a: f32) -> (Vec3, Vec3) {
    let (x, y) = ((v / 2) as f32, 0.5 * (v % 2) as f32);
    let bone1 = |p: Vec3| {
        let q = p - Vec3::X;
        Vec3::new(
            q.x * a.cos() - q.y * a.sin(),
            q.x * a.sin() + q.y * a.cos(),
            0.0,
        ) + Vec3::X
    };
    let p = Vec3::new(x, y, 0.0);
    let turn = |b: f32| Vec3::new(b.cos(), b.sin(), 0.0);
    match v / 2 {
        0 => (p, Vec3::X),
        1 => (0.5 * p + 0.5 * bone1(p), turn(a / 2.0)),
        _ => (bone1(p), turn(a)),
    }
}

#[test]
fn skinned_strip_follows_the_hand_computed_pose_in_every_interpolation_mode() {
    let times = [0.0, 0.25, 0.5, 1.0, 1.5, 1.75, 2.5, 3.0, -0.5];
    for interp in ["LINEAR", "STEP", "CUBICSPLINE"] {
        let (b, doc) = strip(interp, Weights::F32);
        let scene = save_and_load(interp, &b, doc).unwrap();
        let anim = scene.gltf_animation.clone().expect("animation loaded");
        assert_eq!(anim.instances.len(), 1);
        assert_eq!(anim.clips[0].duration, 2.0);
        // The loaded mesh is the rest pose; the mesh node's translation is ignored.
        for v in 0..6 {
            let (p, _) = expected_vertex(v, 0.0);
            assert!(
                scene.mesh.positions[v].abs_diff_eq(p, 1e-6),
                "{interp} rest {v}"
            );
        }
        let choice = Animation::for_scene(&scene);
        assert_eq!(choice.kind(), "gltf");
        assert_eq!(choice.moving_vertices(&scene.mesh), 6);
        let mut mesh = scene.mesh.clone();
        for t in times {
            choice.apply(&mut mesh, t).unwrap();
            let a = expected_angle(interp, t);
            for v in 0..6 {
                let (p, n) = expected_vertex(v, a);
                assert!(
                    mesh.positions[v].abs_diff_eq(p, 2e-6),
                    "{interp} t={t} v={v}: {} vs {p} (angle {a})",
                    mesh.positions[v]
                );
                assert!(
                    mesh.normals[v].abs_diff_eq(n, 2e-6),
                    "{interp} t={t} v={v}: normal {} vs {n}",
                    mesh.normals[v]
                );
                let slow = anim.vertex_at(0, v, t).unwrap();
                assert!(slow.abs_diff_eq(p, 2e-6), "{interp} t={t} v={v}: twin");
            }
            assert!(mesh.validate(scene.materials.len()).is_ok());
        }
        // Sanity of the expectations themselves: the modes differ between keyframes.
        assert!((expected_angle(interp, 1.5) - ANGLES[1]).abs() > 0.1 || interp == "STEP");
    }
}

#[test]
fn integer_and_unnormalised_weights_pose_like_float_weights() {
    let (b, doc) = strip("LINEAR", Weights::F32);
    let reference = save_and_load("wref", &b, doc).unwrap();
    for w in [Weights::F32Double, Weights::U8, Weights::U16] {
        let (b, doc) = strip("LINEAR", w);
        let scene = save_and_load(&format!("{w:?}"), &b, doc).unwrap();
        let (mut m0, mut m1) = (reference.mesh.clone(), scene.mesh.clone());
        for t in [0.3, 1.2] {
            Animation::for_scene(&reference).apply(&mut m0, t).unwrap();
            Animation::for_scene(&scene).apply(&mut m1, t).unwrap();
            for v in 0..6 {
                // u8 / u16 full weight is exactly 1; halves renormalise to exactly 0.5.
                assert!(
                    m0.positions[v].abs_diff_eq(m1.positions[v], 1e-6),
                    "{w:?} t={t} v={v}: {} vs {}",
                    m0.positions[v],
                    m1.positions[v]
                );
            }
        }
        let binding = scene.gltf_animation.as_ref().unwrap().instances[0]
            .skin
            .as_ref()
            .unwrap()
            .clone();
        for v in binding.weights.chunks(binding.influences) {
            assert!((v.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{w:?}");
        }
    }
}

/// Root scaled by 2 with child node 1 (one triangle, normals +Z) animated by a CUBICSPLINE
/// translation with tangents and a LINEAR rotation about +Y (0 to 90 degrees over 2 s); node 2
/// shows the same mesh without animation.
fn rigid_doc() -> (GltfBuf, Value) {
    let mut b = GltfBuf::default();
    let p = b.floats(&[0., 0., 0., 1., 0., 0., 0., 1., 0.], "VEC3");
    let n = b.floats(&[0., 0., 1.].repeat(3), "VEC3");
    let times = b.floats(&[0.0, 2.0], "SCALAR");
    // (in-tangent, value, out-tangent) per keyframe.
    let tr = b.floats(
        &[
            0., 0., 0., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 2., 0., 0., 0., 0.,
        ],
        "VEC3",
    );
    let q1 = Quat::from_rotation_y(FRAC_PI_2).to_array();
    let rot = b.floats(&[[0.0, 0.0, 0.0, 1.0], q1].concat(), "VEC4");
    let doc = json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"name": "root", "children": [1], "scale": [2, 2, 2]},
            {"name": "mover", "mesh": 0},
            {"name": "still", "mesh": 0, "translation": [0, 0, -3]}
        ],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": p, "NORMAL": n}}]}],
        "animations": [{"name": "move",
            "samplers": [
                {"input": times, "output": tr, "interpolation": "CUBICSPLINE"},
                {"input": times, "output": rot}
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 1, "path": "translation"}},
                {"sampler": 1, "target": {"node": 1, "path": "rotation"}}
            ]}]
    });
    (b, doc)
}

#[test]
fn rigid_node_animation_moves_instances_with_their_node() {
    let (b, doc) = rigid_doc();
    let scene = save_and_load("rigid", &b, doc).unwrap();
    let anim = scene.gltf_animation.clone().unwrap();
    assert_eq!(
        anim.instances.len(),
        1,
        "the still instance is not animated"
    );
    assert_eq!(anim.instances[0].object, 0);
    let mut mesh = scene.mesh.clone();
    let still: Vec<Vec3> = mesh.positions[3..].to_vec();
    // Hermite with td = 2: translation(s) = 2 h10 (1,0,0) + h01 (0,2,0) + 2 h11 (0,1,0).
    let translation = |s: f32| {
        let h10 = s * s * s - 2.0 * s * s + s;
        let h01 = -2.0 * s * s * s + 3.0 * s * s;
        let h11 = s * s * s - s * s;
        Vec3::new(2.0 * h10, 2.0 * h01 + 2.0 * h11, 0.0)
    };
    assert!(translation(0.5).abs_diff_eq(Vec3::new(0.25, 0.75, 0.0), 1e-7));
    for t in [0.0, 0.5, 1.0, 1.5, 2.0, 3.0] {
        Animation::for_scene(&scene).apply(&mut mesh, t).unwrap();
        let s = t.rem_euclid(2.0) / 2.0;
        let r = Quat::from_rotation_y(FRAC_PI_2 * s);
        for (v, local) in [Vec3::ZERO, Vec3::X, Vec3::Y].into_iter().enumerate() {
            let p = 2.0 * (translation(s) + r * local);
            assert!(
                mesh.positions[v].abs_diff_eq(p, 2e-6),
                "t={t} v={v}: {} vs {p}",
                mesh.positions[v]
            );
            let n = r * Vec3::Z;
            assert!(mesh.normals[v].abs_diff_eq(n, 1e-6), "t={t} v={v} normal");
        }
        assert_eq!(&mesh.positions[3..], &still[..], "t={t}: still instance");
    }
    let mut other = parallax_scene::TriangleMesh::default();
    assert!(anim.apply(&mut other, 0.0).is_err());
}

#[test]
fn scenes_without_gltf_animation_keep_the_rigid_props() {
    let scene = Scene::load("cornell").unwrap();
    assert!(scene.gltf_animation.is_none());
    assert_eq!(Animation::for_scene(&scene).kind(), "rigid");
}

fn expect_invalid(name: &str, b: &GltfBuf, doc: Value, needle: &str) {
    match save_and_load(name, b, doc) {
        Ok(_) => panic!("{name}: loaded but should fail"),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                matches!(e, SceneError::Invalid { .. }),
                "{name}: wrong error kind: {msg}"
            );
            assert!(msg.contains(needle), "{name}: {msg:?} lacks {needle:?}");
        }
    }
}

/// Replaces the data of accessor `acc` by a new float accessor of the same type.
fn replace_floats(b: &mut GltfBuf, doc: &mut Value, path: &[&str], data: &[f32], ty: &str) {
    let a = b.floats(data, ty);
    let mut v = &mut *doc;
    for p in path {
        v = match p.parse::<usize>() {
            Ok(i) => &mut v[i],
            Err(_) => &mut v[*p],
        };
    }
    *v = json!(a);
}

const ATTRS: [&str; 6] = ["meshes", "0", "primitives", "0", "attributes", ""];

fn attr(name: &'static str) -> Vec<&'static str> {
    let mut p = ATTRS[..5].to_vec();
    p.push(name);
    p
}

#[test]
fn malformed_animation_data_is_an_error() {
    // Joint index beyond the skin's two joints.
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let j = b.ints(&[0, 7, 0, 0].repeat(6), 5123, "VEC4", false);
    doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = json!(j);
    expect_invalid("joint", &b, doc, "uses joint 7 but skin 0 has 2 joints");

    // NaN weight.
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let mut w = [1.0f32, 0.0, 0.0, 0.0].repeat(6);
    w[9] = f32::NAN;
    replace_floats(&mut b, &mut doc, &attr("WEIGHTS_0"), &w, "VEC4");
    expect_invalid("nan", &b, doc, "vertex 2 has skin weight NaN");

    // Weights summing to zero cannot be renormalised.
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    replace_floats(&mut b, &mut doc, &attr("WEIGHTS_0"), &[0.0; 24], "VEC4");
    expect_invalid("zero", &b, doc, "summing to 0");

    // Skinned primitive without weights, then without both attributes.
    let (b, mut doc) = strip("LINEAR", Weights::F32);
    let attrs = &mut doc["meshes"][0]["primitives"][0]["attributes"];
    attrs.as_object_mut().unwrap().remove("WEIGHTS_0");
    expect_invalid("noweights", &b, doc.clone(), "must come together");
    let attrs = &mut doc["meshes"][0]["primitives"][0]["attributes"];
    attrs.as_object_mut().unwrap().remove("JOINTS_0");
    expect_invalid("nojoints", &b, doc, "no JOINTS_0 / WEIGHTS_0");

    // Sampler input not increasing.
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let path = ["animations", "0", "samplers", "0", "input"];
    replace_floats(&mut b, &mut doc, &path, &[0.0, 1.0, 1.0], "SCALAR");
    expect_invalid("times", &b, doc, "not greater than the previous");

    // Output count that does not match (CUBICSPLINE needs three per keyframe).
    let (b, mut doc) = strip("LINEAR", Weights::F32);
    doc["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE");
    expect_invalid("count", &b, doc, "3 per keyframe expected");

    // Too few inverse bind matrices.
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let one = glam::Mat4::IDENTITY.to_cols_array();
    replace_floats(
        &mut b,
        &mut doc,
        &["skins", "0", "inverseBindMatrices"],
        &one,
        "MAT4",
    );
    expect_invalid("ibm", &b, doc, "1 inverse bind matrices for 2 joints");

    // Rotation output of the wrong type (VEC3).
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let path = ["animations", "0", "samplers", "0", "output"];
    replace_floats(&mut b, &mut doc, &path, &[0.0; 9], "VEC3");
    expect_invalid("rottype", &b, doc, "output");

    // An animated node given by a matrix.
    let (b, mut doc) = strip("LINEAR", Weights::F32);
    doc["nodes"][2] = json!({"matrix": glam::Mat4::from_translation(Vec3::X).to_cols_array()});
    expect_invalid("matrix", &b, doc, "has a matrix and cannot be animated");

    // Missing accessor bytes for the weights (view shorter than the accessor).
    let (mut b, mut doc) = strip("LINEAR", Weights::F32);
    let w = b.floats(&[1.0, 0.0, 0.0, 0.0], "VEC4");
    b.accessors[w]["count"] = json!(6);
    doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = json!(w);
    expect_invalid("short", &b, doc, "do not fit");
}

/// A skin without animation: the loaded mesh is the skinned rest pose (bone 1 rests turned by
/// 90 degrees), and the scene falls back to the rigid props animation.
#[test]
fn skins_without_clips_load_in_their_rest_pose() {
    let (b, mut doc) = strip("LINEAR", Weights::F32);
    doc.as_object_mut().unwrap().remove("animations");
    doc["nodes"][2]["rotation"] = json!(Quat::from_rotation_z(FRAC_PI_2).to_array());
    let scene = save_and_load("restpose", &b, doc).unwrap();
    for v in 0..6 {
        let (p, n) = expected_vertex(v, FRAC_PI_2);
        assert!(scene.mesh.positions[v].abs_diff_eq(p, 2e-6), "v={v}");
        assert!(scene.mesh.normals[v].abs_diff_eq(n, 2e-6), "v={v} normal");
    }
    assert!(!scene.gltf_animation.as_ref().unwrap().is_animated());
    assert_eq!(Animation::for_scene(&scene).kind(), "rigid");
}

/// Random byte corruptions of the strip's buffer (weights, joints, matrices, keyframes): loading
/// and posing return errors or valid meshes, never panic or produce non-finite vertices.
#[test]
fn corrupted_animation_buffers_never_panic() {
    let mut seed = 0x1234_5678u32;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed
    };
    let (mut errors, mut loaded) = (0, 0);
    for interp in ["LINEAR", "CUBICSPLINE", "STEP"] {
        let (b, doc) = strip(interp, Weights::U8);
        for _ in 0..100 {
            let mut c = GltfBuf {
                bin: b.bin.clone(),
                views: b.views.clone(),
                accessors: b.accessors.clone(),
            };
            for _ in 0..1 + next() % 4 {
                let i = next() as usize % c.bin.len();
                c.bin[i] = next() as u8;
            }
            match save_and_load("corrupt", &c, doc.clone()) {
                Err(_) => errors += 1,
                Ok(scene) => {
                    loaded += 1;
                    let mut mesh = scene.mesh.clone();
                    for t in [0.3, 1.0, 1.7, f32::NAN] {
                        if Animation::for_scene(&scene).apply(&mut mesh, t).is_ok() {
                            assert!(mesh.positions.iter().all(|p| p.is_finite()), "t={t}");
                        }
                    }
                }
            }
        }
    }
    assert!(errors > 0 && loaded > 0, "{errors} errors, {loaded} loaded");
}

/// Channel targets are not checked by gltf-json's validation (the `gltf` crate unwraps them).
#[test]
fn bad_channel_targets_are_parse_errors() {
    for (target, needle) in [
        (
            json!({"node": 9, "path": "rotation"}),
            "targets node 9 but there are 3",
        ),
        (json!({"node": 2, "path": "spin"}), "unknown target path"),
    ] {
        let (b, mut doc) = strip("LINEAR", Weights::F32);
        doc["animations"][0]["channels"][0]["target"] = target;
        match save_and_load("target", &b, doc) {
            Err(SceneError::Parse { message, .. }) => {
                assert!(message.contains(needle), "{message}")
            }
            other => panic!("{other:?}"),
        }
    }
}
