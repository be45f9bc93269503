//! Build time and memory of DIRT captures (Vardis et al. 2017, §4.1 and Table 3): per pixel
//! and with 4 x 4 tiles, for a 1280 x 720 view and a 6 x 512^2 cube map, on the atrium, Sponza
//! and the Japanese classroom.
//!
//! `cargo run --release -p parallax-raster --example dirt_memory [buckets]`

use glam::Vec3;
use parallax_raster::dirt::{DirtCapture, DirtCube, DirtOptions, DirtStats};
use parallax_scene::camera::{CubeMap, Pinhole};
use parallax_scene::{CameraDesc, Scene};

fn main() {
    let buckets: u32 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("buckets: a positive integer"))
        .unwrap_or(8);
    let dir = format!("{}/../../../shared/scenes", env!("CARGO_MANIFEST_DIR"));
    let atrium = Scene::load("atrium").unwrap();
    let atrium_cam = atrium.camera(None).unwrap();
    let scenes = [
        ("atrium", atrium.mesh, atrium_cam),
        (
            "sponza",
            Scene::load(&format!("{dir}/sponza_dabrovic/sponza_dabrovic.glb"))
                .unwrap()
                .mesh,
            CameraDesc::new(
                Vec3::new(-9.0, 3.5, 0.0),
                Vec3::new(8.0, 5.0, 0.0),
                Vec3::Y,
                60.0,
            ),
        ),
        (
            "classroom",
            Scene::load(&format!("{dir}/japanese_classroom/japanese_classroom.glb"))
                .unwrap()
                .mesh,
            CameraDesc::new(
                Vec3::new(-1.69, 1.272, 5.887),
                Vec3::new(-1.539, 1.3, 4.898),
                Vec3::Y,
                55.0,
            ),
        ),
    ];
    println!(
        "threads {}, B = {buckets}, best of 3 builds\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | tris | capture | S | build ms (setup/fill/asm/mip) | fragments | entries | \
         MiB | bytes/pixel |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (name, mesh, desc) in &scenes {
        for s in [1, 4] {
            let opts = DirtOptions {
                tile_size: s,
                buckets,
                ..DirtOptions::default()
            };
            let view = Pinhole::new(desc, 1280, 720).unwrap();
            let best = (0..3)
                .map(|_| DirtCapture::build(mesh, &view, &opts).unwrap())
                .min_by(|a, b| a.stats().total_ms.total_cmp(&b.stats().total_ms))
                .unwrap();
            row(
                name,
                mesh.triangle_count(),
                "1280x720",
                s,
                &[best.stats().clone()],
                1280 * 720,
            );
            let cube = CubeMap::new(desc, 512).unwrap();
            let best = (0..3)
                .map(|_| DirtCube::build(mesh, &cube, &opts).unwrap())
                .min_by(|a, b| a.total_ms().total_cmp(&b.total_ms()))
                .unwrap();
            let stats: Vec<DirtStats> = best.faces.iter().map(|f| f.stats().clone()).collect();
            row(
                name,
                mesh.triangle_count(),
                "cube 6x512^2",
                s,
                &stats,
                6 * 512 * 512,
            );
        }
    }
}

fn row(name: &str, tris: usize, what: &str, s: u32, st: &[DirtStats], pixels: u64) {
    let sum = |f: fn(&DirtStats) -> f64| st.iter().map(f).sum::<f64>();
    let bytes = sum(|s| s.bytes as f64);
    println!(
        "| {name} | {tris} | {what} | {s} | {:.1} ({:.1}/{:.1}/{:.1}/{:.1}) | {} | {} | {:.1} | {:.1} |",
        sum(|s| s.total_ms),
        sum(|s| s.setup_ms),
        sum(|s| s.fill_ms),
        sum(|s| s.assemble_ms),
        sum(|s| s.mip_ms),
        sum(|s| s.fragments as f64),
        sum(|s| s.entries as f64),
        bytes / (1024.0 * 1024.0),
        bytes / pixels as f64
    );
}
