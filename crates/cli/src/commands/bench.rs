//! `parallax bench ...`: measurements printed as a Markdown table and optionally saved as JSON.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};
use parallax_render::bench::rays;

use crate::args::ViewArgs;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// BVH build ms and closest-hit Mrays/s for primary (coherent) and random (incoherent) rays.
    Rays(RaysArgs),
    /// HVVR Tables 2-6: VR frame stage times, shade counts, Mrays/s vs the per-ray baseline.
    Vr(super::bench_vr::VrBenchArgs),
    /// Stereo warping per method and layer count (Widmer et al. 2015, Table 2).
    Warp(super::bench_synth::WarpBenchArgs),
    /// 15 -> 60 Hz temporal upsampling per method and layer count (Widmer et al. 2015, Table 3).
    Upsample(super::bench_synth::UpsampleBenchArgs),
    /// Quad-tree compression thresholds vs time and PSNR (Widmer et al. 2015, Fig. 14/15).
    Compression(super::bench_synth::CompressionArgs),
    /// Path tracer: paths/s, Mrays/s per bounce, RMSE vs a high-spp reference at equal time.
    Path(super::path::PathBenchArgs),
    /// DIRT Tables 1-3 (Vardis et al. 2017): DIRT vs BVH build, Mrays/s per ray type, memory.
    Dirt(super::bench_dirt::DirtBenchArgs),
    /// Layered depth cube build and trace vs the BVH on the same rays (Bürger et al. 2007, Table 1).
    Ldc(super::secondary::LdcBenchArgs),
    /// Depth of field per N_pri/N_sec, layer count and method (Widmer et al. 2015, Table 4, Fig. 8).
    Dof(super::dof::DofBenchArgs),
    /// Stereo and temporal sample reprojection (Mäkitalo et al. 2019, Tables 1-2): % discarded, effective spp.
    Reproject(super::reproject::ReprojectBenchArgs),
    /// Cube-map reflections per N_p/N_s/N_b and layer count, quad-tree vs DDA vs BVH (Widmer et al. 2015, Table 5).
    Reflect(super::reflect::ReflectBenchArgs),
    /// Quad-tree build of one layer and the cascade's fixed point vs streaming the layer once (Widmer et al. 2015, §3.3).
    QuadtreeBuild(super::bench_synth::BuildBenchArgs),
}

#[derive(Args, Debug)]
pub struct RaysArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Timed repetitions per mode (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Leave out the 16-subsamples-per-pixel (MSAA packet) mode.
    #[arg(long)]
    pub no_msaa: bool,
    /// Embree's build quality for the traced scene: low, medium or high.
    #[arg(long, default_value = "high", value_parser = parse_quality)]
    pub embree_quality: parallax_embree::Quality,
    /// Comma list of methods (default all): single, packet16, packet64, single4, packet4,
    /// embree1, embree8, embree16, embree1m. `single` (the reference) always runs.
    #[arg(long, value_delimiter = ',', value_parser = parse_method)]
    pub methods: Vec<rays::Method>,
    /// Build parallax's BVH without spatial splits (the object-split tree, each triangle in
    /// one leaf); the default build is the SBVH.
    #[arg(long)]
    pub no_spatial_splits: bool,
    /// Accepted for older scripts: spatial splits are the default.
    #[arg(long, hide = true, conflicts_with = "no_spatial_splits")]
    pub spatial_splits: bool,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

fn parse_method(s: &str) -> Result<rays::Method, String> {
    rays::Method::parse(s).ok_or_else(|| format!("unknown method {s}"))
}

fn parse_quality(s: &str) -> Result<parallax_embree::Quality, String> {
    s.parse()
        .map_err(|e: parallax_embree::EmbreeError| e.to_string())
}

fn print_rays(rows: &[rays::RaysRow], embree_missing: Option<&str>) {
    println!(
        "| scene | mode | method | rays | build ms | trace ms | Mrays/s | vs Embree best \
         | per round: median [min, max] | same prim | same t | hit rate | threads |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let vs = r.vs_embree_best.map_or("-".into(), |v| format!("{v:.2}x"));
        let per_round = r.vs_embree_best_rounds.map_or("-".into(), |s| {
            format!("{:.2}x [{:.2}, {:.2}]", s.median, s.min, s.max)
        });
        println!(
            "| {} | {} | {} | {} | {:.1} | {:.1} | {:.2} | {vs} | {per_round} | {:.4}% | {:.4}% | {:.3} | {} |",
            r.scene,
            r.mode,
            r.method,
            r.rays,
            r.build_ms,
            r.trace_ms,
            r.mrays_per_s,
            100.0 * r.same_prim,
            100.0 * r.same_t,
            r.hit_rate,
            r.threads
        );
    }
    if let Some(why) = embree_missing {
        println!("\nNo Embree rows: {why}");
    }
}

pub fn run(cmd: &BenchCommand, quiet: bool) -> Result<()> {
    match cmd {
        BenchCommand::Vr(a) => super::bench_vr::bench(a, quiet),
        BenchCommand::Warp(a) => super::bench_synth::warp_bench(a, quiet),
        BenchCommand::Upsample(a) => super::bench_synth::upsample_bench(a, quiet),
        BenchCommand::Compression(a) => super::bench_synth::compression_bench(a, quiet),
        BenchCommand::Path(a) => super::path::bench(a, quiet),
        BenchCommand::Dirt(a) => super::bench_dirt::run_bench(a, quiet),
        BenchCommand::Ldc(a) => super::secondary::bench(a, quiet),
        BenchCommand::Dof(a) => super::dof::bench(a, quiet),
        BenchCommand::Reproject(a) => super::reproject::bench(a, quiet),
        BenchCommand::Reflect(a) => super::reflect::bench(a, quiet),
        BenchCommand::QuadtreeBuild(a) => super::bench_synth::build_bench(a, quiet),
        BenchCommand::Rays(a) => {
            let scene = a.view.load_scene()?;
            let camera = a.view.camera(&scene, a.width, a.height)?;
            let opts = rays::RaysOptions {
                repeats: a.repeats,
                msaa: !a.no_msaa,
                embree_quality: a.embree_quality,
                methods: a.methods.clone(),
                bvh: parallax_bvh::BuildOptions {
                    spatial_splits: !a.no_spatial_splits,
                    ..Default::default()
                },
            };
            let report = rays::run(&scene, &camera, &opts)?;
            let rows = report.rows;
            if !quiet {
                print_rays(&rows, report.embree_missing.as_deref());
            }
            if let Some(p) = &a.json {
                std::fs::write(p, serde_json::to_string_pretty(&rows)?)
                    .with_context(|| format!("writing {}", p.display()))?;
            }
            Ok(())
        }
    }
}
