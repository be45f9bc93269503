//! Quick measurement (no criterion): rasterized vs BVH G-buffer of the same 1280x720 view, the
//! cost of extra layers, and bytes per capture, for atrium, Sponza and the classroom.
//!
//! `CARGO_TARGET_DIR=/work/target-h8 cargo run --release -p parallax-raster --example raster_vs_bvh`

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene};
use rayon::prelude::*;

fn best_of<T>(n: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..n {
        let t = Instant::now();
        let r = f();
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        out = Some(r);
    }
    (best, out.unwrap())
}

fn main() {
    let root = format!("{}/../../../shared/scenes", env!("CARGO_MANIFEST_DIR"));
    let cases: Vec<(String, Option<CameraDesc>)> = vec![
        ("atrium".into(), None),
        (
            format!("{root}/sponza_dabrovic/sponza_dabrovic.glb"),
            Some(CameraDesc::new(
                Vec3::new(-9.0, 3.5, 0.0),
                Vec3::new(8.0, 5.0, 0.0),
                Vec3::Y,
                60.0,
            )),
        ),
        (
            format!("{root}/japanese_classroom/japanese_classroom.glb"),
            Some(CameraDesc::new(
                Vec3::new(-1.69, 1.272, 5.887),
                Vec3::new(-1.539, 1.3, 4.898),
                Vec3::Y,
                55.0,
            )),
        ),
    ];
    let (w, h) = (1280u32, 720u32);
    println!(
        "threads {}, view {w}x{h}, best of 5",
        rayon::current_num_threads()
    );
    println!(
        "| scene | tris | raster ms | BVH ms | BVH/raster | +1 layer ms | 4 layers ms | bytes (1 layer) | bytes (4 layers) | setup/bin/raster/resolve ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (path, desc) in cases {
        let scene = match Scene::load(&path) {
            Ok(s) => s,
            Err(e) => {
                println!("skip {path}: {e}");
                continue;
            }
        };
        let desc = desc.unwrap_or_else(|| scene.camera(None).unwrap());
        let cam = Pinhole::new(&desc, w, h).unwrap();
        let view = View::from_pinhole(&cam).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let (r1, c1) = best_of(5, || {
            capture_layers(&scene, &view, &RasterOptions::layers(1)).unwrap()
        });
        let (r2, _) = best_of(5, || {
            capture_layers(&scene, &view, &RasterOptions::layers(2)).unwrap()
        });
        let (r4, c4) = best_of(5, || {
            capture_layers(&scene, &view, &RasterOptions::layers(4)).unwrap()
        });
        // BVH: the closest hit through every pixel centre (the G-buffer's visibility part;
        // the reference renderer's shading of the hit is not included, so the ratio favours
        // the BVH slightly).
        let (b, hits) = best_of(5, || {
            (0..h)
                .into_par_iter()
                .map(|y| {
                    let mut n = 0usize;
                    for x in 0..w {
                        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        let r = cam.generate_ray(film, Vec2::splat(0.5), 1).unwrap();
                        n += bvh.closest_hit(&r.ray).is_some() as usize;
                    }
                    n
                })
                .sum::<usize>()
        });
        let s = c1.stats;
        println!(
            "| {} | {} | {r1:.2} | {b:.2} | {:.2} | {:.2} | {r4:.2} | {} | {} | {:.2}/{:.2}/{:.2}/{:.2} |",
            scene.name,
            scene.mesh.indices.len(),
            b / r1,
            r2 - r1,
            c1.bytes(),
            c4.bytes(),
            s.raster.setup_ms,
            s.raster.bin_ms,
            s.raster.raster_ms,
            s.resolve_ms
        );
        println!(
            "  covered pixels: raster {}, BVH {hits}",
            c1.gbuffer().hit_count()
        );
    }
}
