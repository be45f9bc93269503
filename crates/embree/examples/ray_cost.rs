//! One traversal method over one ray set, once, on one thread: the harness for instruction and
//! cache-miss counts per ray (`valgrind --tool=callgrind --cache-sim=yes
//! --toggle-collect='*trace_all*'`), parallax's BVH and Embree on the same rays.
//!
//! ```text
//! cargo build --release -p parallax-embree --features embree --example ray_cost
//! target/release/examples/ray_cost SCENE EYE TARGET FOV_Y METHOD MODE [WIDTH HEIGHT]
//!   METHOD: bvh | bvh4 | packet | packet4 | packet64 | embree1 | embree16 | stats (work counters) |
//!           any (`Bvh::any_hit`) | embree_occluded (`rtcOccluded1`) |
//!           build (build times) | treehash (a hash of both trees, the blocks and the prim ids:
//!           equal hashes = the same BVH) | a comma-separated list (interleaved A/B, best of 7)
//!   MODE:   primary (pixel centres, 8x8 tiles of four 4x4 tiles; traced 64 rays at a time) |
//!           random (cosine bounces from the primary hits)
//! e.g. ray_cost ../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb -9,3.5,0 8,5,0 60 bvh primary
//! ```
//!
//! Under valgrind the CPU model has no AVX-512, so both sides run their AVX2 kernels there.

use glam::{Vec2, Vec3};
use parallax_bvh::{BuildOptions, Bvh, TraversalStats};
use parallax_core::Ray;
use parallax_core::math::Frame;
use parallax_core::sampling::{Rng, warp};
use parallax_embree::{EmbreeScene, Options};
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene};

fn v3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("number")).collect();
    Vec3::new(v[0], v[1], v[2])
}

#[inline(never)]
fn trace_all(rays: &[Ray], f: &mut dyn FnMut(&[Ray]) -> usize, chunk: usize) -> usize {
    rays.chunks(chunk).map(f).sum()
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 7 {
        eprintln!("usage: ray_cost SCENE EYE TARGET FOV_Y METHOD MODE [WIDTH HEIGHT]");
        std::process::exit(2);
    }
    let scene = Scene::load(&a[1]).expect("scene");
    let desc = CameraDesc::new(v3(&a[2]), v3(&a[3]), Vec3::Y, a[4].parse().unwrap());
    let (method, mode) = (a[5].as_str(), a[6].as_str());
    let w: u32 = a.get(7).map_or(1280, |s| s.parse().unwrap());
    let h: u32 = a.get(8).map_or(720, |s| s.parse().unwrap());
    // `BVH_SPATIAL=0` builds without spatial splits (the object-split tree; unset or any
    // other value: the default, the SBVH); `BVH_SPLIT_ALPHA`, `BVH_SPLIT_BUDGET`,
    // `BVH_SPLIT_OVERLAP` override their parameters; `BVH_SAH_BLOCK`, `BVH_MAX_LEAF` the SAH's
    // leaf block size and the largest leaf.
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f32>().ok());
    let d = BuildOptions::default();
    let opts = BuildOptions {
        spatial_splits: std::env::var("BVH_SPATIAL").map_or(d.spatial_splits, |v| v != "0"),
        split_alpha: env("BVH_SPLIT_ALPHA").unwrap_or(d.split_alpha),
        split_budget: env("BVH_SPLIT_BUDGET").unwrap_or(d.split_budget),
        split_overlap: env("BVH_SPLIT_OVERLAP").unwrap_or(d.split_overlap),
        sah_block_size: env("BVH_SAH_BLOCK").map_or(d.sah_block_size, |x| x as usize),
        max_leaf_size: env("BVH_MAX_LEAF").map_or(d.max_leaf_size, |x| x as usize),
        ..d
    };
    let bvh = Bvh::build_with(&scene.mesh, &opts);
    let cam = Pinhole::new(&desc, w, h).unwrap();
    let mut rays: Vec<Ray> = Vec::new();
    for ty in (0..h).step_by(8) {
        for tx in (0..w).step_by(8) {
            for (gx, gy) in [(0, 0), (4, 0), (0, 4), (4, 4)] {
                for y in (ty + gy)..(ty + gy + 4).min(h) {
                    for x in (tx + gx)..(tx + gx + 4).min(w) {
                        let f = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        rays.push(cam.generate_ray(f, Vec2::splat(0.5), 1).unwrap().ray);
                    }
                }
            }
        }
    }
    if mode == "random" {
        // The bounce rays of `parallax bench rays` (render::bench::rays::bounce_rays).
        rays = rays
            .iter()
            .enumerate()
            .filter_map(|(i, r)| {
                let hit = bvh.closest_hit(r)?;
                let p = r.at(hit.t);
                let mut n = scene.mesh.geometric_normal(hit.prim as usize);
                if n.dot(r.dir) > 0.0 {
                    n = -n;
                }
                let mut rng = Rng::for_pixel(7, i as u32, 0, 0);
                let d = Frame::from_normal(n).to_world(warp::cosine_hemisphere(rng.next_vec2()));
                Some(Ray::new(p + n * 1e-4 * p.abs().max_element().max(1.0), d))
            })
            .collect();
    }
    if method == "build" {
        // Builds interleaved, best of 5 wall times (all threads).
        let (mut ours, mut theirs) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..5 {
            let t = std::time::Instant::now();
            std::hint::black_box(Bvh::build_with(&scene.mesh, &opts));
            ours = ours.min(t.elapsed().as_secs_f64() * 1e3);
            let t = std::time::Instant::now();
            std::hint::black_box(EmbreeScene::new(&scene.mesh, Options::default()).unwrap());
            theirs = theirs.min(t.elapsed().as_secs_f64() * 1e3);
        }
        println!("build: parallax {ours:.1} ms, Embree high {theirs:.1} ms (best of 5)");
        return;
    }
    if method == "treehash" {
        use std::hash::{Hash, Hasher};
        // Debug formatting prints every f32 exactly (shortest round-trip form).
        let mut h = std::collections::hash_map::DefaultHasher::new();
        format!("{:?}", bvh.nodes()).hash(&mut h);
        format!("{:?}", bvh.nodes8()).hash(&mut h);
        format!("{:?}", bvh.blocks()).hash(&mut h);
        format!("{:?}", bvh.triangles()).hash(&mut h);
        bvh.prim_ids().hash(&mut h);
        println!(
            "tree: {} references, {} nodes4, {} nodes8, {} blocks, depth {}, hash {:016x}",
            bvh.reference_count(),
            bvh.node_count(),
            bvh.nodes8().len(),
            bvh.blocks().len(),
            bvh.depth(),
            h.finish()
        );
        return;
    }
    if method == "stats" {
        let (mut s8, mut s4) = (TraversalStats::default(), TraversalStats::default());
        for r in &rays {
            bvh.closest_hit_with_stats(r, &mut s8);
            bvh.closest_hit4_with_stats(r, &mut s4);
        }
        for (name, s) in [("8-wide", s8), ("4-wide", s4)] {
            println!(
                "{name}: per ray {:.2} nodes, {:.2} boxes, {:.2} leaves, {:.2} triangles",
                s.per_ray(s.nodes_visited),
                s.per_ray(s.box_tests),
                s.per_ray(s.leaves_visited),
                s.per_ray(s.triangle_tests)
            );
        }
        return;
    }
    let emb = EmbreeScene::new(&scene.mesh, Options::default()).expect("embree");
    if method.contains(',') {
        // Interleaved rounds of several methods, best thread-CPU time each (robust to load).
        let methods: Vec<&str> = method.split(',').collect();
        let mut best = vec![u64::MAX; methods.len()];
        for _ in 0..7 {
            for (m, b) in methods.iter().zip(&mut best) {
                let mut f = tracer(m, &bvh, &emb);
                let c0 = parallax_core::cpu_time::thread_cpu_ns().unwrap();
                std::hint::black_box(trace_all(&rays, &mut *f, 64));
                *b = (*b).min(parallax_core::cpu_time::thread_cpu_ns().unwrap() - c0);
            }
        }
        for (m, b) in methods.iter().zip(&best) {
            let mr = rays.len() as f64 / (*b as f64 * 1e-3);
            println!(
                "{mode:8} {m:10} {:8.1} ms {mr:6.2} Mrays/s (1 thread, best of 7)",
                *b as f64 * 1e-6
            );
        }
        return;
    }
    let mut f = tracer(method, &bvh, &emb);
    let hits = trace_all(&rays, &mut *f, 64);
    println!("{method} {mode}: {} rays, {hits} hits", rays.len());
}

/// A tracer over one chunk of rays, returning the hits.
type Tracer<'a> = Box<dyn FnMut(&[Ray]) -> usize + 'a>;

/// The tracer of `method` over one chunk of at most 64 rays; returns the hits.
fn tracer<'a>(method: &str, bvh: &'a Bvh, e: &'a EmbreeScene) -> Tracer<'a> {
    let mut hb = vec![None; 64];
    let mut he = vec![None; 64];
    match method {
        "bvh" => Box::new(|c| c.iter().filter(|r| bvh.closest_hit(r).is_some()).count()),
        "bvh4" => Box::new(|c| c.iter().filter(|r| bvh.closest_hit4(r).is_some()).count()),
        "packet" => Box::new(move |c| {
            bvh.closest_hit_packet(c, &mut hb);
            hb[..c.len()].iter().filter(|h| h.is_some()).count()
        }),
        "packet64" => Box::new(move |c| {
            bvh.closest_hit_packet64(c, &mut hb);
            hb[..c.len()].iter().filter(|h| h.is_some()).count()
        }),
        "packet4" => Box::new(move |c| {
            bvh.closest_hit_packet4(c, &mut hb);
            hb[..c.len()].iter().filter(|h| h.is_some()).count()
        }),
        "embree1" => Box::new(move |c| {
            e.closest_hits(c, &mut he);
            he[..c.len()].iter().filter(|h| h.is_some()).count()
        }),
        "any" => Box::new(|c| c.iter().filter(|r| bvh.any_hit(r)).count()),
        "embree_occluded" => {
            let mut occ = vec![false; 64];
            Box::new(move |c| {
                e.occluded(c, &mut occ);
                occ[..c.len()].iter().filter(|&&o| o).count()
            })
        }
        "embree16" => Box::new(move |c| {
            e.closest_hit_packets(c, 16, &mut he);
            he[..c.len()].iter().filter(|h| h.is_some()).count()
        }),
        m => panic!("unknown method {m}"),
    }
}
