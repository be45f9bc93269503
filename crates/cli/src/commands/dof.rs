//! `parallax dof` and `parallax bench dof`: thin-lens depth of field by screen-space ray
//! tracing through the layers of a lens-centre reference (Widmer et al. 2015, §5.2, Table 4,
//! Figs. 8-9), from a scene (scored against the converged BVH thin-lens image) or from a
//! colour + depth image pair.

use std::path::PathBuf;

use anyhow::{Context, Result, ensure};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::png;
use parallax_render::score::score;
use parallax_scene::camera::ThinLens;
use parallax_synth::bench::dof as bench_dof;
use parallax_synth::bench::dof_equal;
use parallax_synth::dof::setup::guard_px;
use parallax_synth::dof::truth::thin_lens_truth;
use parallax_synth::dof::{
    DEFAULT_SIGMA, DofOptions, DofSetup, DofStructure, capture_dof_reference, render_dof,
};
use parallax_synth::method::{Method, cube_near_name};
use parallax_synth::warp::Resample;

use super::bench_synth::{cell, reporter};
use crate::args::ViewArgs;
use crate::args::{SynthArgs, layer_count, parse_method};
use crate::output::write_json;
use crate::progress;

/// DDA max steps of the depth-of-field commands (`--dda-max-steps` overrides it): measured
/// with `bench dof --dda-sweep` (docs/notes/synth.md); Widmer et al. tuned 25.
pub const DDA_MAX_STEPS_DOF: u32 = 64;

/// Default aperture radius (m) of the depth-of-field commands when `--aperture` is not given.
pub const DEFAULT_APERTURE_M: f32 = 0.1;

/// Flags of the lens sampling shared by `dof` and `bench dof`.
#[derive(Args, Clone, Debug)]
pub struct LensArgs {
    /// Secondary-weight width sigma in relative depth (> 0): a secondary sample whose depth
    /// differs from the layer's by sigma of it weighs exp(-1).
    #[arg(long, default_value_t = DEFAULT_SIGMA)]
    pub sigma: f32,
    /// Lens samples per pixel of the BVH ground truth (the converged image).
    #[arg(long, default_value_t = 256)]
    pub truth_spp: u32,
    /// Secondary samples take their pixel's colour instead of the depth-aware bilinear colour
    /// at their hit (cheaper, noisier).
    #[arg(long)]
    pub secondary_nearest: bool,
    /// Guard band of the reference in pixels on each side (default: the largest circle of
    /// confusion of the view, probed with BVH rays; 0 with colour + depth input).
    #[arg(long)]
    pub guard: Option<u32>,
}

impl LensArgs {
    fn secondary_resample(&self) -> Resample {
        if self.secondary_nearest {
            Resample::Nearest
        } else {
            Resample::Bilinear
        }
    }
}

#[derive(Args, Debug)]
pub struct DofArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub lens: LensArgs,
    #[arg(long, default_value_t = 1600)]
    pub width: u32,
    #[arg(long, default_value_t = 900)]
    pub height: u32,
    /// Depth layers of the reference (1..=8).
    #[arg(long, default_value_t = 2)]
    pub layers: usize,
    /// quadtree, dda, minmax, hiz or brute.
    #[arg(long, default_value = "quadtree", value_parser = parse_method)]
    pub method: Method,
    /// Lens rays traced per pixel (N_pri).
    #[arg(long, default_value_t = 8)]
    pub n_pri: u32,
    /// Colour samples per lens ray including the traced one (N_sec; > 1 needs the quad-tree).
    #[arg(long, default_value_t = 1)]
    pub n_sec: u32,
    /// Output folder.
    #[arg(long, default_value = "out/dof")]
    pub out: PathBuf,
    /// Instead of a scene: a colour image (EXR R,G,B linear, or PNG sRGB) as the lens-centre
    /// view, one layer at its size, posed at --eye/--target/--up or the identity pose; not
    /// scored.
    #[arg(long, requires = "depth")]
    pub color: Option<PathBuf>,
    /// ... and its view depth (EXR channel Z, depth, Y or R).
    #[arg(long, requires = "color")]
    pub depth: Option<PathBuf>,
    /// Colour + depth input: focal length in pixels (else --fov-y, default 60 degrees).
    #[arg(long, conflicts_with = "fov_y")]
    pub focal_px: Option<f32>,
}

fn method_options(s: &SynthArgs) -> Result<parallax_synth::MethodOptions> {
    let mut o = s.method_options()?;
    o.dda_max_steps = s.dda_max_steps.unwrap_or(DDA_MAX_STEPS_DOF);
    Ok(o)
}

fn aperture(v: &ViewArgs) -> f32 {
    v.aperture.unwrap_or(DEFAULT_APERTURE_M)
}

pub fn run(a: &DofArgs, quiet: bool) -> Result<()> {
    ensure!(
        (1..=8).contains(&a.layers),
        "--layers must be in 1..=8, got {}",
        a.layers
    );
    let opts = method_options(&a.synth)?;
    let dof_opts = DofOptions {
        n_pri: a.n_pri,
        n_sec: a.n_sec,
        sigma: a.lens.sigma,
        seed: a.synth.seed,
        warp: opts.warp,
        secondary_resample: a.lens.secondary_resample(),
    };
    dof_opts.validate()?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let pb = progress::bar(4, "dof", quiet);
    let (mut reference, setup, scene) = match (&a.color, &a.depth) {
        (Some(c), Some(d)) => {
            let (r, desc) = super::input::load_color_depth(&a.view, c, d, a.focal_px)?;
            let lens = ThinLens::new(
                &desc,
                r.width(),
                r.height(),
                aperture(&a.view),
                a.view.focus,
            )?;
            let setup = DofSetup { lens, guard: 0 };
            (r, setup, None)
        }
        _ => {
            pb.set_message("reference");
            let scene = a.view.load_scene()?;
            let bvh = Bvh::try_build(&scene.mesh)?;
            let desc = a.view.camera_desc(&scene)?;
            let lens = ThinLens::new(&desc, a.width, a.height, aperture(&a.view), a.view.focus)?;
            let guard = a.lens.guard.unwrap_or_else(|| guard_px(&bvh, &lens));
            let setup = DofSetup { lens, guard };
            let r = capture_dof_reference(
                &scene,
                &bvh,
                &setup,
                a.layers,
                a.synth.shading(),
                a.synth.seed,
            )?;
            (r, setup, Some((scene, bvh)))
        }
    };
    pb.inc(1);
    reference.fit_cube(opts.cube_near)?;
    pb.set_message(a.method.name());
    let t = std::time::Instant::now();
    let structure = DofStructure::build(a.method, &reference, &opts)?;
    reference.times.build_ms = t.elapsed().as_secs_f64() * 1e3;
    let img = render_dof(&structure, &reference, &setup.lens, &dof_opts)?;
    pb.inc(1);
    let mut written = Vec::new();
    let tm = super::input::output_tonemap(scene.is_none());
    let mut save = |name: &str, im: &parallax_core::Image<parallax_core::Rgb>| -> Result<()> {
        let p = a.out.join(name);
        png::write_png(&p, im, &tm)?;
        written.push(p);
        Ok(())
    };
    save("dof.png", &img.image)?;
    save("reference.png", &reference.colors[0])?;
    let scored = match (&scene, a.synth.no_score) {
        (Some((scene, bvh)), false) => {
            pb.set_message("BVH lens");
            let truth = thin_lens_truth(
                scene,
                bvh,
                &setup.lens,
                a.lens.truth_spp,
                a.synth.shading(),
                a.synth.seed,
            )?;
            save("dof.bvh.png", &truth)?;
            Some(score(&img.image, &truth)?)
        }
        _ => None,
    };
    pb.finish_and_clear();
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        let t = reference.times;
        println!(
            "{} {} layer(s), {}x{} (guard {} px), aperture {} m, focus {:.2} m, N_pri/N_sec {}/{}, cube near {}: T_ref {:.1} ms (capture {:.1}, shade {:.1}, build {:.1}), T_dof {:.1} ms, {:.2} Mrays/s, {:.2}% from layer 2+, {:.2}% miss, {:.2}% occlusion{}",
            a.method,
            reference.layers.len(),
            setup.lens.pinhole.width,
            setup.lens.pinhole.height,
            setup.guard,
            setup.lens.aperture_radius,
            setup.lens.focus_distance,
            a.n_pri,
            a.n_sec,
            cube_near_name(reference.cube_near),
            t.total_ms(),
            t.capture_ms,
            t.shade_ms,
            t.build_ms,
            img.ms,
            img.mrays_per_s(),
            img.pct_deep(),
            100.0 * img.misses as f64 / img.lens_rays.max(1) as f64,
            100.0 * img.occlusions as f64 / img.lens_rays.max(1) as f64,
            if a.n_sec > 1 {
                format!(", secondary weight {:.3}", img.secondary.mean_weight())
            } else {
                String::new()
            }
        );
        if let Some(s) = scored {
            println!(
                "vs BVH thin lens ({} spp): PSNR {:.2} dB, SSIM {:.4}",
                a.lens.truth_spp, s.psnr, s.ssim
            );
        }
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct DofBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub lens: LensArgs,
    #[arg(long, default_value_t = 800)]
    pub width: u32,
    #[arg(long, default_value_t = 450)]
    pub height: u32,
    /// Comma list of methods (quadtree, dda, minmax, hiz, brute).
    #[arg(long, value_delimiter = ',', default_value = "quadtree,dda", value_parser = parse_method)]
    pub method: Vec<Method>,
    /// Comma list of layer counts (each 1..=8).
    #[arg(long, value_delimiter = ',', default_value = "1,2", value_parser = layer_count)]
    pub layers: Vec<usize>,
    /// DDA: one set of rows per max-steps value of this comma list (e.g. 8,16,25,32,64,100000)
    /// instead of --dda-max-steps, and the minimal artifact-free value is printed.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub dda_sweep: Vec<u32>,
    /// Also run Fig. 8 (equal-time noise of plain lens sampling and secondary samples,
    /// quad-tree with the largest layer count).
    #[arg(long)]
    pub fig8: bool,
    /// Instead of Table 4: the quad-tree and the DDA (at --equal-quality-dda-steps) at the
    /// lens-ray counts of --equal-quality-n-pri in the same interleaved rounds, and the DDA's
    /// CPU time interpolated at each quad-tree row's PSNR (time at equal quality).
    #[arg(long)]
    pub equal_quality: bool,
    /// --equal-quality: comma list of lens rays per pixel (N_sec 1) of both methods.
    #[arg(long, value_delimiter = ',', default_value = "2,3,4,5,6,8,10,12", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub equal_quality_n_pri: Vec<u32>,
    /// --equal-quality: the DDA's step bound (default: the first --dda-sweep value, else
    /// --dda-max-steps).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub equal_quality_dda_steps: Option<u32>,
    /// Fig. 8: lens rays per pixel of the quad-tree's own converged image (noise reference).
    #[arg(long, default_value_t = 256)]
    pub own_spp: u32,
    /// Also render every structure of Table 4 with this many lens rays per pixel and no
    /// secondaries (0: none): nearly noise-free, so what is left of the error against the
    /// BVH is the layers' (Fig. 9: one layer, inpainting, two layers).
    #[arg(long, default_value_t = 0)]
    pub converged: u32,
    /// Interleaved timing rounds (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn bench(a: &DofBenchArgs, quiet: bool) -> Result<()> {
    let layers = a.layers.clone();
    let methods = a.method.clone();
    ensure!(!methods.is_empty(), "--method needs at least one method");
    ensure!(
        !methods.contains(&Method::Mesh),
        "the mesh warp is not a tracer: no depth of field"
    );
    let opts = method_options(&a.synth)?;
    DofOptions {
        sigma: a.lens.sigma,
        ..DofOptions::default()
    }
    .validate()?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let desc = a.view.camera_desc(&scene)?;
    let lens = ThinLens::new(&desc, a.width, a.height, aperture(&a.view), a.view.focus)?;
    let guard = a.lens.guard.unwrap_or_else(|| guard_px(&bvh, &lens));
    let b = bench_dof::DofBench {
        setup: DofSetup { lens, guard },
        shading: a.synth.shading(),
        seed: a.synth.seed,
        truth_spp: a.lens.truth_spp,
        repeats: a.repeats.max(1),
        cube_near: opts.cube_near,
        sigma: a.lens.sigma,
        secondary_resample: a.lens.secondary_resample(),
    };
    let progress = reporter(quiet);
    progress(&format!("BVH thin lens, {} spp", b.truth_spp));
    let truth = bench_dof::truth(&scene, &bvh, &b)?;
    let mut steps = a.dda_sweep.clone();
    if steps.is_empty() {
        steps.push(opts.dda_max_steps);
    }
    let eq_steps = a.equal_quality_dda_steps.unwrap_or(steps[0]);
    let entries = if a.equal_quality {
        ensure!(
            methods.contains(&Method::QuadTree) && methods.contains(&Method::Dda),
            "--equal-quality compares the quad-tree with the DDA: --method needs both"
        );
        ensure!(
            !a.equal_quality_n_pri.is_empty(),
            "--equal-quality-n-pri needs at least one value"
        );
        dof_equal::entries(&layers, &a.equal_quality_n_pri, eq_steps)
    } else {
        bench_dof::table4_entries(&layers, &steps, &methods)
    };
    let rows = bench_dof::run(&scene, &bvh, &b, &entries, &opts, &truth, &progress)?;
    let mut all: Vec<bench_dof::DofRow> = rows.into_iter().map(|(r, _)| r).collect();
    if a.equal_quality {
        dof_equal::analyse(&mut all, eq_steps);
    }
    if !quiet {
        println!(
            "{} {}x{} (guard {} px), aperture {} m, focus {:.2} m, sigma {}, truth {} spp, cube near {}, {} threads, best of {} interleaved rounds",
            scene.name,
            a.width,
            a.height,
            guard,
            b.setup.lens.aperture_radius,
            b.setup.lens.focus_distance,
            b.sigma,
            b.truth_spp,
            cube_near_name(opts.cube_near),
            rayon::current_num_threads(),
            b.repeats
        );
        if a.equal_quality {
            print_rows("Equal-quality sweep (plain lens sampling)", &all, false);
            println!(
                "\nQuad-tree vs the DDA at equal quality (same run, CPU ms; DDA time interpolated on log time vs PSNR between its rows bracketing the quad-tree's PSNR, never extrapolated)\n"
            );
            println!("{}", dof_equal::markdown(&all));
        } else {
            print_rows("Table 4", &all, false);
            print_dda_minimal(&all);
            print_vs_dda(&all);
        }
    }
    if a.converged > 0 {
        let mut seen = Vec::new();
        let conv: Vec<bench_dof::DofEntry> = entries
            .iter()
            .filter(|e| {
                let k = (e.method, e.layers, e.inpaint, e.dda_max_steps);
                let new = !seen.contains(&k);
                seen.push(k);
                new
            })
            .map(|e| bench_dof::DofEntry {
                n_pri: a.converged,
                n_sec: 1,
                ..*e
            })
            .collect();
        let rows = bench_dof::run(&scene, &bvh, &b, &conv, &opts, &truth, &progress)?;
        let rows: Vec<_> = rows.into_iter().map(|(r, _)| r).collect();
        if !quiet {
            print_rows("Converged lens sampling (Fig. 9)", &rows, false);
        }
        all.extend(rows);
    }
    if a.fig8 {
        let n = *layers.iter().max().expect("at least one layer count");
        let entries = bench_dof::fig8_entries(n, false);
        let mut rows = bench_dof::run(&scene, &bvh, &b, &entries, &opts, &truth, &progress)?;
        progress(&format!(
            "quadtree {} lens rays (own converged image)",
            a.own_spp
        ));
        let own = bench_dof::run(
            &scene,
            &bvh,
            &bench_dof::DofBench {
                repeats: 1,
                ..b.clone()
            },
            &[bench_dof::DofEntry {
                n_pri: a.own_spp,
                n_sec: 1,
                ..entries[0]
            }],
            &opts,
            &truth,
            &progress,
        )?;
        let own_img = own.first().and_then(|(_, i)| i.as_ref()).map(|i| &i.image);
        bench_dof::equal_time(&mut rows, own_img);
        let fig8: Vec<_> = rows.into_iter().map(|(r, _)| r).collect();
        if !quiet {
            print_rows("Fig. 8 (equal time)", &fig8, true);
        }
        all.extend(fig8);
    }
    write_json(a.json.as_deref(), &all)
}

fn print_rows(title: &str, rows: &[bench_dof::DofRow], fig8: bool) {
    println!("\n{title}\n");
    println!(
        "| method | layers | N_pri/N_sec | dda steps | T_ref ms | T_dof ms | T_dof CPU ms | Mrays/s | Mrays/CPU-s | FPS | nodes/ray | % layer 2+ | % miss | % occl. | sec. weight | PSNR dB | SSIM | PSNR edges dB |{} note |",
        if fig8 {
            " PSNR vs own dB | PSNR plain, equal time |"
        } else {
            ""
        }
    );
    println!(
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|{}---|",
        if fig8 { "---|---|" } else { "" }
    );
    for r in rows {
        let steps = r.dda_max_steps.map_or("-".into(), |n| n.to_string());
        let extra = if fig8 {
            format!(
                " {} | {} |",
                cell(r.psnr_self, 2),
                cell(r.psnr_equal_time, 2)
            )
        } else {
            String::new()
        };
        match &r.error {
            Some(e) => println!(
                "| {} | {} | {}/{} | {steps} | - | - | - | - | - | - | - | - | - | - | - | - | - | - |{} {e} |",
                r.method,
                r.layers,
                r.n_pri,
                r.n_sec,
                if fig8 { " - | - |" } else { "" }
            ),
            None => println!(
                "| {} | {} | {}/{} | {steps} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {:.2} | {:.4} | {} |{extra} {} |",
                r.method,
                r.layers,
                r.n_pri,
                r.n_sec,
                r.ms_ref,
                r.ms_dof,
                r.ms_dof_cpu,
                r.mrays_per_s,
                r.mrays_per_cpu_s,
                r.fps,
                r.nodes_per_ray,
                r.pct_layer2,
                r.pct_miss,
                r.pct_occlusion,
                cell(r.secondary_weight, 3),
                r.psnr,
                r.ssim,
                cell(r.psnr_edges, 2),
                if r.pct_truncated > 0.0 {
                    format!("{:.2}% of rays hit the step bound", r.pct_truncated)
                } else {
                    String::new()
                }
            ),
        }
    }
}

/// The minimal artifact-free DDA max steps per layer count and `N_pri` of a sweep (the
/// criterion of `bench warp`).
fn print_dda_minimal(rows: &[bench_dof::DofRow]) {
    let mut keys: Vec<(usize, u32)> = rows
        .iter()
        .filter(|r| r.dda_max_steps.is_some() && r.error.is_none())
        .map(|r| (r.layers, r.n_pri))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    for (l, p) in keys {
        let sweep: Vec<(u32, f64, f64, f64)> = rows
            .iter()
            .filter(|r| r.layers == l && r.n_pri == p && r.error.is_none())
            .filter_map(|r| {
                r.dda_max_steps
                    .map(|n| (n, r.psnr, r.pct_miss, r.pct_occlusion))
            })
            .collect();
        if sweep.len() < 2 {
            continue;
        }
        if let Some(n) = parallax_synth::bench::warp::dda_minimal_steps(&sweep) {
            println!(
                "dda {l} layer(s), N_pri {p}: minimal artifact-free max steps {n} (PSNR within {} dB of the largest value, at most {}% more misses / occlusion volumes)",
                parallax_synth::bench::warp::DDA_EQUIV_PSNR_DB,
                parallax_synth::bench::warp::DDA_EQUIV_EXTRA_PCT
            );
        }
    }
}

/// Quad-tree against the DDA in the same run, per layer count and `N_pri` (plain lens
/// sampling): the DDA at the step bound of its sweep with the best PSNR (its best quality),
/// CPU times and their ratio next to both methods' PSNR / SSIM: the ratio of the best rounds,
/// and the median (and range) of the ratios round by round (the two ran back to back in each
/// round, `bench_dof::run`: robust to load changes between rounds). "Equal quality" holds where
/// the DDA's best PSNR reaches the quad-tree's; where it does not, the ratio compares the
/// quad-tree's better image with the DDA's best one.
fn print_vs_dda(rows: &[bench_dof::DofRow]) {
    let ok = |r: &&bench_dof::DofRow| r.error.is_none() && r.n_sec == 1;
    let qts: Vec<&bench_dof::DofRow> = rows
        .iter()
        .filter(ok)
        .filter(|r| r.method == "quadtree")
        .collect();
    let mut header = false;
    for q in qts {
        let best = rows
            .iter()
            .filter(ok)
            .filter(|r| r.method == "dda" && r.layers == q.layers && r.n_pri == q.n_pri)
            .max_by(|a, b| a.psnr.total_cmp(&b.psnr));
        let Some(d) = best else { continue };
        if !header {
            println!("\nQuad-tree vs the DDA at its best step bound (same run, CPU ms)\n");
            println!(
                "| layers | N_pri | quad-tree PSNR dB / SSIM | quad-tree CPU ms | DDA steps | DDA PSNR dB / SSIM | DDA CPU ms | CPU ratio quad-tree / DDA (best of rounds each) | median of per-round ratios | per-round range | DDA reaches the quad-tree's PSNR |"
            );
            println!("|---|---|---|---|---|---|---|---|---|---|---|");
            header = true;
        }
        let mut ratios: Vec<f64> = q
            .ms_dof_cpu_rounds
            .iter()
            .zip(&d.ms_dof_cpu_rounds)
            .map(|(a, b)| a / b)
            .collect();
        ratios.sort_by(f64::total_cmp);
        let median = match ratios.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => ratios[n / 2],
            n => 0.5 * (ratios[n / 2 - 1] + ratios[n / 2]),
        };
        let range = match (ratios.first(), ratios.last()) {
            (Some(a), Some(b)) => format!("{a:.3}-{b:.3}"),
            _ => "-".into(),
        };
        println!(
            "| {} | {} | {:.2} / {:.4} | {:.1} | {} | {:.2} / {:.4} | {:.1} | {:.3} | {median:.3} | {range} | {} |",
            q.layers,
            q.n_pri,
            q.psnr,
            q.ssim,
            q.ms_dof_cpu,
            d.dda_max_steps.map_or("-".into(), |n| n.to_string()),
            d.psnr,
            d.ssim,
            d.ms_dof_cpu,
            q.ms_dof_cpu / d.ms_dof_cpu,
            if d.psnr >= q.psnr {
                "yes".to_string()
            } else {
                format!("no ({:+.2} dB)", d.psnr - q.psnr)
            }
        );
    }
}
