//! The packet traversals against single rays: `closest_hit_packet` (8-wide tree, the fastest
//! lanes the CPU has, every supported lane type (`PacketLanes`: AVX2, AVX-512) against the
//! portable twin bit for bit) and `closest_hit_packet4` (4-wide tree, AVX2
//! and portable) return exactly `closest_hit` for every ray (prim, t, u, v bit for bit), for
//! camera rays grouped in 4x4, 4x2 and 3x3 pixel tiles and one pixel's 16 subsamples on the
//! built-in scenes and Sponza (interval culling and the SIMD-over-rays triangle test), for
//! partially filled packets, packets with invalid rays (inactive lanes), packets of incoherent
//! rays (mixed signs and axis permutations), rays through shared vertices from one origin
//! (exact lanes), and slices longer than one packet. `closest_hit_packet64` (64-ray packets of
//! four 16-ray groups, every supported lane type and portable) likewise, on 8x8 pixel tiles of 4x4 groups (edge
//! tiles partial), packets whose groups look in different octants or have zero direction
//! components (the per-group fallback), random rays, rays that miss, and shared-vertex rays.

mod common;

use common::*;
use glam::{Vec2, Vec3};
use parallax_bvh::{BuildOptions, Bvh, Hit, PACKET_SIZE, PACKET64_SIZE, PacketLanes};
use parallax_core::Ray;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, Pinhole};

/// Camera rays of a `w x h` image in `tw x th` tiles, tile after tile (edge tiles partial).
fn tiles(scene: &Scene, w: u32, h: u32, tw: u32, th: u32) -> Vec<Vec<Ray>> {
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let mut out = Vec::new();
    for ty in (0..h).step_by(th as usize) {
        for tx in (0..w).step_by(tw as usize) {
            let mut p = Vec::new();
            for y in ty..(ty + th).min(h) {
                for x in tx..(tx + tw).min(w) {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    if let Some(cr) = cam.generate_ray(film, Vec2::splat(0.5), 0) {
                        p.push(cr.ray);
                    }
                }
            }
            out.push(p);
        }
    }
    out
}

fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
}

/// Asserts packet == single ray for every ray of `packet`; returns the hits.
fn check_packet(bvh: &Bvh, packet: &[Ray], what: &str) -> usize {
    let mut out = vec![
        Some(Hit {
            prim: 7,
            t: 1.0,
            u: 0.0,
            v: 0.0
        });
        packet.len()
    ];
    bvh.closest_hit_packet(packet, &mut out);
    // The portable (SSE / scalar) lanes, the twin of the SIMD ones.
    let mut portable = vec![None; packet.len()];
    bvh.closest_hit_packet_portable(packet, &mut portable);
    // Every lane type the CPU runs (AVX2, AVX-512) against the portable twin, bit for bit.
    for lanes in PacketLanes::supported() {
        let mut simd = vec![None; packet.len()];
        bvh.closest_hit_packet_with(lanes, packet, &mut simd);
        for (i, r) in packet.iter().enumerate() {
            assert_eq!(
                bits(simd[i]),
                bits(portable[i]),
                "{what}, {lanes:?} lanes: {r:?}"
            );
        }
    }
    let mut four = vec![None; packet.len()];
    bvh.closest_hit_packet4(packet, &mut four);
    let mut four_portable = vec![None; packet.len()];
    bvh.closest_hit_packet4_portable(packet, &mut four_portable);
    check_packet64(bvh, packet, what);
    let mut hits = 0;
    for (i, r) in packet.iter().enumerate() {
        let single = bvh.closest_hit(r);
        assert_eq!(bits(out[i]), bits(single), "{what}: {r:?}");
        assert_eq!(bits(portable[i]), bits(single), "{what}, portable: {r:?}");
        assert_eq!(bits(four[i]), bits(single), "{what}, 4-wide: {r:?}");
        assert_eq!(
            bits(four_portable[i]),
            bits(single),
            "{what}, 4-wide portable: {r:?}"
        );
        hits += single.is_some() as usize;
    }
    hits
}

/// Asserts `closest_hit_packet64` (and its portable twin) == single rays for every ray of
/// `rays` (split into packets of 64); returns the hits.
fn check_packet64(bvh: &Bvh, rays: &[Ray], what: &str) -> usize {
    let mut out = vec![None; rays.len()];
    bvh.closest_hit_packet64(rays, &mut out);
    let mut portable = vec![None; rays.len()];
    bvh.closest_hit_packet64_portable(rays, &mut portable);
    for lanes in PacketLanes::supported() {
        let mut simd = vec![None; rays.len()];
        bvh.closest_hit_packet64_with(lanes, rays, &mut simd);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(
                bits(simd[i]),
                bits(portable[i]),
                "{what}, packet64 {lanes:?} lanes, ray {i}: {r:?}"
            );
        }
    }
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let single = bvh.closest_hit(r);
        assert_eq!(
            bits(out[i]),
            bits(single),
            "{what}, packet64 ray {i}: {r:?}"
        );
        assert_eq!(
            bits(portable[i]),
            bits(single),
            "{what}, packet64 portable ray {i}: {r:?}"
        );
        hits += single.is_some() as usize;
    }
    hits
}

/// Camera rays in 8x8 tiles, each as four 4x4 groups of consecutive rays (the order of
/// `closest_hit_packet64`); edge tiles and groups partial.
fn tiles64(scene: &Scene, w: u32, h: u32) -> Vec<Vec<Ray>> {
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let mut out = Vec::new();
    for ty in (0..h).step_by(8) {
        for tx in (0..w).step_by(8) {
            let mut p = Vec::new();
            for (gx, gy) in [(0, 0), (4, 0), (0, 4), (4, 4)] {
                for y in (ty + gy)..(ty + gy + 4).min(h) {
                    for x in (tx + gx)..(tx + gx + 4).min(w) {
                        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        if let Some(cr) = cam.generate_ray(film, Vec2::splat(0.5), 0) {
                            p.push(cr.ray);
                        }
                    }
                }
            }
            out.push(p);
        }
    }
    out
}

/// Each pixel's 16 subsample rays (a 4x4 grid of offsets within the pixel), pixel by pixel.
fn pixel_subsamples(scene: &Scene, w: u32, h: u32) -> Vec<Vec<Ray>> {
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let p: Vec<Ray> = (0..16)
                .filter_map(|k| {
                    let o = Vec2::new((k % 4) as f32 + 0.5, (k / 4) as f32 + 0.5) / 4.0;
                    let film = Vec2::new(x as f32, y as f32) + o;
                    cam.generate_ray(film, Vec2::splat(0.5), 0).map(|c| c.ray)
                })
                .collect();
            out.push(p);
        }
    }
    out
}

/// [`check_scene_bvh`] on the object-split build (`spatial_splits: false`: each triangle in
/// one leaf).
fn check_scene(scene: &Scene, w: u32, h: u32) {
    let opts = BuildOptions {
        spatial_splits: false,
        ..Default::default()
    };
    check_scene_bvh(scene, &Bvh::build_with(&scene.mesh, &opts), w, h);
}

/// [`check_scene`] on a BVH built with spatial splits (the default build; duplicated
/// references).
fn check_scene_spatial(scene: &Scene, w: u32, h: u32) {
    let opts = BuildOptions {
        spatial_splits: true,
        ..Default::default()
    };
    check_scene_bvh(scene, &Bvh::build_with(&scene.mesh, &opts), w, h);
}

fn check_scene_bvh(scene: &Scene, bvh: &Bvh, w: u32, h: u32) {
    let mut hits = 0;
    for (tw, th) in [(4, 4), (4, 2), (3, 3)] {
        for p in tiles(scene, w, h, tw, th) {
            hits += check_packet(bvh, &p, &scene.name);
        }
    }
    for p in pixel_subsamples(scene, w / 2, h / 2) {
        hits += check_packet(bvh, &p, &scene.name);
    }
    assert!(hits > 0, "{}", scene.name);
    let mut hits64 = 0;
    for p in tiles64(scene, w, h) {
        hits64 += check_packet64(bvh, &p, &scene.name);
    }
    // Whole rows of 8x8 tiles in one call (several packets per slice).
    let all: Vec<Ray> = tiles64(scene, w, h).concat();
    assert_eq!(check_packet64(bvh, &all, &scene.name), hits64);
    assert!(hits64 > 0, "{}", scene.name);
}

#[test]
fn builtin_scenes_camera_tiles() {
    for name in parallax_scene::builtin::NAMES.iter() {
        check_scene(&parallax_scene::builtin::by_name(name).unwrap(), 37, 22);
        check_scene_spatial(&parallax_scene::builtin::by_name(name).unwrap(), 37, 22);
    }
}

#[test]
fn sponza_camera_tiles() {
    let path = format!(
        "{}/../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb",
        env!("CARGO_MANIFEST_DIR")
    );
    let scene = Scene::load(&path).unwrap();
    check_scene(&scene, 45, 30);
    check_scene_spatial(&scene, 45, 30);
}

#[test]
fn inactive_lanes_incoherent_rays_and_long_slices() {
    let mesh = soup(3000, 0.08, 4);
    let bvh = Bvh::build(&mesh);
    let mut rays = random_rays(200, Vec3::splat(-1.5), Vec3::splat(1.5), 8);
    // Invalid rays and empty intervals in the middle of packets.
    rays[3] = Ray::new(Vec3::ZERO, Vec3::ZERO);
    rays[17] = Ray::segment(Vec3::ZERO, Vec3::X, 2.0, 1.0);
    rays[18] = Ray::new(Vec3::splat(f32::NAN), Vec3::X);
    rays[40] = Ray::segment(Vec3::splat(-2.0), Vec3::ONE, 0.0, 1.0); // ends before the soup
    // One call over 200 rays (13 packets, the last one partial).
    let hits = check_packet(&bvh, &rays, "soup, all");
    assert!(hits > 50, "{hits}");
    // Every partial size.
    for n in 1..=PACKET_SIZE {
        check_packet(&bvh, &rays[n..2 * n], "soup, partial");
    }
    // Packets of rays through a shared vertex (exact lanes, ties) from many directions.
    let grid = grid(6);
    let bvh = Bvh::build(&grid);
    let mut rng = Rng::new(3);
    for p in &grid.positions {
        let rays: Vec<Ray> = (0..PACKET_SIZE)
            .map(|_| {
                let o = *p + rng.dir() * rng.range(0.5, 2.0);
                Ray::new(o, *p - o)
            })
            .collect();
        check_packet(&bvh, &rays, "grid vertex");
    }
    // One origin, rays at 16 neighbouring vertices (one axis permutation: the SIMD-over-rays
    // triangle test, with exactly-zero edge functions at the vertices).
    let o = Vec3::new(0.1, 3.0, 0.2);
    for chunk in grid.positions.chunks(PACKET_SIZE) {
        let rays: Vec<Ray> = chunk.iter().map(|p| Ray::new(o, *p - o)).collect();
        check_packet(&bvh, &rays, "grid vertices, one origin");
    }
    // An empty BVH and an empty slice.
    let empty = Bvh::build(&mesh_from(Vec::new(), Vec::new()));
    check_packet(&empty, &rays[..5], "empty");
    check_packet(&bvh, &[], "no rays");
}

#[test]
fn packet64_fallbacks_degenerate_and_missing_rays() {
    let mesh = soup(3000, 0.08, 4);
    let bvh = Bvh::build(&mesh);
    // Random rays: incoherent groups (the per-group fallback), every partial length.
    let rays = random_rays(300, Vec3::splat(-1.5), Vec3::splat(1.5), 9);
    assert!(check_packet64(&bvh, &rays, "soup, random") > 50);
    for n in [17, 31, 33, 48, 63, 64, 65] {
        check_packet64(&bvh, &rays[..n], "soup, partial");
    }
    // Coherent 8x8 fans from one origin: through the soup, away from it (all miss), and
    // fans whose four groups look into different octants (per-group fallback).
    let o = Vec3::new(-2.5, 0.1, -0.2);
    let fan = |centre: Vec3, spread: f32, flip: [bool; 4]| -> Vec<Ray> {
        let mut out = Vec::new();
        for (g, f) in flip.iter().enumerate() {
            for k in 0..16 {
                let (x, y) = ((4 * (g % 2) + k % 4) as f32, (4 * (g / 2) + k / 4) as f32);
                let mut d = centre + Vec3::new(0.0, y - 3.5, x - 3.5) * spread;
                if *f {
                    d = -d;
                }
                out.push(Ray::new(o, d));
            }
        }
        out
    };
    for spread in [0.001, 0.02, 0.1] {
        let hits = check_packet64(&bvh, &fan(Vec3::X, spread, [false; 4]), "fan");
        assert!(hits > 0, "{spread}");
        assert_eq!(
            check_packet64(&bvh, &fan(-Vec3::X, spread, [false; 4]), "fan away"),
            0
        );
        check_packet64(
            &bvh,
            &fan(Vec3::X, spread, [false, true, false, false]),
            "octants",
        );
    }
    // Zero and tiny direction components: groups without interval bounds, and rays with
    // infinite `1 / dir` among coherent ones.
    let mut axis = fan(Vec3::X, 0.0, [false; 4]);
    check_packet64(&bvh, &axis, "axis-aligned");
    axis[5].dir = Vec3::new(1.0, 0.0, 1e-30);
    axis[40] = Ray::new(Vec3::ZERO, Vec3::ZERO);
    axis[41] = Ray::segment(o, Vec3::X, 2.0, 1.0);
    check_packet64(&bvh, &axis, "degenerate");
    // Exact lanes: one origin, rays at a grid's vertices, 64 per packet.
    let grid = grid(10);
    let bvh = Bvh::build(&grid);
    let o = Vec3::new(0.1, 3.0, 0.2);
    let rays: Vec<Ray> = grid.positions.iter().map(|p| Ray::new(o, *p - o)).collect();
    assert!(rays.len() > PACKET64_SIZE);
    assert!(check_packet64(&bvh, &rays, "grid vertices, one origin") > 0);
}
