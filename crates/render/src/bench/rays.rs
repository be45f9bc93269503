//! `parallax bench rays`: BVH build time and closest-hit throughput for coherent primary rays
//! and incoherent (diffuse-bounce) rays.
//!
//! Rays are generated up front and only traversal is timed, on all rayon threads; each mode is
//! run `repeats` times and the best run is reported (least disturbed by other processes).

use std::time::Instant;

use glam::Vec2;
use parallax_bvh::{Bvh, BvhError};
use parallax_core::Ray;
use parallax_core::math::Frame;
use parallax_core::sampling::{Rng, warp};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use rayon::prelude::*;
use serde::Serialize;

/// One row of the rays benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct RaysRow {
    /// "primary" (one ray per pixel centre), "primary_packet" (the same rays in 4x4 pixel
    /// tiles, traced with `Bvh::closest_hit_packet`) or "random" (cosine-distributed bounce
    /// rays from the primary hit points).
    pub mode: String,
    pub scene: String,
    pub rays: u64,
    pub build_ms: f64,
    pub trace_ms: f64,
    pub mrays_per_s: f64,
    /// Fraction of rays that hit geometry.
    pub hit_rate: f64,
    pub threads: usize,
}

/// The rays of both modes for `camera`'s view.
pub fn make_rays(bvh: &Bvh, scene: &Scene, camera: &Camera) -> (Vec<Ray>, Vec<Ray>) {
    let (w, h) = (camera.width(), camera.height());
    let primary: Vec<Ray> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).filter_map(move |x| {
                camera
                    .generate_ray(
                        Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                        Vec2::splat(0.5),
                        1,
                    )
                    .map(|r| r.ray)
            })
        })
        .collect();
    let random: Vec<Ray> = primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let hit = bvh.closest_hit(r)?;
            let p = r.at(hit.t);
            let mut n = scene.mesh.geometric_normal(hit.prim as usize);
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let mut rng = Rng::for_pixel(7, i as u32, 0, 0);
            let dir = Frame::from_normal(n).to_world(warp::cosine_hemisphere(rng.next_vec2()));
            let scale = 1e-4 * p.abs().max_element().max(1.0);
            Some(Ray::new(p + n * scale, dir))
        })
        .collect();
    (primary, random)
}

/// Times closest-hit queries over `rays` (best of `repeats`); returns (ms, hits).
pub fn time_closest(bvh: &Bvh, rays: &[Ray], repeats: u32) -> (f64, u64) {
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        hits = rays
            .par_chunks(1024)
            .map(|c| c.iter().filter(|r| bvh.closest_hit(r).is_some()).count() as u64)
            .sum();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    (best, hits)
}

/// The primary rays of [`make_rays`] regrouped into `tile x tile` pixel tiles, tile after tile
/// in scanline order: `(rays, packet lengths)`; a packet holds at most
/// [`parallax_bvh::PACKET_SIZE`] rays (edge tiles and pixels without a ray make it shorter).
pub fn primary_tiles(camera: &Camera, tile: u32) -> (Vec<Ray>, Vec<u32>) {
    let (w, h) = (camera.width(), camera.height());
    let tile = tile.clamp(1, 4);
    let mut rays = Vec::with_capacity((w * h) as usize);
    let mut lens = Vec::new();
    for ty in (0..h).step_by(tile as usize) {
        for tx in (0..w).step_by(tile as usize) {
            let start = rays.len();
            for y in ty..(ty + tile).min(h) {
                for x in tx..(tx + tile).min(w) {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    if let Some(r) = camera.generate_ray(film, Vec2::splat(0.5), 1) {
                        rays.push(r.ray);
                    }
                }
            }
            if rays.len() > start {
                lens.push((rays.len() - start) as u32);
            }
        }
    }
    (rays, lens)
}

/// Times packet closest-hit queries over the tiles of [`primary_tiles`] (best of `repeats`);
/// returns (ms, hits).
pub fn time_closest_packets(bvh: &Bvh, rays: &[Ray], lens: &[u32], repeats: u32) -> (f64, u64) {
    let mut starts = Vec::with_capacity(lens.len());
    let mut s = 0usize;
    for &l in lens {
        starts.push(s);
        s += l as usize;
    }
    let mut best = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        hits = starts
            .par_iter()
            .zip(lens)
            .with_min_len(64)
            .map(|(&s, &l)| {
                let mut out = [None; parallax_bvh::PACKET_SIZE];
                let p = &rays[s..s + l as usize];
                bvh.closest_hit_packet(p, &mut out);
                out[..p.len()].iter().filter(|h| h.is_some()).count() as u64
            })
            .sum();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
    }
    (best, hits)
}

/// Builds the BVH and measures the modes.
pub fn run(scene: &Scene, camera: &Camera, repeats: u32) -> Result<Vec<RaysRow>, BvhError> {
    let t = Instant::now();
    let bvh = Bvh::try_build(&scene.mesh)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let (primary, random) = make_rays(&bvh, scene, camera);
    let (tiled, lens) = primary_tiles(camera, 4);
    let threads = rayon::current_num_threads();
    Ok([
        ("primary", primary, None),
        ("primary_packet", tiled, Some(lens)),
        ("random", random, None),
    ]
    .into_iter()
    .map(|(mode, rays, lens)| {
        let (ms, hits) = match &lens {
            Some(l) => time_closest_packets(&bvh, &rays, l, repeats),
            None => time_closest(&bvh, &rays, repeats),
        };
        RaysRow {
            mode: mode.into(),
            scene: scene.name.clone(),
            rays: rays.len() as u64,
            build_ms,
            trace_ms: ms,
            mrays_per_s: rays.len() as f64 / (ms * 1e3),
            hit_rate: hits as f64 / rays.len().max(1) as f64,
            threads,
        }
    })
    .collect())
}
