//! A driver for instruction-count profiles of DIRT's build and trace (run it under
//! `valgrind --tool=callgrind`; the difference between a mode and `load` is that mode's cost).
//!
//! ```sh
//! cargo build --release -p parallax-path --example dirt_profile
//! valgrind --tool=callgrind target/release/examples/dirt_profile atrium dirt 3
//! ```
//!
//! Arguments: `SCENE MODE N [EYE TARGET FOV_Y]` with `EYE` and `TARGET` as `x,y,z`; modes:
//! `load` (load the scene, build the BVH and the rays, nothing else), `dirt` (the DIRT build
//! `N` times), `bvh` (the BVH build `N` times), `trace-dirt` / `trace-bvh` (the diffuse rays of
//! `bench dirt` traced `N` times). 1024x512 film, the `bench dirt` defaults
//! ([`DIRT_DEFAULTS`]; `DIRT_NOCAM` set: no camera view, the cube alone; `DIRT_FACE`,
//! `DIRT_TILE`, `DIRT_BUCKETS`: other face size, `S`, `B`; `DIRT_CAMERA_TILE`: the camera
//! view's `S` (`none`: the faces' `S`); `DIRT_STATS`: print each build's
//! fragments, entries and a hash of its arrays; `DIRT_TIME`: the min and median CPU time of
//! the `dirt` / `bvh` builds). One thread unless
//! `RAYON_NUM_THREADS` says otherwise.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_path::bench::dirt_rays::{RayOptions, RayType, ray_sets};
use parallax_path::tracers::{DIRT_DEFAULTS, camera_centre};
use parallax_raster::dirt::DirtViews;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{DirtCounters, DirtTracer};

/// Fragments, entries and a hash of every view's arrays (ids, offsets, bounds), to compare
/// two builds' captures (`DIRT_STATS` set).
fn print_capture_stats(v: &DirtViews) {
    use std::hash::{Hash, Hasher};
    let views = v.camera.iter().chain(&v.cube.faces);
    let (mut frags, mut entries) = (0u64, 0u64);
    let mut h = std::collections::hash_map::DefaultHasher::new();
    for c in views {
        frags += c.stats().fragments;
        entries += c.stats().entries;
        c.ids().hash(&mut h);
        c.offsets().hash(&mut h);
        for b in c.mip_arrays().1 {
            b[0].to_bits().hash(&mut h);
            b[1].to_bits().hash(&mut h);
        }
    }
    eprintln!(
        "fragments {frags} entries {entries} hash {:016x}",
        h.finish()
    );
}

/// CPU time of every thread of the process so far, ns (the first field of each thread's
/// `/proc/self/task/*/schedstat`: time on a CPU; other processes' time is not in it).
fn cpu_ns() -> u64 {
    let Ok(dir) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    dir.filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum()
}

/// Min and median CPU ms of the builds (`DIRT_TIME` set): on a loaded host the minimum is
/// the build least disturbed by other processes' cache traffic.
fn print_cpu(cpu: &mut [u64]) {
    if std::env::var_os("DIRT_TIME").is_none() || cpu.is_empty() {
        return;
    }
    cpu.sort_unstable();
    let ms = |x: u64| x as f64 * 1e-6;
    eprintln!(
        "cpu ms per build: min {:.2} median {:.2} of {}",
        ms(cpu[0]),
        ms(cpu[cpu.len() / 2]),
        cpu.len()
    );
}

fn vec3(s: &str) -> Vec3 {
    let v: Vec<f32> = s.split(',').map(|x| x.parse().expect("number")).collect();
    Vec3::new(v[0], v[1], v[2])
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: dirt_profile SCENE MODE N [EYE TARGET FOV_Y]");
        std::process::exit(2);
    }
    if std::env::var_os("RAYON_NUM_THREADS").is_none() {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global()
            .expect("thread pool");
    }
    let scene = Scene::load(&args[1]).expect("scene");
    let n: u32 = args[3].parse().expect("N");
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
    let eye = camera_centre(&camera);
    let bvh = Bvh::try_build(&scene.mesh).expect("bvh");
    let sets = ray_sets(&scene, &bvh, &camera, &RayOptions::default());
    let diffuse = &sets
        .iter()
        .find(|s| s.kind == RayType::Diffuse)
        .expect("diffuse")
        .rays;
    // DIRT_NOCAM: the cube map alone; DIRT_FACE / DIRT_TILE / DIRT_BUCKETS: other settings.
    let pinhole = pinhole.filter(|_| std::env::var_os("DIRT_NOCAM").is_none());
    let env = |k: &str, d: u32| std::env::var(k).map_or(d, |v| v.parse().expect(k));
    let mut opts = DIRT_DEFAULTS;
    opts.face_size = env("DIRT_FACE", opts.face_size);
    opts.capture.tile_size = env("DIRT_TILE", opts.capture.tile_size);
    opts.capture.buckets = env("DIRT_BUCKETS", opts.capture.buckets);
    if let Ok(s) = std::env::var("DIRT_CAMERA_TILE") {
        opts.camera_tile_size = (s != "none").then(|| s.parse().expect("DIRT_CAMERA_TILE"));
    }
    let build = || DirtViews::build(&scene.mesh, pinhole, eye, &opts).expect("dirt");
    let mut hits = 0u64;
    match args[2].as_str() {
        "load" => {}
        "dirt" => {
            let mut cpu = Vec::with_capacity(n as usize);
            for _ in 0..n {
                let t0 = cpu_ns();
                let v = std::hint::black_box(build());
                cpu.push(cpu_ns() - t0);
                hits += v.stats.capture_bytes;
                if std::env::var_os("DIRT_STATS").is_some() {
                    print_capture_stats(&v);
                }
            }
            print_cpu(&mut cpu);
        }
        "bvh" => {
            let mut cpu = Vec::with_capacity(n as usize);
            for _ in 0..n {
                let t0 = cpu_ns();
                hits += std::hint::black_box(Bvh::try_build(&scene.mesh).expect("bvh")).node_count()
                    as u64;
                cpu.push(cpu_ns() - t0);
            }
            print_cpu(&mut cpu);
        }
        "trace-dirt" => {
            let dirt = DirtTracer::new(build());
            let mut c = DirtCounters::default();
            for _ in 0..n {
                hits += diffuse
                    .iter()
                    .filter(|r| dirt.closest_hit_counted(r, &mut c).is_some())
                    .count() as u64;
            }
            eprintln!("{c:?}");
        }
        "trace-bvh" => {
            for _ in 0..n {
                hits += diffuse
                    .iter()
                    .filter(|r| bvh.closest_hit(r).is_some())
                    .count() as u64;
            }
        }
        "dump-rays" => {
            // The diffuse rays as little-endian f32 (origin, dir, t_min, t_max), to
            // `DIRT_RAYS_OUT`.
            let path = std::env::var("DIRT_RAYS_OUT").expect("DIRT_RAYS_OUT");
            let mut bytes = Vec::with_capacity(diffuse.len() * 32);
            for r in diffuse {
                for x in [
                    r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.t_min, r.t_max,
                ] {
                    bytes.extend_from_slice(&x.to_le_bytes());
                }
            }
            std::fs::write(path, bytes).expect("write rays");
            hits = eye.x.to_bits() as u64;
            eprintln!("eye {eye:?}");
        }
        m => panic!("unknown mode {m}"),
    }
    println!("{} diffuse rays, {hits}", diffuse.len());
}
