//! Traces rays from a file through DIRT (for instruction-count profiles of the tracer alone,
//! built without the path crate): `dirt_trace SCENE RAYS N [EYE TARGET FOV_Y]` with `RAYS` written by
//! `dirt_profile SCENE dump-rays 1` (`DIRT_RAYS_OUT`), the same camera, film and DIRT options
//! as `dirt_profile` (`bench dirt`'s defaults). Prints the counters and a hash of the hits.
//!
//! ```sh
//! valgrind --tool=callgrind --toggle-collect='*closest_hit_counted*' \
//!     target/release/examples/dirt_trace atrium /tmp/atrium.rays 1
//! ```

use std::hash::{Hash, Hasher};

use glam::{Vec2, Vec3};
use parallax_core::Ray;
use parallax_raster::dirt::{DirtViews, DirtViewsOptions};
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{DirtCounters, DirtTracer};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: dirt_trace SCENE RAYS N");
        std::process::exit(2);
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("thread pool");
    let scene = Scene::load(&args[1]).expect("scene");
    let bytes = std::fs::read(&args[2]).expect("rays");
    let n: u32 = args[3].parse().expect("N");
    let f = |i: usize| f32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().expect("4 bytes"));
    let rays: Vec<Ray> = (0..bytes.len() / 32)
        .map(|k| {
            let b = 8 * k;
            Ray {
                origin: Vec3::new(f(b), f(b + 1), f(b + 2)),
                dir: Vec3::new(f(b + 3), f(b + 4), f(b + 5)),
                t_min: f(b + 6),
                t_max: f(b + 7),
            }
        })
        .collect();
    let vec3 = |s: &str| {
        let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("number")).collect();
        Vec3::new(v[0], v[1], v[2])
    };
    let desc = if args.len() >= 7 {
        CameraDesc::new(
            vec3(&args[4]),
            vec3(&args[5]),
            Vec3::Y,
            args[6].parse().expect("fov"),
        )
    } else {
        scene.camera(None).expect("camera")
    };
    let camera = Camera::new(
        ModelKind::Pinhole,
        &desc,
        1024,
        512,
        &CameraOptions::default(),
    )
    .expect("camera");
    let pinhole = match &camera {
        Camera::Pinhole(p) => Some(p),
        _ => None,
    };
    let film = Vec2::new(camera.width() as f32, camera.height() as f32) * 0.5;
    let eye = camera
        .generate_ray(film, Vec2::splat(0.5), 1)
        .map_or(Vec3::ZERO, |r| r.ray.origin);
    // `bench dirt`'s configuration (`parallax_path::tracers::DIRT_DEFAULTS`).
    let opts = DirtViewsOptions::TRACING;
    let dirt = DirtTracer::new(DirtViews::build(&scene.mesh, pinhole, eye, &opts).expect("dirt"));
    if std::env::var_os("DIRT_AB").is_some() {
        // In-process interleaved timing of the tracer's compiled copies (the portable twin
        // first), each pass over all rays; ratios against the portable twin.
        let copies = dirt.copies();
        // Chunks of 4096 rays, every copy in turn on each chunk (rotating who goes first), so
        // that load from other processes falls on all copies alike.
        let chunk = |t: &DirtTracer, rays: &[Ray]| {
            let mut c = DirtCounters::default();
            let start = std::time::Instant::now();
            let mut hits = 0u64;
            for r in rays {
                hits += t.closest_hit_counted(r, &mut c).is_some() as u64;
            }
            (start.elapsed().as_secs_f64(), hits)
        };
        let mut sums = vec![0.0; copies.len()];
        for pass in 0..n as usize {
            let before = sums.clone();
            for (i, part) in rays.chunks(4096).enumerate() {
                let mut first = None;
                for j in 0..copies.len() {
                    let k = (i + j + pass) % copies.len();
                    let (s, hits) = chunk(&copies[k].1, part);
                    assert_eq!(*first.get_or_insert(hits), hits);
                    sums[k] += s;
                }
            }
            let line: Vec<String> = copies
                .iter()
                .enumerate()
                .map(|(k, (name, _))| format!("{name} {:.4} s", sums[k] - before[k]))
                .collect();
            println!("{}", line.join("  "));
        }
        for (k, (name, _)) in copies.iter().enumerate() {
            println!(
                "{name}: total {:.4} s, ratio {:.4}",
                sums[k],
                sums[k] / sums[0]
            );
        }
        return;
    }
    let mut c = DirtCounters::default();
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let mut hits = 0u64;
    for _ in 0..n {
        for r in &rays {
            if let Some(hit) = dirt.closest_hit_counted(r, &mut c) {
                hits += 1;
                (hit.prim, hit.t.to_bits()).hash(&mut h);
            } else {
                u32::MAX.hash(&mut h);
            }
        }
    }
    eprintln!("{c:?}");
    println!("{} rays, {hits} hits, hash {:016x}", rays.len(), h.finish());
}
