//! HVVR §5.2 with a skinned character: a glTF tube skinned to a three-bone chain (linear blend
//! skinning, glTF 2.0 spec §3.7.3) bends over time above a static floor; after each pose the
//! refitted BVH answers every closest-hit query like a fresh build of the posed mesh (and like
//! brute force).

mod common;
#[path = "../../scene/tests/common/gltf_build.rs"]
mod gltf_build;

use std::f32::consts::TAU;

use common::*;
use glam::{Mat4, Quat, Vec3};
use gltf_build::{GltfBuf, tmp_dir, write};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_scene::animation::Animation;
use parallax_scene::{Scene, TriangleMesh};
use serde_json::json;

const RINGS: u32 = 31;
const SEGMENTS: u32 = 24;

/// A tube of radius 0.3 along +X from 0 to 3 (RINGS rings of SEGMENTS vertices), each vertex
/// weighted between the two bones nearest its x (bones at x = 0, 1, 2); bone 1 swings about +Z
/// (LINEAR, 0 -> 60 -> 0 degrees over 2 s), bone 2 about +Y (CUBICSPLINE, 0 -> -45 -> 0); a
/// static floor quad at y = -1.
fn skinned_tube() -> String {
    let mut b = GltfBuf::default();
    let (mut pos, mut nrm, mut joints, mut weights) = (vec![], vec![], vec![], vec![]);
    for r in 0..RINGS {
        let x = 3.0 * r as f32 / (RINGS - 1) as f32;
        let i = (x.floor() as u32).min(2);
        let f = (x - i as f32).clamp(0.0, 1.0);
        for s in 0..SEGMENTS {
            let a = TAU * s as f32 / SEGMENTS as f32;
            let n = Vec3::new(0.0, a.cos(), a.sin());
            pos.extend((Vec3::X * x + 0.3 * n).to_array());
            nrm.extend(n.to_array());
            let next = (i + 1).min(2);
            joints.extend([i, next, 0, 0]);
            weights.extend(if next == i {
                [1.0, 0.0, 0.0, 0.0]
            } else {
                [1.0 - f, f, 0.0, 0.0]
            });
        }
    }
    let mut idx = vec![];
    for r in 0..RINGS - 1 {
        for s in 0..SEGMENTS {
            let v = |r: u32, s: u32| r * SEGMENTS + s % SEGMENTS;
            idx.extend([v(r, s), v(r, s + 1), v(r + 1, s)]);
            idx.extend([v(r, s + 1), v(r + 1, s + 1), v(r + 1, s)]);
        }
    }
    let p = b.floats(&pos, "VEC3");
    let n = b.floats(&nrm, "VEC3");
    let j = b.ints(&joints, 5121, "VEC4", false);
    let w = b.floats(&weights, "VEC4");
    let ix = b.ints(&idx, 5123, "SCALAR", false);
    let floor = b.floats(
        &[-2., -1., -2., 5., -1., -2., 5., -1., 2., -2., -1., 2.],
        "VEC3",
    );
    let floor_ix = b.ints(&[0, 2, 1, 0, 3, 2], 5123, "SCALAR", false);
    let ibm: Vec<f32> = (0..3)
        .flat_map(|i| Mat4::from_translation(-Vec3::X * i as f32).to_cols_array())
        .collect();
    let ibm = b.floats(&ibm, "MAT4");
    let times = b.floats(&[0.0, 1.0, 2.0], "SCALAR");
    let q = |axis: Vec3, deg: f32| Quat::from_axis_angle(axis, deg.to_radians()).to_array();
    let swing: Vec<f32> = [q(Vec3::Z, 0.0), q(Vec3::Z, 60.0), q(Vec3::Z, 0.0)].concat();
    let swing = b.floats(&swing, "VEC4");
    let z = [0.0f32; 4];
    let twist: Vec<f32> = [0.0, -45.0, 0.0]
        .into_iter()
        .flat_map(|d| [z, q(Vec3::Y, d), z])
        .flatten()
        .collect();
    let twist = b.floats(&twist, "VEC4");
    b.finish(json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 4]}],
        "nodes": [
            {"name": "tube", "mesh": 0, "skin": 0},
            {"name": "bone0", "children": [2]},
            {"name": "bone1", "translation": [1, 0, 0], "children": [3]},
            {"name": "bone2", "translation": [1, 0, 0]},
            {"name": "floor", "mesh": 1}
        ],
        "meshes": [
            {"name": "tube", "primitives": [{"attributes":
                {"POSITION": p, "NORMAL": n, "JOINTS_0": j, "WEIGHTS_0": w}, "indices": ix}]},
            {"name": "floor", "primitives": [{"attributes": {"POSITION": floor}, "indices": floor_ix}]}
        ],
        "skins": [{"joints": [1, 2, 3], "inverseBindMatrices": ibm}],
        "animations": [{"name": "wave",
            "samplers": [
                {"input": times, "output": swing},
                {"input": times, "output": twist, "interpolation": "CUBICSPLINE"}
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 2, "path": "rotation"}},
                {"sampler": 1, "target": {"node": 3, "path": "rotation"}}
            ]}]
    }))
}

/// Rays from in front and above aimed into the tube's swept region, plus random rays.
fn rays(mesh: &TriangleMesh, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    let mut out: Vec<Ray> = (0..1500)
        .map(|_| {
            let o = rng.vec3_in(Vec3::new(-1.0, -0.5, 4.0), Vec3::new(4.0, 3.0, 5.0));
            let target = rng.vec3_in(Vec3::new(0.0, -0.5, -1.0), Vec3::new(3.0, 2.5, 1.0));
            Ray::new(o, (target - o).normalize())
        })
        .collect();
    let b = mesh.bounds();
    out.extend(random_rays(500, b.min, b.max, seed + 1));
    out
}

#[test]
fn skinned_tube_refits_like_a_fresh_build() {
    let folder = tmp_dir("bvh-refit-skin");
    let d = folder.path();
    let scene = Scene::load(write(d, "tube.gltf", &skinned_tube()).to_str().unwrap()).unwrap();
    let anim = Animation::for_scene(&scene);
    assert_eq!(anim.kind(), "gltf");
    assert_eq!(
        anim.moving_vertices(&scene.mesh),
        (RINGS * SEGMENTS) as usize
    );
    let mut mesh = scene.mesh.clone();
    let mut bvh = Bvh::build(&mesh);
    for (k, t) in [0.5f32, 1.0, 1.37, 2.9].into_iter().enumerate() {
        anim.apply(&mut mesh, t).unwrap();
        let moved = mesh
            .positions
            .iter()
            .zip(&scene.mesh.positions)
            .filter(|(a, b)| (**a - **b).length() > 1e-3)
            .count();
        assert!(moved > 300, "t={t}: only {moved} vertices moved");
        bvh.refit(&mesh).unwrap();
        let fresh = Bvh::build(&mesh);
        assert_eq!(bvh.bounds(), fresh.bounds(), "t={t}: root bounds");
        let rays = rays(&mesh, k as u64);
        let mut hits = 0;
        for (i, r) in rays.iter().enumerate() {
            let a = check_closest(&bvh, &mesh, r, &format!("t={t} ray {i} (refit vs brute)"));
            let b = fresh.closest_hit(r);
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert!(
                        a.prim == b.prim || (a.t - b.t).abs() <= 1e-5 * a.t.max(b.t).max(1.0),
                        "t={t} ray {i}: refit {a:?} vs fresh {b:?}"
                    );
                    hits += 1;
                }
                _ => panic!("t={t} ray {i}: refit {a:?} vs fresh {b:?}"),
            }
        }
        assert!(
            hits > rays.len() / 4,
            "t={t}: {hits} hits of {}",
            rays.len()
        );
    }
}
