//! `parallax bench warp | upsample | compression`: the view-synthesis measurements of Widmer
//! et al. 2015 (Table 2, Table 3, Fig. 14/15). Markdown on stdout, rows as JSON with --json;
//! methods not available in this build give a row with the error.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use parallax_bvh::Bvh;
use parallax_synth::bench::{compression, upsample as up, warp};
use parallax_synth::method::{Method, cube_near_name};
use parallax_synth::upsample::{default_path, scene_path};

use crate::args::{
    MethodListArgs, SynthArgs, SynthSize, ViewArgs, frame_count, layer_count, parse_method,
};
use crate::output;
use crate::progress;

/// One DDA row of a sweep: (layers, max steps if the row has them, PSNR, % miss, % occlusion).
type DdaRow = (usize, Option<u32>, f64, f64, f64);

/// The DDA sweep of one layer count: (layers, [(max steps, PSNR, % miss, % occlusion)]).
type DdaSweep = (usize, Vec<(u32, f64, f64, f64)>);

/// Prints the minimal artifact-free DDA max steps of each layer count of a sweep.
fn print_dda_minimal(sweeps: &[DdaSweep]) {
    for (layers, sweep) in sweeps {
        if sweep.len() < 2 {
            continue;
        }
        if let Some(n) = warp::dda_minimal_steps(sweep) {
            let top = sweep.iter().map(|s| s.0).max().unwrap_or(0);
            println!(
                "dda {layers} layer(s): minimal max steps equivalent to {top} steps (PSNR within {} dB, at most {}% more misses / occlusion volumes): {n}",
                warp::DDA_EQUIV_PSNR_DB,
                warp::DDA_EQUIV_EXTRA_PCT
            );
        }
    }
}

/// Groups the DDA rows of a sweep per layer count: (max steps, PSNR, % miss, % occlusion).
fn dda_sweeps<'a>(rows: impl Iterator<Item = DdaRow> + 'a) -> Vec<DdaSweep> {
    let mut out: Vec<DdaSweep> = Vec::new();
    for (l, steps, p, m, o) in rows {
        let Some(n) = steps else { continue };
        match out.iter_mut().find(|(k, _)| *k == l) {
            Some((_, v)) => v.push((n, p, m, o)),
            None => out.push((l, vec![(n, p, m, o)])),
        }
    }
    out
}

pub(crate) fn cell(v: f64, digits: usize) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.digits$}")
    }
}

/// A stage reporter on stderr (silent with --quiet).
pub(crate) fn reporter(quiet: bool) -> impl Fn(&str) {
    let pb = progress::bar(0, "bench", quiet);
    move |msg: &str| pb.set_message(msg.to_string())
}

#[derive(Args, Debug)]
pub struct WarpBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    #[command(flatten)]
    pub methods: MethodListArgs,
    /// Rounds: each runs every method's warp and trace-only pass of both eyes once
    /// (interleaved); the best round of each method is reported.
    #[arg(long, default_value_t = 1)]
    pub repeats: u32,
    /// Instead of captured layers: warp the BVH render of the reference view and its depth
    /// as a user's colour + depth input (one layer, normals from depth, sky without depth),
    /// PSNR over the whole image, the surfaces and the sky (`parallax_synth::bench::input`).
    #[arg(long)]
    pub color_depth_input: bool,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn warp_bench(a: &WarpBenchArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.method_options()?;
    a.size
        .check_memory(a.methods.layers.iter().copied().max().unwrap_or(1))?;
    a.view.check_ipd()?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let setup = warp::StereoSetup {
        desc: a.view.camera_desc(&scene)?,
        width: a.size.width,
        height: a.size.height,
        ipd: a.view.ipd,
        shading: a.synth.shading(),
        seed: a.synth.seed,
        score: !a.synth.no_score,
        repeats: a.repeats.max(1),
    };
    if a.color_depth_input {
        let rows = parallax_synth::bench::input::run(
            &scene,
            &bvh,
            &setup,
            &a.methods.methods(),
            &opts,
            &reporter(quiet),
        )?;
        if !quiet {
            println!(
                "{} {}x{}, ipd {}, colour + depth input (1 layer, normals from depth), cube near {}",
                scene.name,
                a.size.width,
                a.size.height,
                a.view.ipd,
                cube_near_name(opts.cube_near)
            );
            println!("| method | PSNR dB | PSNR surfaces dB | PSNR sky dB | T_eye ms (both) |");
            println!("|---|---|---|---|---|");
            for r in &rows {
                println!(
                    "| {} | {:.2} | {:.2} | {} | {:.1} |",
                    r.method,
                    r.psnr,
                    r.psnr_surfaces,
                    cell(r.psnr_sky, 2),
                    r.ms_view
                );
            }
        }
        return output::write_json(a.json.as_deref(), &rows);
    }
    let rows = warp::run(
        &scene,
        &bvh,
        &setup,
        &a.methods.methods(),
        &a.methods.layers,
        &opts,
        &a.methods.dda_sweep,
        &reporter(quiet),
    )?;
    if !quiet {
        let near = rows.iter().find(|r| r.error.is_none());
        println!(
            "{} {}x{}, ipd {}, cube near: {}{}, {} threads, best of {} interleaved rounds per eye",
            scene.name,
            a.size.width,
            a.size.height,
            a.view.ipd,
            cube_near_name(opts.cube_near),
            near.map_or(String::new(), |r| format!(
                " ({:.3} m, far {:.1} m)",
                r.near_m, r.far_m
            )),
            rayon::current_num_threads(),
            setup.repeats
        );
        println!(
            "| method | layers | dda steps | T_ref ms | T_eye ms | T_total ms | Mrays/s | trace Mrays/s | trace Mrays/CPU-s | T_trace ms (% T_eye) | raygen ms | nodes/ray | % layer 2+ | % miss | % occl. | PSNR dB | SSIM | note |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            let steps = r.dda_max_steps.map_or("-".into(), |n| n.to_string());
            match &r.error {
                Some(e) => println!(
                    "| {} | {} | {steps} | - | - | - | - | - | - | - | - | - | - | - | - | - | - | {e} |",
                    r.method, r.layers
                ),
                None => println!(
                    "| {} | {} | {steps} | {:.1} | {:.2} | {:.1} | {:.2} | {} | {} | {} | {} | {:.2} | {:.2} | {:.3} | {:.3} | {} | {} | {} |",
                    r.method,
                    r.layers,
                    r.ms_ref,
                    r.ms_view,
                    r.ms_total,
                    r.mrays_per_s,
                    cell(r.trace_mrays_per_s, 2),
                    cell(r.trace_cpu_mrays_per_s, 2),
                    if r.ms_trace.is_nan() {
                        "-".into()
                    } else {
                        format!("{:.2} ({:.0}%)", r.ms_trace, 100.0 * r.ms_trace / r.ms_view)
                    },
                    cell(r.ms_raygen, 2),
                    r.nodes_per_ray,
                    r.pct_layer2,
                    r.pct_miss,
                    r.pct_occlusion,
                    cell(r.psnr, 2),
                    cell(r.ssim, 4),
                    truncation_note(&r.method, r.pct_truncated)
                ),
            }
        }
        print_ratios(&rows);
        print_dda_minimal(&dda_sweeps(rows.iter().filter(|r| r.error.is_none()).map(
            |r| {
                (
                    r.layers,
                    r.dda_max_steps,
                    r.psnr,
                    r.pct_miss,
                    r.pct_occlusion,
                )
            },
        )));
    }
    output::write_json(a.json.as_deref(), &rows)
}

/// The note of a row some of whose rays ran out of their traversal's step bound (they end
/// as misses or occlusion volumes: a DDA `max_steps` too small for the view).
fn truncation_note(method: &str, pct: f64) -> String {
    if !(pct > 0.0) {
        return String::new();
    }
    let hint = if method == "dda" {
        ": raise --dda-max-steps (--dda-sweep finds the minimal artifact-free value)"
    } else {
        ""
    };
    format!("{pct:.2}% of rays hit the step bound{hint}")
}

#[derive(Args, Debug)]
pub struct BuildBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    /// Interleaved rounds (stream, 1-layer build, 2-layer build); the best of each is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: u32,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// `parallax bench quadtree-build` (`parallax_synth::bench::build`).
pub fn build_bench(a: &BuildBenchArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.method_options()?;
    a.size.check_memory(2)?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let desc = a.view.camera_desc(&scene)?;
    let cam = parallax_scene::camera::Pinhole::new(&desc, a.size.width, a.size.height)?;
    let rows =
        parallax_synth::bench::build::run(&scene, &bvh, &cam, &opts, a.repeats, &reporter(quiet))?;
    if !quiet {
        println!(
            "{} {}x{}, cube near {}, {} threads, {} interleaved rounds (best round of each; per-round ratios: median [min, max])",
            scene.name,
            a.size.width,
            a.size.height,
            cube_near_name(opts.cube_near),
            rayon::current_num_threads(),
            a.repeats.max(1)
        );
        println!(
            "| layers | tree | build ms | stream ms | build / stream (best) | build / stream per round | nodes | plane nodes |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        let spread = |s: &parallax_synth::bench::build::Spread| {
            format!("{:.2}x [{:.2}, {:.2}]", s.median, s.min, s.max)
        };
        for r in &rows {
            println!(
                "| {} | {} | {:.2} | {:.3} | {:.1}x | {} | {} | {} |",
                r.layers,
                r.tree,
                r.ms_build,
                r.ms_stream,
                r.ratio,
                spread(&r.ratio_rounds),
                r.nodes,
                r.plane_nodes
            );
        }
        if let [one, fixed, _] = &rows[..] {
            println!(
                "1-layer build / stream in process CPU per round: {}",
                spread(&one.cpu_ratio_rounds)
            );
            println!(
                "fixed point (layer 0 of 2) / 1-layer build: {:.2}x best rounds, {} per round, {} per round in process CPU; its effective planes {:.2} ms (by a climb per pixel: {:.2} ms)",
                fixed.ms_build / one.ms_build,
                spread(&fixed.over_one_layer_rounds),
                spread(&fixed.cpu_over_one_layer_rounds),
                fixed.ms_effective_planes,
                fixed.ms_effective_planes_climb
            );
        }
    }
    output::write_json(a.json.as_deref(), &rows)
}

/// The quad-tree's throughput ratios to every other method of the same layer count (the
/// rounds are interleaved, so these compare like with like): whole warp (by `T_eye`, the
/// same pixels), trace-only Mrays/s (wall) and trace-only Mrays per CPU-second.
fn print_ratios(rows: &[warp::WarpRow]) {
    let ok = |r: &&warp::WarpRow| r.error.is_none();
    for qt in rows.iter().filter(ok).filter(|r| r.method == "quadtree") {
        let mut parts = Vec::new();
        for o in rows
            .iter()
            .filter(ok)
            .filter(|o| o.layers == qt.layers && o.method != "quadtree")
        {
            let ratio = |a: f64, b: f64| {
                let x = a / b;
                if x.is_finite() {
                    format!("{x:.2}x")
                } else {
                    "-".into()
                }
            };
            let name = match o.dda_max_steps {
                Some(n) => format!("{} ({n} steps)", o.method),
                None => o.method.clone(),
            };
            // Whole warp by T_eye (the same pixels; the mesh warp counts no rays).
            let warp = ratio(o.ms_view, qt.ms_view);
            parts.push(if o.trace_mrays_per_s.is_nan() {
                format!("/ {name}: warp {warp}")
            } else {
                format!(
                    "/ {name}: warp {warp}, trace {}, trace CPU {}",
                    ratio(qt.trace_mrays_per_s, o.trace_mrays_per_s),
                    ratio(qt.trace_cpu_mrays_per_s, o.trace_cpu_mrays_per_s)
                )
            });
        }
        if !parts.is_empty() {
            println!(
                "ratios, {} layer(s), quadtree speed {}",
                qt.layers,
                parts.join("; ")
            );
        }
    }
}

#[derive(Args, Debug)]
pub struct UpsampleBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    /// Output frames at 60 Hz (1..=100000).
    #[arg(long, default_value_t = 60, allow_negative_numbers = true, value_parser = frame_count)]
    pub frames: u32,
    #[command(flatten)]
    pub methods: MethodListArgs,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn upsample_bench(a: &UpsampleBenchArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.upsample_options()?;
    a.size
        .check_memory(a.methods.layers.iter().copied().max().unwrap_or(1))?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let path = if a.view.eye.is_some() || a.view.camera.is_some() {
        default_path(&a.view.camera_desc(&scene)?)?
    } else {
        scene_path(&scene)?
    };
    let setup = up::UpsampleSetup {
        width: a.size.width,
        height: a.size.height,
        frames: a.frames,
        shading: a.synth.shading(),
        seed: a.synth.seed,
        score: !a.synth.no_score,
    };
    let rows = up::run(
        &scene,
        &bvh,
        &path,
        &setup,
        &a.methods.methods(),
        &a.methods.layers,
        &opts,
        &a.methods.dda_sweep,
        &reporter(quiet),
    )?;
    if !quiet {
        let near = rows.iter().find(|r| r.error.is_none());
        println!(
            "{} {}x{}, {} frames at 60 Hz, a reference every 4th, cube near: {}{}",
            scene.name,
            a.size.width,
            a.size.height,
            a.frames,
            cube_near_name(opts.cube_near),
            near.map_or(String::new(), |r| format!(
                " ({:.3} m, far {:.1} m)",
                r.near_m, r.far_m
            )),
        );
        println!(
            "| method | layers | dda steps | T_ref ms | T_syn ms | T_amt ms | Mrays/s | nodes/ray | % layer 2+ | % miss | % occl. | PSNR dB | SSIM | note |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            let steps = r.dda_max_steps.map_or("-".into(), |n| n.to_string());
            match &r.error {
                Some(e) => println!(
                    "| {} | {} | {steps} | - | - | - | - | - | - | - | - | - | - | {e} |",
                    r.method, r.layers
                ),
                None => println!(
                    "| {} | {} | {steps} | {:.2} | {:.2} ± {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.3} | {:.3} | {} | {} | {} |",
                    r.method,
                    r.layers,
                    r.ms_ref,
                    r.ms_view,
                    r.ms_view_std,
                    r.ms_amortized,
                    r.mrays_per_s,
                    r.nodes_per_ray,
                    r.pct_layer2,
                    r.pct_miss,
                    r.pct_occlusion,
                    cell(r.psnr, 2),
                    cell(r.ssim, 4),
                    truncation_note(&r.method, r.pct_truncated)
                ),
            }
        }
        print_dda_minimal(&dda_sweeps(rows.iter().filter(|r| r.error.is_none()).map(
            |r| {
                (
                    r.layers,
                    r.dda_max_steps,
                    r.psnr,
                    r.pct_miss,
                    r.pct_occlusion,
                )
            },
        )));
    }
    output::write_json(a.json.as_deref(), &rows)
}

#[derive(Args, Debug)]
pub struct CompressionArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    /// The method whose compression is swept.
    #[arg(long, default_value = "quadtree", value_parser = parse_method)]
    pub method: Method,
    /// Depth layers (1..=8).
    #[arg(long, default_value_t = 1, value_parser = layer_count)]
    pub layers: usize,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn compression_bench(a: &CompressionArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.method_options()?;
    a.size.check_memory(a.layers)?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let setup = warp::StereoSetup {
        desc: a.view.camera_desc(&scene)?,
        width: a.size.width,
        height: a.size.height,
        ipd: a.view.ipd,
        shading: a.synth.shading(),
        seed: a.synth.seed,
        score: !a.synth.no_score,
        repeats: 1,
    };
    let rows = compression::run(
        &scene,
        &bvh,
        &setup,
        a.method,
        a.layers,
        &opts,
        &reporter(quiet),
    )?;
    if !quiet {
        println!(
            "{} {}x{}, {} {} layer(s), ipd {}, cube near: {}",
            scene.name,
            a.size.width,
            a.size.height,
            a.method,
            a.layers,
            a.view.ipd,
            cube_near_name(opts.cube_near)
        );
        println!(
            "| sweep | gamma_norm deg | gamma_dist | adaptive | build ms | T_eye ms | nodes/ray | PSNR dB | SSIM | note |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            let note = r.error.clone().unwrap_or_default();
            println!(
                "| {} | {:.0} | {:.0e} | {} | {:.2} | {:.2} | {:.2} | {} | {} | {note} |",
                r.sweep,
                r.gamma_norm_deg,
                r.gamma_dist,
                r.adaptive,
                r.ms_build,
                r.ms_view,
                r.nodes_per_ray,
                cell(r.psnr, 2),
                cell(r.ssim, 4)
            );
        }
    }
    output::write_json(a.json.as_deref(), &rows)
}
