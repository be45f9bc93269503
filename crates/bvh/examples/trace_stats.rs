//! Single-thread profile of one view: work counters and closest-hit throughput of primary rays
//! (pixel centres, 1280x720) and of the same rays as 4x4-pixel packets.
//!
//! ```text
//! cargo run --release -p parallax-bvh --example trace_stats -- SCENE EYE TARGET FOV [REPEATS]
//! e.g. .. sponza.glb=-9,3.5,0 ... : trace_stats sponza.glb -9,3.5,0 8,5,0 60
//! ```

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, TraversalStats};
use parallax_core::Ray;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene};

fn v3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("number")).collect();
    Vec3::new(v[0], v[1], v[2])
}

fn best_of(repeats: u32, mut f: impl FnMut() -> usize) -> (f64, usize) {
    let mut best = f64::INFINITY;
    let mut n = 0;
    for _ in 0..repeats {
        let t = Instant::now();
        n = f();
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, n)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = Scene::load(&a[1]).expect("scene");
    let desc = CameraDesc::new(v3(&a[2]), v3(&a[3]), Vec3::Y, a[4].parse().unwrap());
    let repeats: u32 = a.get(5).map_or(5, |r| r.parse().unwrap());
    let bvh = Bvh::build(&scene.mesh);
    let (w, h) = (1280u32, 720u32);
    let cam = Pinhole::new(&desc, w, h).unwrap();
    // Rays in 4x4 tiles, tile after tile.
    let mut rays: Vec<Ray> = Vec::new();
    for ty in (0..h).step_by(4) {
        for tx in (0..w).step_by(4) {
            for y in ty..ty + 4 {
                for x in tx..tx + 4 {
                    let f = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    rays.push(cam.generate_ray(f, Vec2::splat(0.5), 1).unwrap().ray);
                }
            }
        }
    }
    let mut st = TraversalStats::default();
    for r in &rays {
        bvh.closest_hit_with_stats(r, &mut st);
    }
    println!(
        "{}: {} rays; per ray {:.1} nodes, {:.1} boxes, {:.1} leaves, {:.1} triangles",
        scene.name,
        rays.len(),
        st.per_ray(st.nodes_visited),
        st.per_ray(st.box_tests),
        st.per_ray(st.leaves_visited),
        st.per_ray(st.triangle_tests)
    );
    let n = rays.len() as f64;
    let (t, hits) = best_of(repeats, || {
        rays.iter().filter(|r| bvh.closest_hit(r).is_some()).count()
    });
    println!(
        "closest_hit        {:6.2} Mrays/s ({hits} hits)",
        n / t / 1e6
    );
    let (t, hits) = best_of(repeats, || {
        rays.iter()
            .filter(|r| bvh.closest_hit_scalar(r).is_some())
            .count()
    });
    println!(
        "closest_hit_scalar {:6.2} Mrays/s ({hits} hits)",
        n / t / 1e6
    );
    let mut out = vec![None; 16];
    let (t, hits) = best_of(repeats, || {
        let mut n = 0;
        for p in rays.chunks(16) {
            bvh.closest_hit_packet(p, &mut out);
            n += out.iter().filter(|h| h.is_some()).count();
        }
        n
    });
    println!(
        "packet 4x4        {:6.2} Mrays/s ({hits} hits)",
        n / t / 1e6
    );
}
