//! `parallax path`: the reference path tracer (or any `--tracer` behind the world-space
//! interface), progressive, with a sample count or a time budget, EXR with variance and
//! sample-count channels or a tonemapped PNG.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use parallax_core::image::exr;
use parallax_path::options::MAX_SPP;
use parallax_path::{
    LightOverrides, PathOptions, PathOutput, PathTracer, TracerKind, TracerOptions, apply_lighting,
    build_tracer,
};
use parallax_render::bsdf::MaterialMode;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};

use crate::args::ViewArgs;
use crate::demo_piece::{DemoPiece, section};
use crate::output;
use crate::progress;

/// The path tracer's flags (shared by `parallax path` and `parallax bench path`).
#[derive(Args, Clone, Debug)]
pub struct PathFlags {
    /// Samples (paths) per pixel [default: 16; with --time-budget: as many as fit].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Render whole passes until this many seconds are spent (at least one sample per pixel).
    #[arg(long, allow_negative_numbers = true)]
    pub time_budget: Option<f64>,
    /// Seed of the per-pixel random streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Longest path in segments, as Mitsuba 3's max_depth (1: emitters seen directly, 2: direct
    /// light only).
    #[arg(long, default_value_t = 16)]
    pub max_depth: u32,
    /// Depth from which Russian roulette may end paths (Mitsuba 3's rr_depth).
    #[arg(long, default_value_t = 5)]
    pub rr_depth: u32,
    /// Probability that a path vertex connects to the constant environment (next-event
    /// estimation, MIS-weighted against BSDF sampling), in [0, 1].
    #[arg(long, default_value_t = parallax_path::light_sampler::DEFAULT_ENV_NEE)]
    pub env_nee: f32,
    /// The structure that answers the rays: bvh or dirt.
    #[arg(long, default_value = "bvh")]
    pub tracer: String,
    /// DIRT: cube face size in pixels [default: 128].
    #[arg(long)]
    pub dirt_face: Option<u32>,
    /// DIRT: tile size S (a power of two), one primitive list per S x S pixels [default: 4 for
    /// the cube faces, 8 for the camera view; given alone, S of every view].
    #[arg(long)]
    pub dirt_tile: Option<u32>,
    /// DIRT: the camera view's tile size S [default: 8, or `--dirt-tile` when that is given].
    #[arg(long)]
    pub dirt_camera_tile: Option<u32>,
    /// DIRT: depth buckets B per cell [default: 16].
    #[arg(long)]
    pub dirt_buckets: Option<u32>,
    /// as-is (the scene's materials) or diffuse (every opaque surface Lambertian with its base
    /// colour or texture; glass a thin dielectric of index 1.5).
    #[arg(long, default_value = "as-is")]
    pub materials: String,
    /// Constant environment radiance `R[,G,B]` (as Mitsuba's constant emitter). Any light
    /// override replaces the scene's analytic lights and environment.
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true)]
    pub env: Option<Vec<f32>>,
    /// A point light at x,y,z (repeatable; write --point=-1,2,3 for a leading minus).
    #[arg(long, allow_negative_numbers = true)]
    pub point: Vec<String>,
    /// Radiant intensity `I[,I,I]` in W/sr of each --point (once for all, or once per point).
    #[arg(long, allow_negative_numbers = true)]
    pub point_intensity: Vec<String>,
}

#[derive(Args, Debug)]
pub struct PathArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    #[command(flatten)]
    pub path: PathFlags,
    /// Output image: .exr (linear RGB + variance.R/G/B + samples, and a .preview.png) or .png
    /// (tonemapped sRGB).
    #[arg(long, default_value = "out/path.png")]
    pub out: PathBuf,
    /// Write run statistics (spp, seconds, paths/s, rays per bounce) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Also write the scene, camera and lights as a Mitsuba 3 cross-check reads them
    /// (PLY meshes, EXR textures, scene.json) into this folder.
    #[arg(long)]
    pub export_mitsuba: Option<PathBuf>,
}

fn floats(flag: &str, s: &str) -> Result<Vec<f32>> {
    s.split(',')
        .map(|t| {
            t.trim()
                .parse::<f32>()
                .with_context(|| format!("--{flag} expects comma-separated numbers, got {s:?}"))
        })
        .collect()
}

fn rgb(flag: &str, v: &[f32]) -> Result<Vec3> {
    match v {
        [x] => Ok(Vec3::splat(*x)),
        [r, g, b] => Ok(Vec3::new(*r, *g, *b)),
        _ => bail!("--{flag} expects one value or three (R,G,B), got {v:?}"),
    }
}

impl PathFlags {
    /// The light overrides of the flags.
    pub fn overrides(&self) -> Result<LightOverrides> {
        let env = self.env.as_deref().map(|v| rgb("env", v)).transpose()?;
        let intensities = self
            .point_intensity
            .iter()
            .map(|s| rgb("point-intensity", &floats("point-intensity", s)?))
            .collect::<Result<Vec<_>>>()?;
        if !self.point.is_empty() && intensities.is_empty() {
            bail!("--point needs --point-intensity");
        }
        if intensities.len() > 1 && intensities.len() != self.point.len() {
            bail!(
                "--point-intensity given {} times for {} --point lights: give it once or once per point",
                intensities.len(),
                self.point.len()
            );
        }
        if self.point.is_empty() && !intensities.is_empty() {
            bail!("--point-intensity needs --point");
        }
        let points = self
            .point
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let v = floats("point", p)?;
                let [x, y, z] = v[..] else {
                    bail!("--point expects x,y,z, got {p:?}");
                };
                Ok((
                    Vec3::new(x, y, z),
                    intensities[i.min(intensities.len() - 1)],
                ))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(LightOverrides { env, points })
    }

    /// The tracers' options of the flags (out-of-range values are reported by the build).
    pub fn tracer_options(&self) -> TracerOptions {
        let mut o = TracerOptions::default();
        o.dirt = o
            .dirt
            .with_tile_flags(self.dirt_tile, self.dirt_camera_tile);
        let d = &mut o.dirt;
        d.face_size = self.dirt_face.unwrap_or(d.face_size);
        d.capture.buckets = self.dirt_buckets.unwrap_or(d.capture.buckets);
        o
    }

    /// The path tracer's options of the flags.
    pub fn options(&self) -> Result<PathOptions> {
        let materials = MaterialMode::parse(&self.materials).with_context(|| {
            format!(
                "--materials must be as-is or diffuse, got {:?}",
                self.materials
            )
        })?;
        let spp = match (self.spp, self.time_budget) {
            (Some(s), _) => s,
            (None, Some(_)) => MAX_SPP,
            (None, None) => 16,
        };
        let o = PathOptions {
            spp,
            time_budget: self.time_budget,
            seed: self.seed,
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            materials,
            env_nee: self.env_nee,
            ..PathOptions::default()
        };
        o.validate()?;
        Ok(o)
    }

    /// Loads and lights the scene (printing the default-sky message unless quiet).
    pub fn scene(&self, view: &ViewArgs, quiet: bool) -> Result<Scene> {
        let overrides = self.overrides()?;
        let mut scene = view.load_scene()?;
        let note = apply_lighting(&mut scene, &overrides)?;
        if let Some(m) = note.message(&scene)
            && !quiet
        {
            eprintln!("note: {m}");
        }
        Ok(scene)
    }
}

/// Writes a path-traced image: EXR with `R,G,B`, `variance.R/G/B` and `samples` plus a
/// tonemapped `<stem>.preview.png` beside it, or a PNG.
pub fn write_path_image(path: &std::path::Path, out: &PathOutput) -> Result<()> {
    let is_exr = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        output::write_render(path, &out.image, None, &[])?;
        return Ok(());
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let split = |img: &parallax_core::Image<parallax_core::Rgb>, c: usize| -> Vec<f32> {
        img.data().iter().map(|v| v[c]).collect()
    };
    let owned: Vec<(&str, Vec<f32>)> = vec![
        ("R", split(&out.image, 0)),
        ("G", split(&out.image, 1)),
        ("B", split(&out.image, 2)),
        ("variance.R", split(&out.variance, 0)),
        ("variance.G", split(&out.variance, 1)),
        ("variance.B", split(&out.variance, 2)),
        (
            "samples",
            out.counts.data().iter().map(|&n| n as f32).collect(),
        ),
    ];
    let channels: Vec<(&str, &[f32])> = owned.iter().map(|(n, v)| (*n, v.as_slice())).collect();
    exr::write_exr(path, out.image.width(), out.image.height(), &channels)?;
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("out");
    output::write_render(
        &path.with_file_name(format!("{stem}.preview.png")),
        &out.image,
        None,
        &[],
    )?;
    Ok(())
}

/// Renders with a progress bar (over samples, or over the time budget).
pub fn render_with_progress(pt: &PathTracer, what: &str, quiet: bool) -> PathOutput {
    let (w, h) = (pt.camera.width() as u64, pt.camera.height() as u64);
    match pt.opts.time_budget {
        Some(budget) => {
            let pb = progress::bar((budget * 1e3) as u64, what, quiet);
            let start = Instant::now();
            let out = pt.render(&|_| pb.set_position(start.elapsed().as_millis() as u64));
            pb.finish_and_clear();
            out
        }
        None => {
            let pb = progress::bar(w * h * pt.opts.spp as u64, what, quiet);
            let out = pt.render(&|n| pb.inc(n));
            pb.finish_and_clear();
            out
        }
    }
}

pub fn run(a: &PathArgs, quiet: bool) -> Result<()> {
    output::check_image_path(&a.out)?;
    let opts = a.path.options()?;
    let kind = TracerKind::parse(&a.path.tracer)?;
    let scene = a.path.scene(&a.view, quiet)?;
    let camera: Camera = a.view.camera(&scene, a.width, a.height)?;
    if let Some(dir) = &a.export_mitsuba {
        let desc = a.view.camera_desc(&scene)?;
        parallax_path::export::mitsuba::export(
            dir,
            &scene,
            &desc,
            camera.width(),
            camera.height(),
            &opts,
        )
        .with_context(|| format!("exporting to {}", dir.display()))?;
        if !quiet {
            println!("wrote {}", dir.join("scene.json").display());
        }
    }
    let built = build_tracer(kind, &scene, &camera, &a.path.tracer_options())?;
    let pt = PathTracer::new(&scene, &camera, built.tracer.as_ref(), opts)?;
    let out = render_with_progress(&pt, "path", quiet);
    write_path_image(&a.out, &out)?;
    let summary = serde_json::json!({
        "scene": scene.name,
        "tracer": kind.name(),
        "width": camera.width(),
        "height": camera.height(),
        "spp": out.spp,
        "seconds": out.seconds,
        "build_ms": built.build_ms,
        "threads": rayon::current_num_threads(),
        "paths": out.stats.paths,
        "paths_per_s": out.stats.paths as f64 / out.seconds,
        "rays": out.stats.rays(),
        "mrays_per_s": out.stats.rays() as f64 / out.seconds * 1e-6,
        "stats": out.stats,
    });
    if let Some(p) = &a.stats {
        std::fs::write(p, serde_json::to_string_pretty(&summary)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if !quiet {
        println!("wrote {}", a.out.display());
        println!(
            "{}: {}x{} {} spp in {:.2} s ({:.2} M paths/s, {:.1} Mrays/s, depth {}), {} build {:.1} ms",
            scene.name,
            camera.width(),
            camera.height(),
            out.spp,
            out.seconds,
            out.stats.paths as f64 / out.seconds * 1e-6,
            out.stats.rays() as f64 / out.seconds * 1e-6,
            out.stats.depth(),
            kind.name(),
            built.build_ms
        );
    }
    Ok(())
}

/// `parallax bench path`.
#[derive(Args, Debug)]
pub struct PathBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    #[arg(long, default_value_t = 180)]
    pub height: u32,
    #[command(flatten)]
    pub path: PathFlags,
    /// Samples of the reference image the RMSE is measured against.
    #[arg(long, default_value_t = 256)]
    pub reference_spp: u32,
    /// Interleaved timing rounds (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Tracers to compare, comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    pub tracers: Option<Vec<String>>,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn bench(a: &PathBenchArgs, quiet: bool) -> Result<()> {
    use parallax_path::bench::path::{PathBenchSetup, run};
    let opts = a.path.options()?;
    let tracers = match &a.tracers {
        Some(list) => list
            .iter()
            .map(|s| TracerKind::parse(s))
            .collect::<std::result::Result<Vec<_>, _>>()?,
        None => TracerKind::ALL.to_vec(),
    };
    let scene = a.path.scene(&a.view, quiet)?;
    let camera = a.view.camera(&scene, a.width, a.height)?;
    let setup = PathBenchSetup {
        opts,
        reference_spp: a.reference_spp,
        repeats: a.repeats,
        tracers,
    };
    let rows = run(&scene, &camera, &setup, &|what| {
        if !quiet {
            eprintln!("bench path: {what}");
        }
    })?;
    if !quiet {
        println!(
            "| method | scene | size | spp | threads | paths/s | Mrays/s | rays/path | RMSE | efficiency | build ms | render ms |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            println!(
                "| {} | {} | {}x{} | {} | {} | {:.0} | {:.2} | {:.2} | {:.5} | {:.3e} | {:.1} | {:.0} |",
                r.method,
                r.scene,
                r.width,
                r.height,
                r.spp,
                r.threads,
                r.paths_per_s,
                r.mrays_per_s,
                r.rays_per_path,
                r.rmse,
                r.efficiency,
                r.ms_build,
                r.ms_render
            );
        }
        println!();
        println!(
            "| method | bounce | rays | hit rate | trace Mrays/s | shadow rays | shadow Mrays/s | ms trace | ms fetch | ms shade | ms shadow |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            for b in &r.bounces {
                println!(
                    "| {} | {} | {} | {:.3} | {:.2} | {} | {:.2} | {:.1} | {:.1} | {:.1} | {:.1} |",
                    r.method,
                    b.bounce,
                    b.rays,
                    b.hit_rate,
                    b.trace_mrays_per_s,
                    b.shadow_rays,
                    b.shadow_mrays_per_s,
                    b.ms_trace,
                    b.ms_fetch,
                    b.ms_shade,
                    b.ms_shadow
                );
            }
        }
        println!();
        println!("| method | budget s | seconds | spp | RMSE | efficiency |");
        println!("|---|---|---|---|---|---|");
        for r in &rows {
            for b in &r.budgets {
                println!(
                    "| {} | {:.3} | {:.3} | {} | {:.5} | {:.3e} |",
                    r.method, b.budget_s, b.seconds, b.spp, b.rmse, b.efficiency
                );
            }
        }
    }
    if let Some(p) = &a.json {
        std::fs::write(p, serde_json::to_string_pretty(&rows)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

/// The demo's path-traced view: the scene through the demo camera at a quarter of the
/// demo's size, 16 samples per pixel, the scene's own lights (or the default sky).
pub fn demo_view(
    scene: &Scene,
    desc: &parallax_scene::CameraDesc,
    width: u32,
    height: u32,
    out: &std::path::Path,
    quiet: bool,
) -> Result<DemoPiece> {
    let mut scene = scene.clone();
    apply_lighting(&mut scene, &LightOverrides::default())?;
    let (w, h) = ((width / 3).max(1), (height / 3).max(1));
    let camera = Camera::new(
        parallax_scene::camera::ModelKind::Pinhole,
        desc,
        w,
        h,
        &parallax_scene::camera::CameraOptions::default(),
    )?;
    let built = build_tracer(TracerKind::Bvh, &scene, &camera, &TracerOptions::default())?;
    let opts = PathOptions {
        spp: 16,
        seed: 1,
        ..PathOptions::default()
    };
    let pt = PathTracer::new(&scene, &camera, built.tracer.as_ref(), opts)?;
    let res = render_with_progress(&pt, "path", quiet);
    write_path_image(&out.join("path_traced.png"), &res)?;
    Ok(DemoPiece {
        label: "path_traced".into(),
        section: section::PATH,
        title: "Path-traced view".into(),
        what: format!(
            "unidirectional path tracer over the BVH, next-event estimation with MIS, depth {} ({:.2} M paths/s)",
            pt.opts.max_depth,
            res.stats.paths as f64 / res.seconds * 1e-6
        ),
        size: format!("{w}x{h}"),
        spp: res.spp.to_string(),
        mrays: Some(res.stats.rays() as f64 / res.seconds * 1e-6),
        ms: res.seconds * 1e3,
        images: vec!["path_traced.png".into()],
        truth: None,
    })
}
