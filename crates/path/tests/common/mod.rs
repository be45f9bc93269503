//! Scenes and helpers shared by the path tracer's tests.

#![allow(dead_code)]

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_path::{PathOptions, PathOutput, PathTracer};
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Material, Scene, TriangleMesh};

/// A flat-shaded icosphere (no vertex normals) of radius `r` at `c`, `subdiv` times
/// subdivided, outward-facing, material 0.
pub fn icosphere(c: Vec3, r: f32, subdiv: u32) -> TriangleMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut v: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdiv {
        let mut nf = Vec::new();
        for [a, b, cc] in f {
            let mut mid = |i: u32, j: u32| {
                v.push(((v[i as usize] + v[j as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, cc), mid(cc, a));
            nf.extend([[a, ab, ca], [b, bc, ab], [cc, ca, bc], [ab, bc, ca]]);
        }
        f = nf;
    }
    let mut m = TriangleMesh::default();
    m.positions = v.iter().map(|p| c + *p * r).collect();
    m.normals = vec![Vec3::ZERO; m.positions.len()];
    m.uvs = vec![Vec2::ZERO; m.positions.len()];
    m.material_ids = vec![0; f.len()];
    m.indices = f;
    m
}

/// An axis-aligned cube of half-size `h` around the origin with inward-facing faces, flat.
pub fn inward_cube(h: f32) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 != 0 { h } else { -h },
                if i & 2 != 0 { h } else { -h },
                if i & 4 != 0 { h } else { -h },
            )
        })
        .collect();
    // Quads listed outward-wound; the triangles reverse them so that normals point inward.
    let quads = [
        [0, 2, 3, 1], // z = -h, normal +z
        [4, 5, 7, 6], // z = +h, normal -z
        [0, 1, 5, 4], // y = -h, normal +y
        [2, 6, 7, 3], // y = +h, normal -y
        [0, 4, 6, 2], // x = -h, normal +x
        [1, 3, 7, 5], // x = +h, normal -x
    ];
    m.positions = corners;
    m.normals = vec![Vec3::ZERO; 8];
    m.uvs = vec![Vec2::ZERO; 8];
    for q in quads {
        m.indices.push([q[0], q[2], q[1]]);
        m.indices.push([q[0], q[3], q[2]]);
    }
    m.material_ids = vec![0; m.indices.len()];
    m
}

pub fn scene(name: &str, mesh: TriangleMesh, material: Material, env: Vec3) -> Scene {
    let s = Scene {
        name: name.into(),
        mesh,
        materials: vec![material],
        environment: env,
        ..Scene::default()
    };
    s.validate().unwrap();
    s
}

pub fn pinhole(eye: Vec3, target: Vec3, fov: f32, w: u32, h: u32) -> Camera {
    let desc = CameraDesc::new(eye, target, Vec3::Y, fov);
    Camera::new(ModelKind::Pinhole, &desc, w, h, &CameraOptions::default()).unwrap()
}

pub fn render(scene: &Scene, camera: &Camera, opts: PathOptions) -> PathOutput {
    let bvh = Bvh::build(&scene.mesh);
    PathTracer::new(scene, camera, &bvh, opts)
        .unwrap()
        .render(&|_| {})
}

/// Mean over pixels and channels, and its standard error from the per-pixel variances of
/// the mean (pixels are independent: each has its own random streams).
pub fn mean_and_se(out: &PathOutput) -> (f64, f64) {
    let n = out.image.len() as f64 * 3.0;
    let mean = out
        .image
        .data()
        .iter()
        .map(|c| c.element_sum() as f64)
        .sum::<f64>()
        / n;
    let var: f64 = out
        .variance
        .data()
        .iter()
        .map(|v| v.element_sum() as f64)
        .sum();
    (mean, var.sqrt() / n)
}
