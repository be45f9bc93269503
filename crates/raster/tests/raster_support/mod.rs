//! Shared helpers of the rasterizer tests: scenes, cameras and the BVH ground truth computed
//! directly from camera rays (the render crate's reference renderer sits above this crate).
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, Hit};
use parallax_core::image::GBuffer;
use parallax_core::math::WatertightRay;
use parallax_core::{NO_ID, Ray};
use parallax_raster::View;
use parallax_scene::camera::{Camera, CameraModel};
use parallax_scene::{CameraDesc, Scene};

pub fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// (name, scene, camera pose) for the built-ins and the shared models with their suggested
/// cameras (skipping a model file that is not present).
pub fn scenes(include_real: bool) -> Vec<(String, Scene, CameraDesc)> {
    let mut out = Vec::new();
    for name in ["atrium", "cornell", "foliage"] {
        let s = Scene::load(name).unwrap();
        let d = s.camera(None).unwrap();
        out.push((name.to_string(), s, d));
    }
    if !include_real {
        return out;
    }
    let real = [
        (
            "sponza_dabrovic/sponza_dabrovic.glb",
            [-9.0, 3.5, 0.0],
            [8.0, 5.0, 0.0],
            60.0,
        ),
        (
            "japanese_classroom/japanese_classroom.glb",
            [-1.69, 1.272, 5.887],
            [-1.539, 1.3, 4.898],
            55.0,
        ),
        (
            "stanford_bunny/bun_zipper.ply",
            [-0.017, 0.14, 0.25],
            [-0.017, 0.105, 0.0],
            40.0,
        ),
        (
            "box_textured/BoxTextured.glb",
            [1.2, 1.0, 2.2],
            [0.0, 0.0, 0.0],
            40.0,
        ),
    ];
    for (rel, eye, target, fov) in real {
        let path = shared(rel);
        if !std::path::Path::new(&path).exists() {
            eprintln!("skipping missing {path}");
            continue;
        }
        let s = Scene::load(&path).unwrap();
        let d = CameraDesc::new(Vec3::from(eye), Vec3::from(target), Vec3::Y, fov);
        out.push((rel.to_string(), s, d));
    }
    out
}

/// The ray through the centre of pixel `(x, y)`.
pub fn pixel_ray(camera: &Camera, x: u32, y: u32) -> parallax_scene::camera::CameraRay {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    camera.generate_ray(film, Vec2::splat(0.5), 1).unwrap()
}

/// True when triangle `prim` is hit by some but not all of four rays `eps` pixels around the
/// pixel centre: the centre lies within `eps` of one of its edges.
pub fn near_edge(scene: &Scene, camera: &Camera, x: u32, y: u32, prim: u32, eps: f32) -> bool {
    let [a, b, c] = scene.mesh.triangle(prim as usize);
    let mut hits = 0;
    for o in [
        Vec2::new(eps, 0.0),
        Vec2::new(-eps, 0.0),
        Vec2::new(0.0, eps),
        Vec2::new(0.0, -eps),
    ] {
        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + o;
        let r = camera.generate_ray(film, Vec2::splat(0.5), 1).unwrap().ray;
        if WatertightRay::new(&r).intersect(a, b, c).is_some() {
            hits += 1;
        }
    }
    hits > 0 && hits < 4
}

/// How a rasterized G-buffer compares with BVH primary hits.
#[derive(Debug, Default)]
pub struct Agreement {
    /// Pixels covered by the raster or the BVH.
    pub covered: usize,
    pub same_prim: usize,
    /// Same primitive but view depth off by more than 1e-4 relative.
    pub depth_off: usize,
    /// Worst relative depth error among same-primitive pixels.
    pub max_rel_depth: f32,
    /// Differences (other primitive, or covered by only one) within 0.02 pixel of an edge of
    /// one of the two primitives.
    pub explained: usize,
    /// Differences with neither excuse.
    pub unexplained: usize,
    /// Other primitive at the same depth (within [`TIE_REL`]): both triangles pass through the
    /// pixel-centre point — a shared edge, a crease or coplanar overlapping geometry — so either
    /// answer is right; the BVH's watertight tie-break (decided by float rounding of `t`) and the
    /// rasterizer's top-left rule / `(depth, id)` order may choose differently.
    pub ties: usize,
}

impl Agreement {
    pub fn same_fraction(&self) -> f64 {
        self.same_prim as f64 / self.covered.max(1) as f64
    }

    /// Same primitive, or an exact tie between two that both contain the point.
    pub fn same_surface_fraction(&self) -> f64 {
        (self.same_prim + self.ties) as f64 / self.covered.max(1) as f64
    }
}

/// Relative depth difference below which two different primitives are a tie.
pub const TIE_REL: f32 = 1e-5;

pub fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-6)
}

/// Compares `g` (rasterized with a view of `camera`) with BVH closest hits.
pub fn compare_primary(scene: &Scene, bvh: &Bvh, camera: &Camera, g: &GBuffer) -> Agreement {
    let mut a = Agreement::default();
    for y in 0..g.height() {
        for x in 0..g.width() {
            let cr = pixel_ray(camera, x, y);
            let hit = bvh.closest_hit(&cr.ray);
            let s = g.get(x, y);
            let (bp, bd) = hit.map_or((NO_ID, f32::INFINITY), |h| (h.prim, cr.view_depth(h.t)));
            if bp == NO_ID && s.primitive_id == NO_ID {
                continue;
            }
            a.covered += 1;
            if bp == s.primitive_id {
                a.same_prim += 1;
                let e = rel(bd, s.depth);
                a.max_rel_depth = a.max_rel_depth.max(e);
                if e > 1e-4 {
                    a.depth_off += 1;
                }
                continue;
            }
            let tie = bp != NO_ID && s.primitive_id != NO_ID && rel(bd, s.depth) <= TIE_REL;
            if tie {
                a.ties += 1;
                continue;
            }
            let edge = |p: u32| p != NO_ID && near_edge(scene, camera, x, y, p, 0.02);
            if edge(bp) || edge(s.primitive_id) {
                a.explained += 1;
                if std::env::var("RASTER_DEBUG").is_ok() {
                    eprintln!(
                        "edge diff ({x},{y}): bvh {bp} @ {bd}, raster {} @ {}",
                        s.primitive_id, s.depth
                    );
                }
            } else {
                a.unexplained += 1;
                if a.unexplained < 5 {
                    eprintln!(
                        "unexplained at ({x},{y}): bvh {bp} @ {bd}, raster {} @ {}",
                        s.primitive_id, s.depth
                    );
                }
            }
        }
    }
    a
}

/// BVH all hits through the centre of every pixel (row-major).
pub fn all_hits(bvh: &Bvh, camera: &Camera, w: u32, h: u32) -> Vec<Vec<(Hit, f32)>> {
    let mut out = Vec::with_capacity((w * h) as usize);
    let mut buf = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let cr = pixel_ray(camera, x, y);
            bvh.all_hits(&cr.ray, &mut buf);
            out.push(buf.iter().map(|h| (*h, cr.view_depth(h.t))).collect());
        }
    }
    out
}

/// A pinhole camera of `desc` at `w x h` as a `Camera` and its `View`.
pub fn pinhole(desc: &CameraDesc, w: u32, h: u32) -> (Camera, View) {
    let p = parallax_scene::camera::Pinhole::new(desc, w, h).unwrap();
    let v = View::from_pinhole(&p).unwrap();
    (Camera::Pinhole(p), v)
}

/// A tessellated plane `n x n` quads (two triangles each, alternating diagonals) spanning
/// `[-s, s]^2` at z = `z`.
pub fn grid_mesh(n: u32, s: f32, z: f32) -> parallax_scene::TriangleMesh {
    let mut m = parallax_scene::TriangleMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            // Irregular spacing so edges do not align with pixel centres by construction.
            let fx = i as f32 / n as f32;
            let fy = j as f32 / n as f32;
            let wob = |f: f32, k: u32| {
                if k == 0 || k == n {
                    f
                } else {
                    f + 0.013 * (k as f32 * 1.7).sin() / n as f32
                }
            };
            m.positions.push(Vec3::new(
                (2.0 * wob(fx, i) - 1.0) * s,
                (2.0 * wob(fy, j) - 1.0) * s,
                z,
            ));
            m.normals.push(Vec3::ZERO);
            m.uvs.push(Vec2::new(fx, fy));
        }
    }
    let id = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            if (i + j) % 2 == 0 {
                m.indices.push([a, b, c]);
                m.indices.push([a, c, d]);
            } else {
                m.indices.push([a, b, d]);
                m.indices.push([b, c, d]);
            }
            m.material_ids.extend([0, 0]);
        }
    }
    m
}

/// A scene holding `mesh` with one default material.
pub fn scene_of(mesh: parallax_scene::TriangleMesh) -> Scene {
    let mut s = Scene::load("cornell").unwrap();
    s.mesh = mesh;
    s.materials.truncate(1);
    s.textures.clear();
    s.materials[0].base_color_texture = None;
    s
}

/// `Ray` helper for tests that need one.
pub fn ray(o: Vec3, d: Vec3) -> Ray {
    Ray::new(o, d)
}
