//! `parallax render`: the BVH reference renderer for any scene and camera model.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_render::reference::{self, RenderOptions};
use parallax_render::{RunStats, StageTimer};
use parallax_scene::camera::CameraModel;

use crate::args::ViewArgs;
use crate::output::{self, Aov};
use crate::progress;

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Image width in pixels (per eye for stereo, per face for cube maps).
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Samples per pixel.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Seed of the per-pixel random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output image: .png (tonemapped sRGB) or .exr (linear, AOVs as channels).
    #[arg(long, default_value = "out/render.png")]
    pub out: PathBuf,
    /// G-buffer channels to write: comma list of depth, normal, albedo, id.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub aov: Vec<Aov>,
    /// Write run statistics (rays, seconds, Mrays/s, build and stage ms) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
}

pub fn run(a: &RenderArgs, quiet: bool) -> Result<()> {
    output::check_image_path(&a.out)?;
    let aovs = &a.aov;
    anyhow::ensure!(
        a.spp >= 1 && a.spp <= 1 << 16,
        "--spp must be in 1..=65536, got {}",
        a.spp
    );
    let start = Instant::now();
    let mut timer = StageTimer::new();
    let scene = a.view.load_scene()?;
    timer.stage("load");
    let camera = a.view.camera(&scene, a.width, a.height)?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let build_ms = timer.stage("bvh_build");
    let (w, h) = (camera.width(), camera.height());
    let pb = progress::bar(w as u64 * h as u64, "render", quiet);
    let opts = RenderOptions {
        spp: a.spp,
        seed: a.seed,
        gbuffer: !aovs.is_empty(),
    };
    let out = reference::render(&scene, &bvh, &camera, &opts, &|n| pb.inc(n));
    pb.finish_and_clear();
    let trace_ms = timer.stage("trace");
    let written = output::write_render(&a.out, &out.image, out.gbuffer.as_ref(), aovs)?;
    timer.stage("write");
    let stats = RunStats {
        scene: scene.name.clone(),
        camera_model: a.view.model.name().into(),
        width: w,
        height: h,
        spp: a.spp,
        triangles: scene.mesh.triangle_count(),
        rays: out.rays,
        seconds: start.elapsed().as_secs_f64(),
        mrays_per_s: out.rays as f64 / (trace_ms * 1e3),
        build_ms,
        threads: rayon::current_num_threads(),
        stages: timer.stages,
    };
    if let Some(p) = &a.stats {
        let json = serde_json::to_string_pretty(&stats)?;
        std::fs::write(p, json).with_context(|| format!("writing {}", p.display()))?;
    }
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        println!(
            "{}: {} triangles, {}x{} {} spp, {:.1} Mrays/s ({} rays), BVH {:.1} ms, total {:.2} s",
            stats.scene,
            stats.triangles,
            w,
            h,
            a.spp,
            stats.mrays_per_s,
            stats.rays,
            build_ms,
            stats.seconds
        );
    }
    Ok(())
}
