//! `parallax bench dirt`: DIRT Tables 1-3 (Vardis et al. 2017) for DIRT against the BVH in the
//! same run: build times, Mrays/s per ray type, memory per buffer, `B` and `S` sweeps.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use parallax_path::bench::dirt::{DirtBenchOptions, DirtBenchReport, run};
use parallax_path::bench::dirt_path::path_agreement;
use parallax_path::bench::dirt_rays::RayOptions;
use parallax_path::{LightOverrides, PathOptions, TracerOptions, apply_lighting};
use parallax_raster::dirt::{DirtOptions, DirtViewsOptions};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

use crate::args::ViewArgs;
use crate::demo_piece::{DemoPiece, section};

#[derive(Args, Debug)]
pub struct DirtBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    #[arg(long, default_value_t = 512)]
    pub height: u32,
    /// Cube face size in pixels.
    #[arg(long, default_value_t = 128)]
    pub face: u32,
    /// Tile size S (a power of two): one primitive list per S x S pixels [default: 4 for the
    /// cube faces, 8 for the camera view (the tracers' configuration); given alone, S of every
    /// view].
    #[arg(long)]
    pub tile: Option<u32>,
    /// The camera view's tile size S [default: 8, or `--tile` when that is given].
    #[arg(long)]
    pub camera_tile: Option<u32>,
    /// Depth buckets B per cell.
    #[arg(long, default_value_t = 16)]
    pub buckets: u32,
    /// Interleaved rounds per measurement (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// B values of the bucket sweep (comma-separated; empty: none).
    #[arg(long, value_delimiter = ',', default_value = "1,4,8,16,32")]
    pub sweep_buckets: Vec<u32>,
    /// S values of the tile sweep (comma-separated; empty: none).
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
    pub sweep_tiles: Vec<u32>,
    /// Skip both sweeps.
    #[arg(long)]
    pub no_sweep: bool,
    /// Seed of the ray generation.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// glTF roughness of the glossy rays' rough metal (GGX alpha = roughness^2).
    #[arg(long, default_value_t = 0.3)]
    pub glossy_roughness: f32,
    /// Also path-trace the view with the BVH and with DIRT at this many samples per pixel and
    /// compare every bounce's hits and the images (0: skip).
    #[arg(long, default_value_t = 0)]
    pub path_spp: u32,
    /// Longest path of that comparison (segments).
    #[arg(long, default_value_t = 5)]
    pub path_max_depth: u32,
    /// Build and trace the cube map alone, without DIRT's camera view (Table 1, the build and
    /// the sweeps; the path-tracing comparison keeps the camera view).
    #[arg(long)]
    pub no_camera_view: bool,
    /// Write the report as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn run_bench(a: &DirtBenchArgs, quiet: bool) -> Result<()> {
    if !(a.glossy_roughness.is_finite() && a.glossy_roughness > 0.0 && a.glossy_roughness <= 1.0) {
        bail!(
            "--glossy-roughness {} must be in (0, 1]",
            a.glossy_roughness
        );
    }
    let scene = a.view.load_scene()?;
    let camera = a.view.camera(&scene, a.width, a.height)?;
    const TRACING: DirtViewsOptions = DirtViewsOptions::TRACING;
    let opts = DirtBenchOptions {
        views: DirtViewsOptions {
            face_size: a.face,
            capture: DirtOptions {
                tile_size: TRACING.capture.tile_size,
                buckets: a.buckets,
                ..DirtOptions::default()
            },
            camera_tile_size: TRACING.camera_tile_size,
        }
        .with_tile_flags(a.tile, a.camera_tile),
        repeats: a.repeats,
        sweep_buckets: if a.no_sweep {
            vec![]
        } else {
            a.sweep_buckets.clone()
        },
        sweep_tiles: if a.no_sweep {
            vec![]
        } else {
            a.sweep_tiles.clone()
        },
        rays: RayOptions {
            seed: a.seed,
            glossy_roughness: a.glossy_roughness,
        },
        path_spp: a.path_spp,
        path_max_depth: a.path_max_depth,
        camera_view: !a.no_camera_view,
    };
    let report = run(&scene, &camera, &opts).context("bench dirt")?;
    if !quiet {
        print(&report);
    }
    if let Some(p) = &a.json {
        std::fs::write(p, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

fn print(r: &DirtBenchReport) {
    let o = &r.options.views;
    println!(
        "DIRT vs BVH, {}x{}, {}cube faces {}^2, S = {}{}, B = {}, {} threads, best of {} interleaved rounds\n",
        r.width,
        r.height,
        if r.options.camera_view {
            "camera view + "
        } else {
            "no camera view, "
        },
        o.face_size,
        o.capture.tile_size,
        match o.camera_tile_size {
            Some(s) if r.options.camera_view => format!(" (camera view S = {s})"),
            _ => String::new(),
        },
        o.capture.buckets,
        r.threads,
        r.options.repeats
    );
    println!(
        "Build (ms; DIRT stages: triangle buffer / camera view / cube / tracer (slab masks); capture setup / fill / assemble / mip)\n"
    );
    println!("| scene | method | triangles | build ms | vs BVH | stages | capture stages | MiB |");
    println!("|---|---|---|---|---|---|---|---|");
    for b in &r.build {
        println!(
            "| {} | {} | {} | {:.1} | {:.2}x | {:.1} / {:.1} / {:.1} / {:.1} | {:.1} / {:.1} / {:.1} / {:.1} | {:.1} |",
            b.scene,
            b.method,
            b.triangles,
            b.ms_build,
            b.build_vs_bvh,
            b.ms_triangles,
            b.ms_camera,
            b.ms_cube,
            b.ms_tracer,
            b.ms_setup,
            b.ms_fill,
            b.ms_assemble,
            b.ms_mip,
            b.bytes as f64 / (1 << 20) as f64
        );
    }
    println!("\nTable 1: first path event, Mrays/s per ray type (time = thread CPU per ray)\n");
    println!(
        "| scene | rays | method | count | Mrays/s | CPU Mrays/s | time vs BVH | hit rate | same prim | ties | views | texels | cells | buckets | tests | % truncated |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for x in &r.rays {
        println!(
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2}x | {:.3} | {:.5} | {} | {:.2} | {:.1} | {:.1} | {:.1} | {:.1} | {:.3} |",
            x.scene,
            x.ray_type.name(),
            x.method,
            x.rays,
            x.mrays_per_s,
            x.cpu_mrays_per_s,
            x.time_vs_bvh,
            x.hit_rate,
            x.same_prim,
            x.ties,
            x.views_per_ray,
            x.texels_per_ray,
            x.cells_per_ray,
            x.buckets_per_ray,
            x.tests_per_ray,
            x.pct_truncated
        );
    }
    println!(
        "\nTable 3: memory (the paper's formula with the measured c·n_p, and the bytes measured)\n"
    );
    println!("| scene | buffer | formula | units | formula MiB | measured MiB | note |");
    println!("|---|---|---|---|---|---|---|");
    for m in &r.memory {
        println!(
            "| {} | {} | {} | {} | {:.2} | {:.2} | {} |",
            m.scene,
            m.buffer,
            m.formula,
            m.units,
            m.formula_bytes / (1 << 20) as f64,
            m.measured_bytes as f64 / (1 << 20) as f64,
            m.note
        );
    }
    if let Some(p) = &r.path {
        println!(
            "\nPath tracing, BVH vs DIRT behind the same path tracer: {}x{}, {} spp, max depth {}, same seed; PSNR {:.1} dB, {} pixels differ; build ms BVH {:.1} / DIRT {:.1}; render ms BVH {:.0} / DIRT {:.0}\n",
            p.width,
            p.height,
            p.spp,
            p.max_depth,
            p.psnr,
            p.pixels_differ,
            p.ms_build_bvh,
            p.ms_build_dirt,
            p.ms_render_bvh,
            p.ms_render_dirt
        );
        println!(
            "| bounce | rays | same prim | ties | same or tie | unmatched | shadow rays | same occlusion |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        for b in &p.bounces {
            println!(
                "| {} | {} | {:.6} | {} | {:.6} | {} | {} | {:.6} |",
                b.bounce,
                b.rays,
                b.same_fraction(),
                b.ties,
                b.same_or_tie_fraction(),
                b.unmatched,
                b.shadow_rays,
                b.shadow_same as f64 / b.shadow_rays.max(1) as f64
            );
        }
    }
    if !r.sweep.is_empty() {
        println!("\nSweeps over B and S (Fig. 10): build, memory, diffuse rays\n");
        println!(
            "| scene | S | B | face | build ms | vs BVH | MiB | entries | diffuse Mrays/s | time vs BVH | tests/ray |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|");
        for s in &r.sweep {
            println!(
                "| {} | {} | {} | {} | {:.1} | {:.2}x | {:.1} | {} | {:.2} | {:.2}x | {:.1} |",
                s.scene,
                s.tile,
                s.buckets,
                s.face,
                s.ms_build,
                s.build_vs_bvh,
                s.bytes as f64 / (1 << 20) as f64,
                s.entries,
                s.diffuse_mrays_per_s,
                s.diffuse_time_vs_bvh,
                s.tests_per_ray
            );
        }
    }
}

/// DIRT's piece of `parallax demo`: the path tracer with DIRT behind it and with the BVH, same
/// seed, on a small view; writes DIRT's image and the BVH's, and says how many hits agree.
pub fn demo_view(
    scene: &Scene,
    desc: &parallax_scene::CameraDesc,
    width: u32,
    height: u32,
    out: &std::path::Path,
) -> Result<DemoPiece> {
    let mut scene = scene.clone();
    apply_lighting(&mut scene, &LightOverrides::default())?;
    let (w, h) = ((width / 4).max(1), (height / 4).max(1));
    let camera = Camera::new(ModelKind::Pinhole, desc, w, h, &CameraOptions::default())?;
    let opts = PathOptions {
        spp: 2,
        seed: 1,
        max_depth: 5,
        ..PathOptions::default()
    };
    let (a, bvh, dirt) = path_agreement(&scene, &camera, &opts, &TracerOptions::default())?;
    super::path::write_path_image(&out.join("dirt_path_traced.png"), &dirt)?;
    super::path::write_path_image(&out.join("dirt_path_traced_bvh.png"), &bvh)?;
    let (rays, same) = a
        .bounces
        .iter()
        .fold((0, 0), |(r, s), b| (r + b.rays, s + b.same));
    let psnr = if a.psnr.is_finite() {
        format!("{:.0} dB", a.psnr)
    } else {
        "bit-identical".into()
    };
    Ok(DemoPiece {
        label: "dirt_path_traced".into(),
        section: section::PATH,
        title: "DIRT behind the path tracer".into(),
        what: format!(
            "the same path tracer and seed with DIRT's per-view primitive lists answering every ray: {:.4}% of {rays} hits = the BVH's, image vs the BVH's {psnr}",
            100.0 * same as f64 / rays.max(1) as f64
        ),
        size: format!("{w}x{h}"),
        spp: a.spp.to_string(),
        mrays: Some(rays as f64 / (a.ms_render_dirt * 1e3)),
        ms: a.ms_render_dirt + a.ms_build_dirt,
        images: vec!["dirt_path_traced.png".into()],
        truth: Some("dirt_path_traced_bvh.png".into()),
    })
}
