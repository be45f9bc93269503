//! Rasterized G-buffers against the BVH ground truth, exact coverage, determinism, pixel-centre
//! alignment of the views and robustness to hostile input.

mod raster_support;

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::NO_ID;
use parallax_raster::{RasterError, RasterOptions, View, capture_gbuffer, capture_layers};
use parallax_scene::camera::{Camera, CameraModel, CubeMap, Eye, Orthographic, Pinhole, StereoRig};
use parallax_scene::{CameraDesc, TriangleMesh};
use raster_support::*;

fn check(name: &str, scene: &parallax_scene::Scene, bvh: &Bvh, cam: &Camera, view: &View) {
    let cap = capture_gbuffer(scene, view).unwrap();
    let a = compare_primary(scene, bvh, cam, cap.gbuffer());
    eprintln!(
        "{name}: {a:?} same {:.5} same surface {:.5}",
        a.same_fraction(),
        a.same_surface_fraction()
    );
    // (A cube face may look out of an open scene and see nothing.)
    assert!(
        a.covered > 0 || name.contains("cube"),
        "{name}: nothing covered"
    );
    if a.covered == 0 {
        assert_eq!(cap.gbuffer().hit_count(), 0);
        return;
    }
    assert!(a.same_surface_fraction() >= 0.999, "{name}: {a:?}");
    assert_eq!(a.depth_off, 0, "{name}: depth beyond 1e-4 relative: {a:?}");
    assert_eq!(
        a.unexplained, 0,
        "{name}: differences away from edges: {a:?}"
    );
    assert_eq!(cap.bytes(), cap.stats.bytes);
    assert_eq!(cap.bytes(), (view.width * view.height) as usize * 56);
}

#[test]
fn layer0_matches_bvh_pinhole_on_all_scenes() {
    for (name, scene, desc) in scenes(true) {
        let bvh = Bvh::build(&scene.mesh);
        let (cam, view) = pinhole(&desc, 160, 90);
        check(&name, &scene, &bvh, &cam, &view);
    }
}

#[test]
fn layer0_matches_bvh_stereo_ortho_offaxis() {
    for (name, scene, desc) in scenes(false) {
        let bvh = Bvh::build(&scene.mesh);
        let rig = StereoRig::new(&desc, 96, 64, 0.3).unwrap();
        let eye = rig.eye(Eye::Right).clone();
        let view = View::from_pinhole(&eye).unwrap();
        check(
            &format!("{name} right eye"),
            &scene,
            &bvh,
            &Camera::Pinhole(eye),
            &view,
        );

        let off = Pinhole::new(&desc, 96, 64)
            .unwrap()
            .with_shift(Vec2::new(0.3, -0.2));
        let view = View::from_pinhole(&off).unwrap();
        check(
            &format!("{name} off-axis"),
            &scene,
            &bvh,
            &Camera::Pinhole(off),
            &view,
        );

        let o = Orthographic::new(&desc, 96, 64, None).unwrap();
        let view = View::from_orthographic(&o).unwrap();
        check(
            &format!("{name} ortho"),
            &scene,
            &bvh,
            &Camera::Orthographic(o),
            &view,
        );

        // A generic centre: from the built-ins' round-numbered eyes, 90-degree faces put
        // silhouette edges exactly through rows of pixel centres (atrium face 5: 18 of 2084
        // pixels decided by the tie-breaks, which differ between the two).
        let mut cdesc = desc;
        cdesc.eye += Vec3::new(0.0123, 0.0071, -0.0093);
        cdesc.target += Vec3::new(0.0123, 0.0071, -0.0093);
        let cube = CubeMap::new(&cdesc, 48).unwrap();
        for i in [0, 3, 5] {
            let f = cube.face_camera(i);
            let view = View::cube_face(&cube, i).unwrap();
            check(
                &format!("{name} cube face {i}"),
                &scene,
                &bvh,
                &Camera::Pinhole(f),
                &view,
            );
        }
    }
}

#[test]
fn pixel_centres_coincide_with_camera_rays() {
    let desc = CameraDesc::new(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(0.2, 1.1, -1.0),
        Vec3::Y,
        50.0,
    );
    let p = Pinhole::new(&desc, 64, 48)
        .unwrap()
        .with_shift(Vec2::new(0.25, -0.1));
    let o = Orthographic::new(&desc, 64, 48, Some(3.0)).unwrap();
    let cube = CubeMap::new(&desc, 32).unwrap();
    let mut cams: Vec<(Camera, View)> = vec![
        (Camera::Pinhole(p.clone()), View::from_pinhole(&p).unwrap()),
        (
            Camera::Orthographic(o.clone()),
            View::from_orthographic(&o).unwrap(),
        ),
    ];
    for i in 0..6 {
        cams.push((
            Camera::Pinhole(cube.face_camera(i)),
            View::cube_face(&cube, i).unwrap(),
        ));
    }
    let mut worst = 0.0f32;
    for (cam, view) in &cams {
        for (x, y) in [
            (0, 0),
            (5, 7),
            (31, 20),
            (cam.width() - 1, cam.height() - 1),
        ] {
            let cr = pixel_ray(cam, x, y);
            for t in [0.5, 3.7, 40.0] {
                let q = cr.ray.at(t);
                let f = view.project(q).unwrap();
                let err = (f - Vec2::new(x as f32 + 0.5, y as f32 + 0.5)).length();
                worst = worst.max(err);
                assert!(err < 2e-3, "{:?} ({x},{y}) t {t}: {f}", cam.kind());
                let d = view.view_depth(q) as f32;
                assert!(
                    rel(d, cr.view_depth(t)) < 1e-5,
                    "{d} vs {}",
                    cr.view_depth(t)
                );
            }
        }
    }
    eprintln!("worst pixel-centre offset {worst} px");
}

/// A tessellated plane filling the view: every pixel covered exactly once (two layers: the
/// second must stay empty, the first full).
#[test]
fn shared_edges_cover_every_pixel_exactly_once() {
    let scene = scene_of(grid_mesh(23, 5.0, -2.0));
    let desc = CameraDesc::new(
        Vec3::new(0.1, -0.05, 0.0),
        Vec3::new(0.1, -0.05, -1.0),
        Vec3::Y,
        60.0,
    );
    for (w, h) in [(160, 90), (97, 61)] {
        let (_, view) = pinhole(&desc, w, h);
        let cap = capture_layers(&scene, &view, &RasterOptions::layers(2)).unwrap();
        assert_eq!(cap.layers.layer(0).hit_count(), (w * h) as usize);
        assert_eq!(cap.layers.layer(1).hit_count(), 0, "a pixel covered twice");
    }
    // The same through an orthographic view, and a cube face (mirrored frame).
    let o = Orthographic::new(&desc, 80, 60, Some(2.0)).unwrap();
    let cap = capture_layers(
        &scene,
        &View::from_orthographic(&o).unwrap(),
        &RasterOptions::layers(2),
    )
    .unwrap();
    assert_eq!(cap.layers.layer(0).hit_count(), 80 * 60);
    assert_eq!(cap.layers.layer(1).hit_count(), 0);
    let cube = CubeMap::new(&desc, 40).unwrap();
    let cap = capture_layers(
        &scene,
        &View::cube_face(&cube, 5).unwrap(),
        &RasterOptions::layers(2),
    )
    .unwrap();
    assert_eq!(cap.layers.layer(0).hit_count(), 40 * 40);
    assert_eq!(cap.layers.layer(1).hit_count(), 0);
}

#[test]
fn one_and_two_threads_give_identical_captures() {
    let scene = parallax_scene::Scene::load("foliage").unwrap();
    let desc = scene.camera(None).unwrap();
    let (_, view) = pinhole(&desc, 120, 80);
    let opts = RasterOptions::layers(3);
    let run = |n: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap();
        pool.install(|| capture_layers(&scene, &view, &opts).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert!(a.layers.layer(0).hit_count() > 0);
    assert_eq!(a.layers, b.layers);
}

#[test]
fn hostile_geometry_does_not_panic() {
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
    let (_, view) = pinhole(&desc, 64, 48);
    let mut m = TriangleMesh::default();
    let tris: [[Vec3; 3]; 7] = [
        // Degenerate: a point and a line.
        [Vec3::new(0.0, 0.0, -1.0); 3],
        [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(2.0, 0.0, -1.0),
        ],
        // Entirely behind the camera.
        [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
        ],
        // Straddling the eye plane.
        [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(1.0, -1.0, -3.0),
            Vec3::new(0.0, 1.0, -3.0),
        ],
        // Huge.
        [
            Vec3::new(-1e7, -1e7, -5.0),
            Vec3::new(1e7, -1e7, -5.0),
            Vec3::new(0.0, 1e7, -5.0),
        ],
        // Extreme but finite coordinates.
        [
            Vec3::new(-3e38, 0.0, -1.0),
            Vec3::new(3e38, 1e30, -1e-30),
            Vec3::new(0.0, -3e38, 3e38),
        ],
        // Through the eye itself.
        [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
        ],
    ];
    for t in tris {
        let b = m.positions.len() as u32;
        m.positions.extend(t);
        m.normals.extend([Vec3::ZERO; 3]);
        m.uvs.extend([Vec2::ZERO; 3]);
        m.indices.push([b, b + 1, b + 2]);
        m.material_ids.push(0);
    }
    let scene = scene_of(m);
    let cap = capture_layers(&scene, &view, &RasterOptions::layers(4)).unwrap();
    let g = cap.gbuffer();
    // The huge triangle at depth 5 covers the whole view.
    assert_eq!(g.hit_count(), 64 * 48);
    for i in 0..g.len() {
        assert!(g.depth[i] > 0.0 && g.position[i].is_finite() && g.normal[i].is_finite());
    }
    let s = cap.stats.raster;
    assert!(s.culled >= 3 && s.clipped >= 2, "{s:?}");

    // Out-of-range indices are an error, not a panic.
    let mut bad = scene.mesh.clone();
    bad.indices.push([0, 1, 999]);
    bad.material_ids.push(0);
    assert!(matches!(
        parallax_raster::rasterize(&bad, &view, &RasterOptions::default(), None),
        Err(RasterError::InvalidMesh(_))
    ));
}

#[test]
fn invalid_views_and_options_are_errors() {
    let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
    let frame = parallax_scene::camera::CameraFrame::look_at(&desc).unwrap();
    for (w, h) in [(0, 10), (10, 0), (0, 0)] {
        let p = Pinhole::from_frame(frame, w, h, 0.5);
        assert!(matches!(View::from_pinhole(&p), Err(RasterError::Size(_))));
    }
    let p = Pinhole::from_frame(frame, 10, 10, f32::NAN);
    assert!(View::from_pinhole(&p).is_err());
    let (_, view) = pinhole(&desc, 16, 16);
    assert!(view.clone().with_depth_range(0.0, 10.0).is_err());
    assert!(view.clone().with_depth_range(2.0, 1.0).is_err());
    let scene = scene_of(grid_mesh(2, 1.0, -1.0));
    for opts in [
        RasterOptions::layers(0),
        RasterOptions::layers(65),
        RasterOptions {
            min_separation: -1.0,
            ..RasterOptions::default()
        },
        RasterOptions {
            min_separation: f32::NAN,
            ..RasterOptions::default()
        },
    ] {
        assert!(capture_layers(&scene, &view, &opts).is_err(), "{opts:?}");
    }
    let fisheye = Camera::new(
        parallax_scene::camera::ModelKind::Fisheye,
        &desc,
        16,
        16,
        &Default::default(),
    )
    .unwrap();
    assert!(View::views_of(&fisheye).is_err());
}

#[test]
fn near_and_far_planes_clip() {
    let scene = scene_of(grid_mesh(4, 50.0, -2.0));
    // A tilted view of the plane: depth grows towards the top of the image.
    let desc = CameraDesc::new(
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.5, -2.0),
        Vec3::Y,
        70.0,
    );
    let (_, view) = pinhole(&desc, 64, 48);
    let full = capture_gbuffer(&scene, &view).unwrap();
    let clipped =
        capture_gbuffer(&scene, &view.clone().with_depth_range(1.5, 3.0).unwrap()).unwrap();
    let (g, c) = (full.gbuffer(), clipped.gbuffer());
    let mut kept = 0;
    for i in 0..g.len() {
        let d = g.depth[i];
        if c.primitive_id[i] != NO_ID {
            kept += 1;
            assert!(c.depth[i] >= 1.5 * (1.0 - 1e-3) && c.depth[i] <= 3.0 * (1.0 + 1e-3));
        } else if d.is_finite() {
            // Dropped pixels lie outside the range (up to the snapping of the clipped edge).
            assert!(!(1.52..=2.98).contains(&d), "pixel {i} at depth {d} lost");
        }
    }
    assert!(kept > 0 && kept < g.hit_count());
}
