//! Build time and memory of layered depth cubes (Bürger et al. 2007, §1.2-1.3; their Table 1
//! uses 512^2 and 1024^2 LDIs) on the atrium, Sponza and the Japanese classroom.
//!
//! `cargo run --release -p parallax-raster --example ldc_build [block]`

use parallax_raster::ldc::{LayeredDepthCube, LdcOptions};
use parallax_scene::Scene;

fn main() {
    let block: u32 = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("block: a positive integer"))
        .unwrap_or(8);
    let dir = format!("{}/../../../shared/scenes", env!("CARGO_MANIFEST_DIR"));
    let scenes = [
        ("atrium", "atrium".to_string()),
        (
            "sponza",
            format!("{dir}/sponza_dabrovic/sponza_dabrovic.glb"),
        ),
        (
            "classroom",
            format!("{dir}/japanese_classroom/japanese_classroom.glb"),
        ),
    ];
    println!(
        "threads {}, coarse block {block}, best of 3 builds\n",
        rayon::current_num_threads()
    );
    println!(
        "| scene | tris | res | LDI sizes | tris per LDI | samples | max depth cx | build ms \
         (assign / per LDI setup+bin, count, fill+sort, resolve, coarse) | MiB | bytes/sample |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for (name, path) in &scenes {
        let scene = match Scene::load(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("skipping {name}: {e}");
                continue;
            }
        };
        let b = scene.mesh.bounds();
        println!("<!-- {name}: mesh bounds {} .. {} -->", b.min, b.max);
        for res in [512, 1024] {
            let opts = LdcOptions {
                block,
                ..LdcOptions::default()
            };
            let best = (0..3)
                .map(|_| LayeredDepthCube::build(&scene, res, &opts).unwrap())
                .min_by(|a, b| a.stats.total_ms.total_cmp(&b.stats.total_ms))
                .unwrap();
            let st = &best.stats;
            let sizes: Vec<String> = st
                .ldis
                .iter()
                .map(|l| format!("{}x{}", l.capture.width, l.capture.height))
                .collect();
            let tris: Vec<String> = st.ldis.iter().map(|l| l.triangles.to_string()).collect();
            let stages: Vec<String> = st
                .ldis
                .iter()
                .map(|l| {
                    let c = &l.capture;
                    format!(
                        "{:.1}+{:.1}, {:.1}, {:.1}, {:.1}, {:.1}",
                        c.raster.setup_ms,
                        c.raster.bin_ms,
                        c.raster.raster_ms,
                        c.fill_ms,
                        c.resolve_ms,
                        l.coarse_ms
                    )
                })
                .collect();
            println!(
                "| {name} | {} | {res} | {} | {} | {} | {} | **{:.1}** ({:.1} / {}) | {:.1} | {:.1} |",
                st.triangles,
                sizes.join(", "),
                tris.join(", "),
                st.samples,
                st.max_depth_complexity,
                st.total_ms,
                st.assign_ms,
                stages.join(" / "),
                best.bytes() as f64 / (1 << 20) as f64,
                best.bytes() as f64 / st.samples.max(1) as f64,
            );
        }
    }
}
