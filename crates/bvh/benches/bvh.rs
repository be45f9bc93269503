//! Criterion benchmarks of parallax-bvh: build (procedural icosphere, and Sponza when the file
//! exists) and closest-hit / any-hit throughput for coherent (camera grid) and incoherent
//! (random) rays. Throughput is reported per ray (criterion "elements").
//!
//! ```text
//! CARGO_TARGET_DIR=... cargo bench -p parallax-bvh
//! ```
//!
//! For a quick table of Mrays/s (1 thread and a rayon pool) use the example
//! `cargo run --release -p parallax-bvh --example bvh_throughput`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;

use common::{Rng, icosphere, soup};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene, TriangleMesh};

fn sponza() -> Option<Scene> {
    let path = format!(
        "{}/../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb",
        env!("CARGO_MANIFEST_DIR")
    );
    std::path::Path::new(&path)
        .exists()
        .then(|| Scene::load(&path).ok())
        .flatten()
}

fn camera_rays(desc: &CameraDesc, w: u32, h: u32) -> Vec<Ray> {
    let cam = Pinhole::new(desc, w, h).unwrap();
    (0..h)
        .flat_map(|y| (0..w).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .filter_map(|f| cam.generate_ray(f, Vec2::splat(0.5), 0).map(|c| c.ray))
        .collect()
}

fn random_rays(mesh: &TriangleMesh, n: usize) -> Vec<Ray> {
    let b = mesh.bounds();
    let mut rng = Rng::new(42);
    (0..n)
        .map(|_| Ray::new(rng.vec3_in(b.min, b.max), rng.dir()))
        .collect()
}

fn bench_build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    let ico = icosphere(6);
    g.throughput(Throughput::Elements(ico.triangle_count() as u64));
    g.bench_function("icosphere_82k", |b| b.iter(|| Bvh::build(black_box(&ico))));
    let s = soup(100_000, 0.02, 1);
    g.throughput(Throughput::Elements(s.triangle_count() as u64));
    g.bench_function("soup_100k", |b| b.iter(|| Bvh::build(black_box(&s))));
    if let Some(scene) = sponza() {
        g.throughput(Throughput::Elements(scene.mesh.triangle_count() as u64));
        g.bench_function("sponza", |b| b.iter(|| Bvh::build(black_box(&scene.mesh))));
        let mut bvh = Bvh::build(&scene.mesh);
        g.bench_function("sponza_refit", |b| {
            b.iter(|| bvh.refit(black_box(&scene.mesh)).unwrap())
        });
    }
    g.finish();
}

fn bench_rays(c: &mut Criterion, name: &str, mesh: &TriangleMesh, desc: &CameraDesc) {
    let bvh = Bvh::build(mesh);
    let sets = [
        ("coherent", camera_rays(desc, 256, 192)),
        ("random", random_rays(mesh, 50_000)),
    ];
    let mut g = c.benchmark_group(format!("trace_{name}"));
    g.sample_size(10);
    for (kind, rays) in &sets {
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function(format!("closest_{kind}"), |b| {
            b.iter(|| rays.iter().filter(|r| bvh.closest_hit(r).is_some()).count())
        });
        g.bench_function(format!("any_{kind}"), |b| {
            b.iter(|| rays.iter().filter(|r| bvh.any_hit(r)).count())
        });
    }
    g.finish();
}

fn bench_trace(c: &mut Criterion) {
    let ico = icosphere(6);
    let desc = CameraDesc::new(Vec3::new(0.0, 0.5, 3.0), Vec3::ZERO, Vec3::Y, 45.0);
    bench_rays(c, "icosphere", &ico, &desc);
    if let Some(scene) = sponza() {
        bench_rays(c, "sponza", &scene.mesh, &scene.camera(None).unwrap());
    }
}

criterion_group!(benches, bench_build, bench_trace);
criterion_main!(benches);
