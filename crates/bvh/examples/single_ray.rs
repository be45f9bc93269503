//! Single-thread single-ray throughput (thread CPU time, best of N) on one view, with a checksum
//! of the answers so that traversal changes can be A/B-compared for speed and sameness:
//!
//! ```text
//! cargo run --release -p parallax-bvh --example single_ray -- SCENE EYE TARGET FOV [REPEATS]
//! ```
//!
//! Sets: primary rays (1280x720 pixel centres, closest and any hit), shadow-like rays from the
//! primary hit points towards a point above the scene (any hit), and 300k random rays (origins
//! in the bounds, uniform directions; closest and any hit).

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene};

fn v3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("number")).collect();
    Vec3::new(v[0], v[1], v[2])
}

fn thread_cpu_ns() -> u64 {
    parallax_core::cpu_time::thread_cpu_ns().expect("thread CPU clock (Linux)")
}

/// Best of `reps` in Mrays/s of this thread's CPU time, and the checksum of the last run.
fn run(rays: &[Ray], reps: u32, f: impl Fn(&Ray) -> u64) -> (f64, u64) {
    let mut best = u64::MAX;
    let mut sum = 0;
    for _ in 0..reps {
        let c0 = thread_cpu_ns();
        sum = rays
            .iter()
            .fold(0u64, |a, r| a.wrapping_mul(31).wrapping_add(f(r)));
        best = best.min(thread_cpu_ns() - c0);
    }
    (rays.len() as f64 / (best as f64 * 1e-9) / 1e6, sum)
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = Scene::load(&a[1]).expect("scene");
    let desc = CameraDesc::new(v3(&a[2]), v3(&a[3]), Vec3::Y, a[4].parse().unwrap());
    let reps: u32 = a.get(5).map_or(5, |r| r.parse().unwrap());
    let bvh = Bvh::build(&scene.mesh);
    let (w, h) = (1280u32, 720u32);
    let cam = Pinhole::new(&desc, w, h).unwrap();
    let mut primary = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let f = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            primary.push(cam.generate_ray(f, Vec2::splat(0.5), 1).unwrap().ray);
        }
    }
    let b = scene.bounds();
    let light = Vec3::new(b.center().x, b.max.y * 0.9 + b.min.y * 0.1, b.center().z);
    let shadow: Vec<Ray> = primary
        .iter()
        .filter_map(|r| {
            let h = bvh.closest_hit(r)?;
            let p = r.at(h.t * 0.9999);
            let d = light - p;
            let mut s = Ray::new(p, d);
            s.t_max = 0.999;
            Some(s)
        })
        .collect();
    let mut s = 0x1234_5678u32;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1 << 24) as f32
    };
    let random: Vec<Ray> = (0..300_000)
        .map(|_| {
            let o = b.min + Vec3::new(rnd(), rnd(), rnd()) * b.extent();
            let z = 2.0 * rnd() - 1.0;
            let phi = std::f32::consts::TAU * rnd();
            let r = (1.0 - z * z).sqrt();
            Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect();
    let closest = |r: &Ray| {
        bvh.closest_hit(r).map_or(0, |h| {
            (h.prim as u64) << 32 ^ h.t.to_bits() as u64 ^ (h.u.to_bits() as u64) << 7
        })
    };
    let any = |r: &Ray| bvh.any_hit(r) as u64;
    if let Ok(path) = std::env::var("DUMP") {
        let lines: Vec<String> = random
            .iter()
            .enumerate()
            .map(|(i, r)| format!("{i} {:?} | {:?} {:?}", bvh.closest_hit(r), r.origin, r.dir))
            .collect();
        std::fs::write(path, lines.join("\n")).unwrap();
        return;
    }
    let only = std::env::var("SETS").unwrap_or_default();
    for (name, rays) in [
        ("primary", &primary),
        ("shadow", &shadow),
        ("random", &random),
    ] {
        if !only.is_empty() && !only.contains(name) {
            continue;
        }
        let (c, cs) = run(rays, reps, closest);
        let (an, as_) = run(rays, reps, any);
        println!(
            "{name:8} {:7} rays: closest {c:6.2} Mrays/s [{cs:016x}]  any {an:6.2} Mrays/s [{as_:016x}]",
            rays.len()
        );
    }
}
