//! `parallax reproject` (a stereo sequence with sample reprojection: both eyes' frames, discard
//! masks, 1 spp beside the reprojected frames) and `parallax bench reproject` (Mäkitalo et al.
//! 2019, Tables 1-2: discarded pixels and effective spp per scene and mode). The technique is
//! `parallax_path::reproject`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use parallax_core::{Image, Rgb};
use parallax_path::reproject::dataset::{Dataset, Variant};
use parallax_path::reproject::footprint::Outcome;
use parallax_path::reproject::history::Blend;
use parallax_path::reproject::method::{Method, MethodState};
use parallax_path::reproject::reference::{ReferenceCache, ReferenceSpec};
use parallax_path::reproject::sequence::{RunOptions, run};
use parallax_path::reproject::{EvalOptions, Evaluation, Mode, ReprojectError, evaluate};
use parallax_render::bsdf::MaterialMode;
use serde::Serialize;

use crate::args::ViewArgs;
use crate::demo_piece::{DemoPiece, section};
use crate::output;
use crate::progress;

/// Flags shared by `parallax reproject` and `parallax bench reproject`.
#[derive(Args, Clone, Debug)]
pub struct ReprojectFlags {
    /// Scene, and optionally a head camera (`--eye/--target`, `--camera`): given, the head
    /// follows a backward dolly from it; else the scene's own path (Sponza, the classroom and
    /// the built-in scenes have one). `--ipd` is the eye separation.
    #[command(flatten)]
    pub view: ViewArgs,
    /// Width of ONE eye (the paper: 1280).
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    /// Height of one eye (the paper: 720).
    #[arg(long, default_value_t = 180)]
    pub height: u32,
    /// Frames from the start of the path (the paper: 60).
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Seed of every sample stream.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Scene variant: base, glossy, moving-light, moving-objects.
    #[arg(long, default_value = "base", value_parser = parse_variant)]
    pub variant: Variant,
    /// Methods (comma list): paper (Mäkitalo et al. as published), bmfr (the paper with BMFR's
    /// running mean), ours (both eyes' histories, running mean, albedo demodulation).
    #[arg(long, value_delimiter = ',', default_value = "paper,ours")]
    pub methods: Vec<String>,
    /// Temporal blend weight of the new sample, in (0, 1] (the floor of the running mean);
    /// default: each method's own (0.2).
    #[arg(long, allow_negative_numbers = true)]
    pub alpha: Option<f32>,
    /// World-position limit of the discard test, scene units (default: 3 % of the median view
    /// depth of the first traced frame).
    #[arg(long, allow_negative_numbers = true)]
    pub max_position: Option<f32>,
    /// Shading-normal limit of the discard test, degrees [default: 25].
    #[arg(long, allow_negative_numbers = true)]
    pub max_normal_deg: Option<f32>,
    /// Every opaque surface Lambertian (the paper's diffuse scenes).
    #[arg(long)]
    pub diffuse: bool,
}

fn parse_variant(s: &str) -> Result<Variant, String> {
    Variant::parse(s).map_err(|e| e.to_string())
}

impl ReprojectFlags {
    fn run_options(&self) -> RunOptions {
        RunOptions {
            width: self.width,
            height: self.height,
            ipd: self.view.ipd,
            frames: self.frames,
            seed: self.seed,
            materials: if self.diffuse {
                MaterialMode::Diffuse
            } else {
                MaterialMode::AsIs
            },
            max_position: self.max_position,
            max_normal_deg: self.max_normal_deg,
        }
    }

    fn methods(&self) -> Result<Vec<Method>> {
        self.methods
            .iter()
            .map(|name| {
                let mut m = Method::named(name)?;
                if let Some(a) = self.alpha {
                    m.blend = match m.blend {
                        Blend::Fixed(_) => Blend::Fixed(a),
                        Blend::RunningMean { .. } => Blend::RunningMean { floor: a },
                    };
                }
                m.validate()?;
                Ok(m)
            })
            .collect()
    }

    /// The dataset of `scene` (a `--scene` value).
    fn dataset(&self, scene: &str) -> Result<Dataset> {
        let view = ViewArgs {
            scene: scene.to_string(),
            ..self.view.clone()
        };
        let s = view.load_scene()?;
        let head = if self.view.eye.is_some() || self.view.camera.is_some() {
            Some(view.camera_desc(&s)?)
        } else {
            None
        };
        Ok(Dataset::with_head(s, self.variant, head)?)
    }
}

/// `parallax reproject`.
#[derive(Args, Debug)]
pub struct ReprojectArgs {
    #[command(flatten)]
    pub flags: ReprojectFlags,
    /// Output folder: per frame `left_NNN`, `right_NNN` (the first method's stereo + temporal
    /// and temporal frames), `mask_NNN.png` (red: left pixels the stereo tests discarded; green:
    /// right pixels whose history was discarded; blue: sky) and `compare_NNN.png` (right 1 spp |
    /// right temporal | left stereo | left stereo + temporal).
    #[arg(long, default_value = "reproject")]
    pub out: PathBuf,
    /// Image format of the frames: png or exr (linear).
    #[arg(long, default_value = "png")]
    pub format: String,
}

fn image(w: u32, h: u32, data: Vec<Vec3>) -> Result<Image<Rgb>> {
    Ok(Image::from_vec(w, h, data)?)
}

/// Images side by side.
fn side_by_side(w: u32, h: u32, parts: &[&[Vec3]]) -> Result<Image<Rgb>> {
    let n = parts.len() as u32;
    Ok(Image::from_fn(w * n, h, |x, y| {
        parts[(x / w) as usize][(y * w + x % w) as usize]
    })?)
}

fn mask(stereo: &[Outcome], temporal: &[Outcome]) -> Vec<Vec3> {
    stereo
        .iter()
        .zip(temporal)
        .map(|(s, t)| {
            Vec3::new(
                s.is_discarded() as u8 as f32,
                t.is_discarded() as u8 as f32,
                (*s == Outcome::Background) as u8 as f32,
            )
        })
        .collect()
}

pub fn run_reproject(a: &ReprojectArgs, quiet: bool) -> Result<()> {
    let ext = match a.format.as_str() {
        "png" | "exr" => a.format.as_str(),
        f => bail!("--format must be png or exr, got {f:?}"),
    };
    let f = &a.flags;
    let methods = f.methods()?;
    let opts = f.run_options();
    opts.validate()?;
    let mut world = f.dataset(&f.view.scene)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let mut states: Vec<MethodState> = methods.into_iter().map(MethodState::new).collect();
    let bar = progress::bar(opts.frames as u64, "frames", quiet);
    let (w, h) = (opts.width, opts.height);
    let out = &a.out;
    let write = |name: String, img: Image<Rgb>| -> Result<()> {
        let p = out.join(name);
        if ext == "exr" {
            output::write_render(&p, &img, None, &[])?;
        } else {
            output::write_png(&p, &img)?;
        }
        Ok(())
    };
    let mut discards = Vec::new();
    run(&mut world, &opts, &mut states, &mut |frame, _| {
        let mut one = || -> Result<()> {
            let m = &frame.methods[0];
            let i = frame.index;
            write(
                format!("left_{i:03}.{ext}"),
                image(w, h, m.combined.image.clone())?,
            )?;
            write(
                format!("right_{i:03}.{ext}"),
                image(w, h, m.temporal.image.clone())?,
            )?;
            let mk = mask(&m.stereo.outcomes, &m.temporal.outcomes);
            output::write_png(&out.join(format!("mask_{i:03}.png")), &image(w, h, mk)?)?;
            let parts: [&[Vec3]; 4] = [
                frame.right_radiance,
                &m.temporal.image,
                &m.stereo.image,
                &m.combined.image,
            ];
            write(format!("compare_{i:03}.{ext}"), side_by_side(w, h, &parts)?)?;
            let n = m.stereo.outcomes.len().max(1) as f64;
            discards.push((
                100.0 * m.stereo.discarded() as f64 / n,
                100.0 * m.temporal.discarded() as f64 / n,
            ));
            bar.inc(1);
            Ok(())
        };
        one().map_err(|e| ReprojectError::Consumer(format!("{e:#}")))
    })?;
    bar.finish_and_clear();
    if !quiet {
        let frames = discards.len().max(1) as f64;
        let s: f64 = discards.iter().map(|d| d.0).sum::<f64>() / frames;
        let t: f64 = discards.iter().skip(1).map(|d| d.1).sum::<f64>() / (frames - 1.0).max(1.0);
        println!(
            "{}: {} frames of {w}x{h} per eye into {}; discarded: stereo {s:.2}%, temporal {t:.2}% (frames 1..)",
            world_label(&a.flags),
            opts.frames,
            out.display()
        );
    }
    Ok(())
}

fn world_label(f: &ReprojectFlags) -> String {
    Path::new(&f.view.scene)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(&f.view.scene)
        .to_string()
}

/// `parallax bench reproject` (Tables 1-2).
#[derive(Args, Debug)]
pub struct ReprojectBenchArgs {
    #[command(flatten)]
    pub flags: ReprojectFlags,
    /// Scenes (comma list) instead of `--scene`, e.g.
    /// `atrium,../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb,../shared/scenes/japanese_classroom/japanese_classroom.glb`.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Option<Vec<String>>,
    /// Samples of each frame's progressive reference render (the paper: 4096); the reference
    /// is the mean of the samples after the curve's.
    #[arg(long, default_value_t = 256)]
    pub reference_spp: u32,
    /// Largest n of the n-spp error curve (effective spp above it are extrapolated).
    #[arg(long, default_value_t = 32)]
    pub curve_spp: u32,
    /// Folder of the reference cache (content-addressed; reruns reuse it).
    #[arg(long, default_value = "target/reproject-cache")]
    pub cache: PathBuf,
    /// Render every reference again, keep none.
    #[arg(long)]
    pub no_cache: bool,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// One JSON row: a scene, method and mode (field names as `bench warp`'s where they apply).
#[derive(Serialize, Debug)]
pub struct ReprojectRow {
    pub scene: String,
    pub method: String,
    pub mode: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub effective_spp_avg: f64,
    pub effective_spp_min: f64,
    pub effective_spp_max: f64,
    pub extrapolated_frames: usize,
    pub discard_pct_avg: f64,
    pub discard_pct_min: f64,
    pub discard_pct_max: f64,
    pub ms_reproject: f64,
    pub ms_trace_1spp: f64,
    pub reference_spp: u32,
    pub curve_spp: u32,
    pub reference_noise_ratio: f64,
    pub max_position: f32,
    pub max_normal_deg: f32,
    pub threads: usize,
}

fn rows(e: &Evaluation, a: &ReprojectBenchArgs) -> Vec<ReprojectRow> {
    e.series
        .iter()
        .map(|s| {
            let (eff, dis) = (s.effective_spp(), s.discard_pct());
            ReprojectRow {
                scene: e.label.clone(),
                method: s.method.clone(),
                mode: s.mode.name().into(),
                width: a.flags.width,
                height: a.flags.height,
                frames: a.flags.frames,
                effective_spp_avg: eff.avg,
                effective_spp_min: eff.min,
                effective_spp_max: eff.max,
                extrapolated_frames: s.extrapolated(),
                discard_pct_avg: dis.avg,
                discard_pct_min: dis.min,
                discard_pct_max: dis.max,
                ms_reproject: s.ms_reproject(),
                ms_trace_1spp: e.ms_trace_1spp,
                reference_spp: a.reference_spp,
                curve_spp: a.curve_spp,
                reference_noise_ratio: e.reference_noise_ratio,
                max_position: e.tests.position,
                max_normal_deg: e.tests.normal_deg,
                threads: rayon::current_num_threads(),
            }
        })
        .collect()
}

fn print_tables(rows: &[ReprojectRow]) {
    println!("Table 1: % of pixels discarded (stereo: all frames; temporal: frames 1..)\n");
    println!("| scene | method | mode | avg | min | max |");
    println!("|---|---|---|---:|---:|---:|");
    for r in rows
        .iter()
        .filter(|r| r.mode != Mode::StereoTemporal.name())
    {
        println!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} |",
            r.scene, r.method, r.mode, r.discard_pct_avg, r.discard_pct_min, r.discard_pct_max
        );
    }
    println!("\nTable 2: effective spp (RMSE vs the reference, interpolated on the n-spp curve)\n");
    println!(
        "| scene | method | mode | avg | min | max | extrapolated frames | ms reproject | ms trace 1 spp | ratio |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        println!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {} | {:.2} | {:.2} | {:.3}x |",
            r.scene,
            r.method,
            r.mode,
            r.effective_spp_avg,
            r.effective_spp_min,
            r.effective_spp_max,
            r.extrapolated_frames,
            r.ms_reproject,
            r.ms_trace_1spp,
            r.ms_reproject / r.ms_trace_1spp.max(1e-9)
        );
    }
}

pub fn bench(a: &ReprojectBenchArgs, quiet: bool) -> Result<()> {
    let f = &a.flags;
    let methods = f.methods()?;
    let opts = EvalOptions {
        run: f.run_options(),
        reference: ReferenceSpec {
            spp: a.reference_spp,
            curve_spp: a.curve_spp,
        },
        cache: ReferenceCache {
            dir: (!a.no_cache).then(|| a.cache.clone()),
        },
    };
    opts.run.validate()?;
    opts.reference.validate()?;
    let scenes = a
        .scenes
        .clone()
        .unwrap_or_else(|| vec![f.view.scene.clone()]);
    let mut all = Vec::new();
    for scene in &scenes {
        let mut world = f.dataset(scene)?;
        let total = 2 * f.frames as u64 * f.width as u64 * f.height as u64 * a.reference_spp as u64;
        let bar = progress::bar(total, "references", quiet);
        let e = evaluate(&mut world, &opts, &methods, &|n| bar.inc(n))
            .with_context(|| format!("scene {scene}"))?;
        bar.finish_and_clear();
        if !quiet {
            eprintln!(
                "{}: limits {:.4} units / {:.1} deg; references rendered {}, cached {}; \
                 reference noise <= {:.1}% of the smallest MSE measured",
                e.label,
                e.tests.position,
                e.tests.normal_deg,
                e.references_rendered,
                e.references_cached,
                100.0 * e.reference_noise_ratio
            );
        }
        all.extend(rows(&e, a));
    }
    if !quiet {
        print_tables(&all);
    }
    output::write_json(a.json.as_deref(), &all)
}

/// The demo's piece: a short stereo sequence of `scene` with our method, scored against small
/// references (no cache), and the last frame's comparison image.
pub fn demo_reproject(scene: &str, w: u32, h: u32, out: &Path) -> Result<DemoPiece> {
    let t = std::time::Instant::now();
    let mut world = Dataset::new(parallax_scene::Scene::load(scene)?, Variant::Base)?;
    let run = RunOptions {
        width: w,
        height: h,
        ipd: 0.065,
        frames: 4,
        seed: 0,
        materials: MaterialMode::AsIs,
        max_position: None,
        max_normal_deg: None,
    };
    let opts = EvalOptions {
        run: run.clone(),
        reference: ReferenceSpec {
            spp: 48,
            curve_spp: 16,
        },
        cache: ReferenceCache::default(),
    };
    let e = evaluate(&mut world, &opts, &[Method::ours()], &|_| {})?;
    // The comparison image of the last frame (a second, unscored pass over the sequence).
    let mut states = vec![MethodState::new(Method::ours())];
    let path = out.join("reproject_compare.png");
    run_sequence_last(&mut world, &run, &mut states, &path)?;
    let spp = |m| e.series("ours", m).map_or(0.0, |s| s.effective_spp().avg);
    Ok(DemoPiece {
        label: "reproject (ours, 4 frames)".into(),
        section: section::REPROJECT,
        title: "Path-traced stereo at 1 spp, reprojected".into(),
        what: format!(
            "last frame of a 4-frame stereo sequence: the right eye's 1-spp trace (left half) beside the left eye with stereo + temporal reprojection (ours, right half); effective spp: stereo {:.2}, temporal {:.2}, stereo+temporal {:.2}",
            spp(Mode::Stereo),
            spp(Mode::Temporal),
            spp(Mode::StereoTemporal)
        ),
        size: format!("{w}x{h} x2"),
        spp: "1".into(),
        mrays: None,
        ms: t.elapsed().as_secs_f64() * 1e3,
        images: vec!["reproject_compare.png".into()],
        truth: None,
    })
}

/// Runs the sequence and writes the last frame's right 1 spp | left stereo + temporal.
fn run_sequence_last(
    world: &mut Dataset,
    opts: &RunOptions,
    states: &mut [MethodState],
    path: &Path,
) -> Result<()> {
    let (w, h) = (opts.width, opts.height);
    let mut last = None;
    run(world, opts, states, &mut |f, _| {
        if f.index + 1 == opts.frames {
            let m = &f.methods[0];
            last = Some(side_by_side(w, h, &[f.right_radiance, &m.combined.image]));
        }
        Ok(())
    })?;
    if let Some(img) = last {
        output::write_png(path, &img?)?;
    }
    Ok(())
}
