//! BVH closest / any / all hits equal brute force on the real scene files and on every
//! built-in scene, for random rays inside the bounds and for camera rays.

mod common;

use common::*;
use glam::{Vec2, Vec3};
use parallax_bvh::{BuildOptions, Bvh};
use parallax_core::Ray;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, Pinhole};
use rayon::prelude::*;

/// Random rays with origins inside the bounds, plus a `w x h` grid of rays of the scene's
/// default camera.
fn rays_for(scene: &Scene, random: usize, w: u32, h: u32) -> Vec<Ray> {
    let b = scene.bounds();
    let mut rays = random_rays(random, b.min, b.max, 1234);
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    for y in 0..h {
        for x in 0..w {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            if let Some(cr) = cam.generate_ray(film, Vec2::splat(0.5), 0) {
                rays.push(cr.ray);
            }
        }
    }
    rays
}

/// `check_scene_with` on the object-split build (`spatial_splits: false`, the CLI's
/// `--no-spatial-splits`; the default build is the SBVH, tested by the `_spatial_splits`
/// tests below).
fn check_scene(scene: &Scene, random: usize, w: u32, h: u32) {
    check_scene_with(scene, random, w, h, &object_splits());
}

/// The build with spatial splits (SBVH; the default, spelled out).
fn spatial() -> BuildOptions {
    BuildOptions {
        spatial_splits: true,
        ..Default::default()
    }
}

/// The build without spatial splits (each triangle in exactly one leaf).
fn object_splits() -> BuildOptions {
    BuildOptions {
        spatial_splits: false,
        ..Default::default()
    }
}

/// `check_scene` for a build with `opts`; returns the BVH.
fn check_scene_with(scene: &Scene, random: usize, w: u32, h: u32, opts: &BuildOptions) -> Bvh {
    let mesh = &scene.mesh;
    let bvh = Bvh::build_with(mesh, opts);
    assert_eq!(bvh.triangle_count(), mesh.triangle_count());
    if !opts.spatial_splits {
        assert_eq!(bvh.reference_count(), mesh.triangle_count());
    }
    let rays = rays_for(scene, random, w, h);
    let hits: usize = rays
        .par_iter()
        .map(|r| check_closest(&bvh, mesh, r, &scene.name).is_some() as usize)
        .sum();
    rays.par_iter().step_by(10).for_each(|r| {
        check_all(&bvh, mesh, r, &scene.name);
        // The 4-wide twin: the same hit list, the closest hit at the same `t`.
        let (mut a, mut b) = (Vec::new(), Vec::new());
        bvh.all_hits(r, &mut a);
        bvh.all_hits4(r, &mut b);
        assert_eq!(a, b, "{}: all_hits4 for {r:?}", scene.name);
        let t = |h: Option<parallax_bvh::Hit>| h.map(|h| h.t);
        assert_eq!(
            t(bvh.closest_hit(r)),
            t(bvh.closest_hit4(r)),
            "{}",
            scene.name
        );
        assert_eq!(bvh.any_hit(r), bvh.any_hit4(r), "{}", scene.name);
    });
    if mesh.triangle_count() > 0 {
        assert!(hits > 0, "{}: no ray hit anything", scene.name);
    }
    eprintln!(
        "{}: {} triangles, {} nodes, {:.1} MB, depth {}, build {:.1} ms, {hits}/{} hits",
        scene.name,
        mesh.triangle_count(),
        bvh.node_count(),
        bvh.bytes() as f64 / 1e6,
        bvh.depth(),
        bvh.build_time().as_secs_f64() * 1e3,
        rays.len()
    );
    bvh
}

fn load(rel: &str) -> Scene {
    let path = format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    );
    Scene::load(&path).unwrap_or_else(|e| panic!("loading {path}: {e}"))
}

#[test]
fn sponza_object_splits() {
    check_scene(&load("sponza_dabrovic/sponza_dabrovic.glb"), 200, 12, 9);
}

#[test]
fn japanese_classroom_object_splits() {
    check_scene(
        &load("japanese_classroom/japanese_classroom.glb"),
        200,
        12,
        9,
    );
}

/// The SBVH's closest hit is the object-split tree's, record for record (primitive, `t`, `u`,
/// `v`), for every ray of `rays_for(scene, random, w, h)`: the tie rule does not depend on the
/// tree.
fn same_as_object_split_tree(scene: &Scene, sbvh: &Bvh, random: usize, w: u32, h: u32) {
    let bvh = Bvh::build_with(&scene.mesh, &object_splits());
    let rays = rays_for(scene, random, w, h);
    let hits: usize = rays
        .par_iter()
        .map(|r| {
            let a = sbvh.closest_hit(r);
            assert_eq!(
                a,
                bvh.closest_hit(r),
                "{}: SBVH vs object-split tree for {r:?}",
                scene.name
            );
            a.is_some() as usize
        })
        .sum();
    assert!(hits > rays.len() / 5, "{}: {hits} hits", scene.name);
}

/// Spatial splits: closest / any / all hits still equal brute force (each primitive reported
/// once), on the scenes whose large tilted triangles get split; the closest hits are the
/// object-split tree's. `Bvh::build` builds this tree (the default options).
#[test]
fn sponza_spatial_splits() {
    let scene = load("sponza_dabrovic/sponza_dabrovic.glb");
    let bvh = check_scene_with(&scene, 400, 16, 12, &spatial());
    // The build did split references (Sponza is the scene SBVH is for).
    assert!(bvh.reference_count() > scene.mesh.triangle_count());
    same_as_object_split_tree(&scene, &bvh, 20_000, 160, 120);
    assert_eq!(spatial(), BuildOptions::default());
}

#[test]
fn japanese_classroom_spatial_splits() {
    let scene = load("japanese_classroom/japanese_classroom.glb");
    let bvh = check_scene_with(&scene, 400, 16, 12, &spatial());
    assert!(bvh.reference_count() > scene.mesh.triangle_count());
    same_as_object_split_tree(&scene, &bvh, 20_000, 160, 120);
}

#[test]
fn small_and_builtin_scenes_spatial_splits() {
    check_scene_with(
        &load("stanford_bunny/bun_zipper.ply"),
        600,
        24,
        18,
        &spatial(),
    );
    check_scene_with(
        &load("box_textured/BoxTextured.glb"),
        2000,
        32,
        24,
        &spatial(),
    );
    for name in parallax_scene::builtin::NAMES.iter() {
        let scene = parallax_scene::builtin::by_name(name).unwrap();
        check_scene_with(&scene, 1000, 32, 24, &spatial());
    }
}

#[test]
fn stanford_bunny_object_splits() {
    check_scene(&load("stanford_bunny/bun_zipper.ply"), 600, 24, 18);
}

#[test]
fn box_textured_object_splits() {
    check_scene(&load("box_textured/BoxTextured.glb"), 2000, 32, 24);
}

#[test]
fn builtin_scenes_object_splits() {
    for name in parallax_scene::builtin::NAMES.iter() {
        let scene = parallax_scene::builtin::by_name(name)
            .unwrap_or_else(|| panic!("built-in {name} listed but not found"));
        check_scene(&scene, 1000, 32, 24);
    }
}

/// Rays aimed exactly at the bunny's vertices (where many triangles meet) from a point inside
/// its bounds: the BVH agrees with brute force. (A ray may touch the surface only at a
/// silhouette vertex, where the watertight tie-break may report no hit, so "hit" is not asserted.)
#[test]
fn bunny_rays_through_vertices_match_brute_force() {
    let scene = load("stanford_bunny/bun_zipper.ply");
    let bvh = Bvh::build(&scene.mesh);
    let c = scene.bounds().center() + Vec3::new(0.0, 0.0, 0.3) * scene.bounds().extent();
    let n = scene.mesh.positions.len();
    let hits: usize = (0..n)
        .into_par_iter()
        .step_by(n / 300 + 1)
        .map(|i| {
            let r = Ray::new(c, scene.mesh.positions[i] - c);
            check_closest(&bvh, &scene.mesh, &r, "bunny vertex").is_some() as usize
        })
        .sum();
    assert!(hits > 250, "{hits}");
}
