//! Release measurement of build time and ray throughput on a scene:
//!
//! ```text
//! cargo run --release -p parallax-bvh --example bvh_throughput -- [scene] [threads] [coherent|random]
//! ```
//!
//! Prints build ms, refit ms, and closest-hit / any-hit Mrays/s for coherent (camera grid) and
//! incoherent (random origins in the bounds, random directions) rays, single-threaded and on a
//! rayon pool of `threads` threads (default 2).

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, TraversalStats};
use parallax_core::Ray;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, Pinhole};
use rayon::prelude::*;

fn camera_rays(scene: &Scene, w: u32, h: u32) -> Vec<Ray> {
    let cam = Pinhole::new(&scene.camera(None).expect("camera"), w, h).expect("pinhole");
    let mut rays = Vec::with_capacity((w * h) as usize);
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

fn random_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let b = scene.bounds();
    let mut s = 0x1234_5678u32;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let o = b.min + Vec3::new(rnd(), rnd(), rnd()) * b.extent();
            let z = 2.0 * rnd() - 1.0;
            let phi = std::f32::consts::TAU * rnd();
            let r = (1.0 - z * z).sqrt();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

// Nanoseconds this thread has run on a CPU, so that a single-threaded measurement on a loaded
// machine is not diluted by other processes.
use parallax_core::cpu_time::thread_cpu_ns;

/// Best of `reps` runs, in Mrays/s of wall time and (single-threaded) of this thread's CPU time.
fn mrays(rays: &[Ray], reps: usize, f: impl Fn(&[Ray]) -> usize) -> (f64, usize, f64) {
    let mut best = f64::INFINITY;
    let mut best_cpu = f64::INFINITY;
    let mut hits = 0;
    for _ in 0..reps {
        let c = thread_cpu_ns();
        let t = Instant::now();
        hits = f(rays);
        best = best.min(t.elapsed().as_secs_f64());
        if let (Some(c0), Some(c1)) = (c, thread_cpu_ns()) {
            best_cpu = best_cpu.min((c1 - c0) as f64 * 1e-9);
        }
    }
    let n = rays.len() as f64 / 1e6;
    (n / best, hits, n / best_cpu)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let default = format!(
        "{}/../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb",
        env!("CARGO_MANIFEST_DIR")
    );
    let path = args
        .get(1)
        .filter(|s| !s.is_empty())
        .cloned()
        .unwrap_or(default);
    let threads: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2);
    let scene = Scene::load(&path).expect("scene");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();

    let mut builds = Vec::new();
    let mut bvh = None;
    for _ in 0..5 {
        let b = pool.install(|| Bvh::build(&scene.mesh));
        builds.push(b.build_time().as_secs_f64() * 1e3);
        bvh = Some(b);
    }
    let mut bvh = bvh.unwrap();
    let refit = pool
        .install(|| bvh.refit(&scene.mesh).unwrap())
        .as_secs_f64()
        * 1e3;
    builds.sort_by(f64::total_cmp);
    println!(
        "{}: {} triangles, {} nodes ({:.1} MB), depth {}; build {:.1} ms (median of 5, {threads} threads), refit {:.2} ms",
        scene.name,
        scene.mesh.triangle_count(),
        bvh.node_count(),
        bvh.bytes() as f64 / 1e6,
        bvh.depth(),
        builds[2],
        refit
    );

    let sets = [
        ("coherent 1024x768", camera_rays(&scene, 1024, 768)),
        ("random 500k", random_rays(&scene, 500_000)),
    ];
    let only = args.get(3).cloned().unwrap_or_default();
    for (name, rays) in sets.iter().filter(|(n, _)| n.contains(only.as_str())) {
        let mut st = TraversalStats::default();
        for r in rays.iter().step_by(16) {
            bvh.closest_hit_with_stats(r, &mut st);
        }
        println!(
            "  {name}: per ray {:.1} nodes, {:.1} boxes, {:.1} leaves, {:.1} triangles",
            st.per_ray(st.nodes_visited),
            st.per_ray(st.box_tests),
            st.per_ray(st.leaves_visited),
            st.per_ray(st.triangle_tests)
        );
        let closest = |rs: &[Ray]| rs.iter().filter(|r| bvh.closest_hit(r).is_some()).count();
        let any = |rs: &[Ray]| rs.iter().filter(|r| bvh.any_hit(r)).count();
        let (c1, h, c1cpu) = mrays(rays, 3, closest);
        let (a1, _, a1cpu) = mrays(rays, 3, any);
        let par = |f: &(dyn Fn(&[Ray]) -> usize + Sync)| {
            mrays(rays, 3, |rs| {
                pool.install(|| rs.par_chunks(4096).map(f).sum())
            })
            .0
        };
        let cn = par(&closest);
        let an = par(&any);
        println!(
            "  {name}: closest {c1:.2} Mrays/s (1 thread; {c1cpu:.2} per CPU-second), {cn:.2} ({threads} threads); any {a1:.2} ({a1cpu:.2}) / {an:.2}; {:.0}% hit",
            100.0 * h as f64 / rays.len() as f64
        );
    }
}
