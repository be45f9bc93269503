//! The reference renderer on scenes whose answers are known in closed form.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_render::reference::{RenderOptions, render, render_gbuffer};
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Light, Material, ObjectRange, Scene, TriangleMesh};

/// Appends an axis-aligned box (12 triangles, outward winding) to `mesh`.
fn add_box(mesh: &mut TriangleMesh, min: Vec3, max: Vec3, material: u32) {
    let v0 = mesh.positions.len() as u32;
    let t0 = mesh.indices.len() as u32;
    for i in 0..8 {
        mesh.positions.push(Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        ));
        mesh.normals.push(Vec3::ZERO);
        mesh.uvs.push(Vec2::ZERO);
    }
    // Faces as quads (a, b, c, d) counter-clockwise seen from outside.
    let quads = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    for [a, b, c, d] in quads {
        mesh.indices.push([v0 + a, v0 + b, v0 + c]);
        mesh.indices.push([v0 + a, v0 + c, v0 + d]);
        mesh.material_ids.extend([material, material]);
    }
    mesh.objects.push(ObjectRange {
        name: "box".into(),
        first_triangle: t0,
        triangle_count: 12,
        first_vertex: v0,
        vertex_count: 8,
    });
}

/// A 20 x 20 m floor slab (top at y = 0) and a 2 x 2 m occluder 3 m above it, lit from
/// straight above by a directional light; no environment.
fn shadow_scene() -> Scene {
    let mut mesh = TriangleMesh::default();
    add_box(
        &mut mesh,
        Vec3::new(-10.0, -1.0, -10.0),
        Vec3::new(10.0, 0.0, 10.0),
        0,
    );
    add_box(
        &mut mesh,
        Vec3::new(-1.0, 3.0, -1.0),
        Vec3::new(1.0, 3.2, 1.0),
        0,
    );
    let mut m = Material::diffuse("grey", Vec3::splat(0.5));
    m.roughness = 1.0;
    Scene {
        name: "shadow".into(),
        mesh,
        materials: vec![m],
        lights: vec![Light::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::splat(3.0),
        }],
        ..Scene::default()
    }
}

/// An orthographic camera looking straight down at the floor, 8 m wide view.
fn top_camera(size: u32) -> Camera {
    let desc = CameraDesc::new(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 45.0);
    let opts = CameraOptions {
        ortho_height: Some(8.0),
        ..CameraOptions::default()
    };
    Camera::new(ModelKind::Orthographic, &desc, size, size, &opts).unwrap()
}

#[test]
fn hard_shadow_has_the_occluders_footprint() {
    let scene = shadow_scene();
    let bvh = Bvh::build(&scene.mesh);
    let n = 64u32;
    // The occluder itself is seen from above; render from below it is not possible, so score
    // the floor pixels only: those whose G-buffer depth is the floor's (10 m).
    let cam = top_camera(n);
    let out = render(&scene, &bvh, &cam, &RenderOptions::default(), &|_| {});
    let g = out.gbuffer.unwrap();
    let mut lit = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let i = (y * n + x) as usize;
            let depth = g.depth[i];
            let c = out.image.data()[i].x;
            if (depth - 10.0).abs() < 1e-3 {
                // Floor pixel: it is outside the 2x2 m shadow square (pixels are 8/64 m).
                lit.push(c);
            } else {
                assert!(
                    (depth - 6.8).abs() < 1e-3,
                    "occluder top at 6.8 m, got {depth}"
                );
            }
        }
    }
    // Occluder covers 2x2 m of the 8x8 m view = 1/16 of the pixels, exactly 16x16 pixels.
    assert_eq!(lit.len(), (n * n - 16 * 16) as usize);
    // Every floor pixel is lit (the shadow lies under the occluder, hidden from the camera),
    // with the same radiance, by symmetry of the straight-down sun and view.
    let first = lit[0];
    assert!(first > 0.0);
    assert!(lit.iter().all(|&c| (c - first).abs() < 1e-4 * first));
}

#[test]
fn shadow_seen_from_the_side_is_dark() {
    let scene = shadow_scene();
    let bvh = Bvh::build(&scene.mesh);
    // Look at the floor point under the occluder's centre from the side, below the occluder.
    let desc = CameraDesc::new(Vec3::new(6.0, 1.0, 0.0), Vec3::ZERO, Vec3::Y, 10.0);
    let cam = Camera::new(ModelKind::Pinhole, &desc, 9, 9, &CameraOptions::default()).unwrap();
    let out = render(&scene, &bvh, &cam, &RenderOptions::default(), &|_| {});
    let centre = out.image.get(4, 4).x;
    assert_eq!(
        centre, 0.0,
        "the floor under the occluder receives no light"
    );
    // And a floor point outside the shadow is lit.
    let desc = CameraDesc::new(
        Vec3::new(6.0, 1.0, 0.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::Y,
        10.0,
    );
    let cam = Camera::new(ModelKind::Pinhole, &desc, 9, 9, &CameraOptions::default()).unwrap();
    let out = render(&scene, &bvh, &cam, &RenderOptions::default(), &|_| {});
    assert!(out.image.get(4, 4).x > 0.1);
}

#[test]
fn gbuffer_view_depth_is_distance_along_the_view_axis() {
    // A pinhole camera 5 m above the floor looking straight down: every floor pixel has view
    // depth 5 (not the ray length, which grows towards the corners).
    let scene = shadow_scene();
    let bvh = Bvh::build(&scene.mesh);
    let desc = CameraDesc::new(
        Vec3::new(3.0, 5.0, 3.0),
        Vec3::new(3.0, 0.0, 3.0),
        Vec3::NEG_Z,
        60.0,
    );
    let cam = Camera::new(ModelKind::Pinhole, &desc, 32, 24, &CameraOptions::default()).unwrap();
    let g = render_gbuffer(&scene, &bvh, &cam);
    for (i, &d) in g.depth.iter().enumerate() {
        if g.primitive_id[i] < 12 {
            assert!((d - 5.0).abs() < 1e-4, "pixel {i}: depth {d}");
            assert!((g.normal[i] - Vec3::Y).length() < 1e-5);
            assert!(g.position[i].y.abs() < 1e-4);
        }
    }
    assert!(g.primitive_id.iter().filter(|&&p| p < 12).count() > 32 * 24 / 2);
}

#[test]
fn image_is_identical_for_any_thread_count() {
    let scene = Scene::load("cornell").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let desc = scene.camera(None).unwrap();
    let cam = Camera::new(
        ModelKind::ThinLens,
        &desc,
        40,
        30,
        &CameraOptions::default(),
    )
    .unwrap();
    let opts = RenderOptions {
        spp: 3,
        seed: 9,
        gbuffer: true,
    };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render(&scene, &bvh, &cam, &opts, &|_| {}))
    };
    let (a, b) = (run(1), run(3));
    assert_eq!(a.image, b.image);
    assert_eq!(a.rays, b.rays);
    assert_eq!(a.gbuffer.unwrap().depth, b.gbuffer.unwrap().depth);
}

#[test]
fn open_sky_gives_albedo_times_sky_radiance() {
    // No lights, constant sky 1.0: an unoccluded diffuse floor reflects exactly albedo * sky
    // (every cosine-sampled visibility ray escapes); under a roof it reflects much less.
    let floor_radiance = |roof: bool| {
        let mut mesh = TriangleMesh::default();
        add_box(
            &mut mesh,
            Vec3::new(-10.0, -1.0, -10.0),
            Vec3::new(10.0, 0.0, 10.0),
            0,
        );
        if roof {
            add_box(
                &mut mesh,
                Vec3::new(-4.0, 0.5, -4.0),
                Vec3::new(4.0, 0.6, 4.0),
                0,
            );
        }
        let scene = Scene {
            name: "sky".into(),
            mesh,
            materials: vec![Material::diffuse("grey", Vec3::splat(0.5))],
            environment: Vec3::ONE,
            ..Scene::default()
        };
        let bvh = Bvh::build(&scene.mesh);
        let desc = CameraDesc::new(Vec3::new(3.0, 0.3, 0.0), Vec3::ZERO, Vec3::Y, 1.0);
        let cam = Camera::new(ModelKind::Pinhole, &desc, 3, 3, &CameraOptions::default()).unwrap();
        let opts = RenderOptions {
            spp: 16,
            seed: 3,
            gbuffer: false,
        };
        render(&scene, &bvh, &cam, &opts, &|_| {}).image.get(1, 1).x
    };
    let open = floor_radiance(false);
    assert!((open - 0.5).abs() < 1e-6, "open floor {open}");
    let covered = floor_radiance(true);
    assert!(covered < 0.25, "floor under the roof {covered}");
}
