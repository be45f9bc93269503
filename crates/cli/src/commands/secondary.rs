//! `parallax secondary`: reflections, refractions and shadows from a rasterized view, traced
//! through any world-space tracer (the layered depth cube paper's application), with every
//! tracer compared to the BVH on identical rays; and `parallax bench ldc`, the paper's Table 1.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use parallax_core::{Image, Rgb};
use parallax_path::secondary::bench::{LdcBenchRow, LdcBenchSetup};
use parallax_path::secondary::replay::EffectRow;
use parallax_path::secondary::{Effects, SecondaryOptions, bench, compare};
use parallax_path::tracers::{LdcSettings, TracerKind, TracerOptions, build_tracer};
use parallax_raster::ldc::{LdcOptions, MAX_RESOLUTION};
use parallax_scene::camera::{Camera, Pinhole};
use parallax_screen::ldc::{LdcTraceOptions, SampleTest};

use crate::args::ViewArgs;
use crate::demo_piece::{DemoPiece, section};
use crate::output;

/// The `ldc` tracer's flags.
#[derive(Args, Clone, Debug)]
pub struct LdcArgs {
    /// LDI resolution: pixels along the cube's longest side.
    #[arg(long, default_value_t = 1024)]
    pub ldc_res: u32,
    /// Hit tolerance in world units (the paper's 0.001).
    #[arg(long, default_value_t = parallax_screen::ldc::DEFAULT_EPS, allow_negative_numbers = true)]
    pub ldc_eps: f32,
    /// Sample test: `plane` (tangent-plane splats) or `depth` (the paper's constant depth).
    #[arg(long, default_value = "plane")]
    pub ldc_test: String,
    /// Coarse grid block edge in pixels.
    #[arg(long, default_value_t = parallax_raster::ldc::DEFAULT_BLOCK)]
    pub ldc_block: u32,
    /// Depth intervals per coarse block (1 = the paper's single [min, max]).
    #[arg(long, default_value_t = parallax_screen::ldc::DEFAULT_INTERVALS)]
    pub ldc_intervals: u32,
    /// Hits nearer to a ray's origin than this many LDI pixels are ignored (the surface the
    /// ray leaves, known only to within a pixel).
    #[arg(long, default_value_t = parallax_screen::ldc::DEFAULT_SKIP, allow_negative_numbers = true)]
    pub ldc_skip: f32,
    /// Growth of a planar splat past its pixel's square, in pixels on every side.
    #[arg(long, default_value_t = parallax_screen::ldc::DEFAULT_OVERLAP, allow_negative_numbers = true)]
    pub ldc_overlap: f32,
    /// Layer limit (depth complexity) of an LDI pixel.
    #[arg(long, default_value_t = parallax_raster::ldc::DEFAULT_MAX_LAYERS)]
    pub ldc_max_layers: u32,
    /// Region of interest the cube is fitted to: `auto` (the view's visible geometry plus a
    /// margin), `none` (the whole scene) or `--ldc-roi=minx,miny,minz,maxx,maxy,maxz`.
    #[arg(long, default_value = "auto", allow_hyphen_values = true)]
    pub ldc_roi: String,
    /// `--ldc-roi auto`: growth of the view's box on every side, fraction of its longest side.
    #[arg(long, default_value_t = parallax_path::secondary::roi::DEFAULT_MARGIN)]
    pub ldc_roi_margin: f32,
}

/// How the cube's box is chosen (`--ldc-roi`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RoiChoice {
    /// Fitted to the view ([`parallax_path::secondary::roi::view_roi`]).
    View,
    /// The whole scene, or the given box (in the settings).
    Fixed,
}

impl LdcArgs {
    /// The choice of box; a given box is in [`Self::settings`].
    pub fn roi_choice(&self) -> RoiChoice {
        if self.ldc_roi.trim() == "auto" {
            RoiChoice::View
        } else {
            RoiChoice::Fixed
        }
    }

    fn roi_box(&self) -> Result<Option<[Vec3; 2]>> {
        let s = self.ldc_roi.trim();
        if s == "auto" || s == "none" {
            return Ok(None);
        }
        let v: Vec<f32> = s
            .split(',')
            .map(|x| x.trim().parse::<f32>())
            .collect::<std::result::Result<_, _>>()
            .with_context(|| format!("--ldc-roi expects auto, none or six numbers, got {s:?}"))?;
        match v.as_slice() {
            [a, b, c, d, e, f] => Ok(Some([Vec3::new(*a, *b, *c), Vec3::new(*d, *e, *f)])),
            _ => bail!("--ldc-roi expects auto, none or six numbers, got {s:?}"),
        }
    }

    /// The cube's box for `camera`'s view `g` of `scene` (`--ldc-roi auto` fits it here).
    pub fn resolve_roi(
        &self,
        settings: &mut LdcSettings,
        scene: &parallax_scene::Scene,
        camera: &Pinhole,
        g: &parallax_core::image::GBuffer,
    ) {
        if self.roi_choice() == RoiChoice::View {
            use parallax_path::secondary::roi::{DEFAULT_TRIM, view_roi};
            settings.build.roi = view_roi(scene, camera, g, DEFAULT_TRIM, self.ldc_roi_margin);
        }
    }
}

impl LdcArgs {
    pub fn settings(&self) -> Result<LdcSettings> {
        if self.ldc_res == 0 || self.ldc_res > MAX_RESOLUTION {
            bail!(
                "--ldc-res must be in 1..={MAX_RESOLUTION}, got {}",
                self.ldc_res
            );
        }
        if !(self.ldc_eps.is_finite() && self.ldc_eps > 0.0) {
            bail!(
                "--ldc-eps must be a finite number > 0, got {}",
                self.ldc_eps
            );
        }
        let roi = self.roi_box()?;
        if !(self.ldc_roi_margin.is_finite() && (0.0..=10.0).contains(&self.ldc_roi_margin)) {
            bail!(
                "--ldc-roi-margin must be in [0, 10], got {}",
                self.ldc_roi_margin
            );
        }
        Ok(LdcSettings {
            resolution: self.ldc_res,
            build: LdcOptions {
                block: self.ldc_block,
                max_layers: self.ldc_max_layers,
                roi,
                ..LdcOptions::default()
            },
            trace: LdcTraceOptions {
                eps: self.ldc_eps,
                test: SampleTest::parse(&self.ldc_test)?,
                intervals: self.ldc_intervals,
                skip: self.ldc_skip,
                overlap: self.ldc_overlap,
            },
        })
    }
}

#[derive(Args, Debug)]
pub struct SecondaryArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    #[arg(long, default_value_t = 540)]
    pub height: u32,
    /// Tracers, a comma list of `bvh`, `ldc`, `cubemap` (the BVH always renders the reference).
    #[arg(long, default_value = "bvh,ldc")]
    pub tracer: String,
    /// Secondary effects: a comma list of `reflect`, `refract`, `shadow` (or `all`).
    #[arg(long, default_value = "reflect,refract,shadow")]
    pub effects: String,
    /// Specular levels after the primary hit.
    #[arg(long, default_value_t = 4)]
    pub bounces: u32,
    #[command(flatten)]
    pub ldc: LdcArgs,
    /// Agreement distance in world units (default: the LDC's eps).
    #[arg(long)]
    pub agree_eps: Option<f32>,
    /// Timed replay rounds per tracer (the best is kept).
    #[arg(long, default_value_t = 1)]
    pub repeats: u32,
    /// Output image (.png or .exr); with several tracers `<stem>.<tracer>.<ext>` each.
    #[arg(long, default_value = "out/secondary.png")]
    pub out: PathBuf,
    /// Write the per-tracer and per-effect rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The pinhole camera of the view flags (primary hits are rasterized).
fn pinhole(view: &ViewArgs, scene: &parallax_scene::Scene, w: u32, h: u32) -> Result<Pinhole> {
    match view.camera(scene, w, h)? {
        Camera::Pinhole(p) => Ok(p),
        other => bail!(
            "secondary rays start from a rasterized view: --model {} is not supported, use pinhole",
            other.kind().name()
        ),
    }
}

fn image_path(out: &Path, tracer: &str, several: bool) -> PathBuf {
    if !several {
        return out.to_path_buf();
    }
    let stem = out
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("secondary");
    let ext = out.extension().and_then(|s| s.to_str()).unwrap_or("png");
    out.with_file_name(format!("{stem}.{tracer}.{ext}"))
}

fn print_rows(rows: &[EffectRow]) {
    println!(
        "| tracer | effect | bounce | rays | agreement | only bvh | only other | differ | ms | Mrays/s | nodes/ray | tests/ray | truncated % |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let bounce = if r.bounce < 0 {
            "all".to_string()
        } else {
            r.bounce.to_string()
        };
        println!(
            "| {} | {} | {bounce} | {} | {:.4} | {} | {} | {} | {:.1} | {:.2} | {:.1} | {:.1} | {:.3} |",
            r.method,
            r.effect,
            r.rays,
            r.agreement,
            r.counts.only_reference,
            r.counts.only_other,
            r.counts.differ,
            r.ms_trace,
            r.mrays_per_s,
            r.nodes_per_ray,
            r.tests_per_ray,
            r.pct_truncated
        );
    }
}

fn write_json(path: &Path, value: &serde_json::Value) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(path, serde_json::to_string_pretty(value)?)
        .with_context(|| format!("writing {}", path.display()))
}

pub fn run(a: &SecondaryArgs, quiet: bool) -> Result<()> {
    output::check_image_path(&a.out)?;
    let mut kinds = Vec::new();
    for name in a.tracer.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let k = TracerKind::parse(name)?;
        if !kinds.contains(&k) {
            kinds.push(k);
        }
    }
    if kinds.is_empty() {
        bail!("--tracer needs at least one tracer");
    }
    let opts = SecondaryOptions {
        effects: Effects::parse(&a.effects)?,
        bounces: a.bounces,
    };
    opts.validate()?;
    let mut settings = a.ldc.settings()?;
    let tolerance = a.agree_eps.unwrap_or(settings.trace.eps);
    if !(tolerance.is_finite() && tolerance > 0.0) {
        bail!("--agree-eps must be a finite number > 0, got {tolerance}");
    }
    let scene = a.view.load_scene()?;
    let camera = pinhole(&a.view, &scene, a.width, a.height)?;
    let view = parallax_raster::View::from_pinhole(&camera)?;
    let g = parallax_raster::capture_gbuffer(&scene, &view)?
        .layers
        .layers
        .remove(0);
    a.ldc.resolve_roi(&mut settings, &scene, &camera, &g);
    let cam = Camera::Pinhole(camera.clone());
    let topts = TracerOptions {
        ldc: settings,
        ..TracerOptions::default()
    };
    let reference = build_tracer(TracerKind::Bvh, &scene, &cam, &topts)?;
    let mut others = Vec::new();
    for &k in kinds.iter().filter(|&&k| k != TracerKind::Bvh) {
        let t = build_tracer(k, &scene, &cam, &topts)?;
        if let Some(s) = &t.ldc {
            warn_ldc(s, quiet);
        }
        others.push(t);
    }
    let c = compare(
        &scene, &camera, &g, &reference, &others, &opts, a.repeats, tolerance,
    )?;
    let several = kinds.len() > 1;
    for (name, image) in &c.images {
        if !kinds.iter().any(|k| k.name() == name) {
            continue;
        }
        let p = image_path(&a.out, name, several);
        output::write_render(&p, image, None, &[])?;
        if !quiet {
            println!("wrote {}", p.display());
        }
        if name != "bvh" {
            let p = image_path(&a.out, &format!("{name}_vs_bvh"), true).with_extension("png");
            write_difference(&p, image, &c.images[0].1)?;
            if !quiet {
                println!(
                    "wrote {} (|difference| x 10 after the display transform)",
                    p.display()
                );
            }
        }
    }
    if !quiet {
        println!(
            "{}: {}x{}, effects {}, {} bounces",
            scene.name, camera.width, camera.height, a.effects, a.bounces
        );
        println!("| tracer | build ms | MB | render ms | rays | PSNR dB | SSIM |");
        println!("|---|---|---|---|---|---|---|");
        for t in &c.tracers {
            println!(
                "| {} | {:.1} | {:.1} | {:.1} | {} | {:.2} | {:.4} |",
                t.method,
                t.ms_build,
                t.bytes as f64 / 1e6,
                t.ms_render,
                t.rays,
                t.psnr,
                t.ssim
            );
        }
        print_rows(&c.rows);
    }
    if let Some(p) = &a.json {
        write_json(
            p,
            &serde_json::json!({
                "scene": scene.name,
                "width": camera.width,
                "height": camera.height,
                "ldc": settings,
                "tolerance": tolerance,
                "threads": rayon::current_num_threads(),
                "tracers": c.tracers,
                "rows": c.rows,
            }),
        )?;
    }
    Ok(())
}

/// Writes `|tonemap(a) - tonemap(b)| * 10` as a PNG (linear, clamped).
fn write_difference(path: &Path, a: &Image<Rgb>, b: &Image<Rgb>) -> Result<()> {
    use parallax_core::image::png::{tonemap_image, write_png_linear_clamped};
    use parallax_render::score::SCORE_TONEMAP;
    let (ta, tb) = (
        tonemap_image(a, &SCORE_TONEMAP),
        tonemap_image(b, &SCORE_TONEMAP),
    );
    let d = Image::from_vec(
        a.width(),
        a.height(),
        ta.data()
            .iter()
            .zip(tb.data())
            .map(|(x, y)| (*x - *y).abs() * 10.0)
            .collect(),
    )?;
    write_png_linear_clamped(path, &d)?;
    Ok(())
}

/// Says what a region of interest leaves out and when a cube is coarse for its eps.
fn warn_ldc(s: &parallax_raster::ldc::LdcStats, quiet: bool) {
    if quiet {
        return;
    }
    if s.roi {
        eprintln!(
            "note: the LDC covers only the region of interest {} .. {}: rays that leave it see the environment",
            s.box_min, s.box_max
        );
    }
}

#[derive(Args, Debug)]
pub struct LdcBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// Image width (the paper: 1280 x 1024).
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// LDI resolutions, a comma list.
    #[arg(long, default_value = "512,1024", value_delimiter = ',')]
    pub resolutions: Vec<u32>,
    #[command(flatten)]
    pub ldc: LdcArgs,
    /// Effects of the rendered image scored by PSNR / SSIM.
    #[arg(long, default_value = "reflect,refract,shadow")]
    pub effects: String,
    #[arg(long, default_value_t = 4)]
    pub bounces: u32,
    /// Rays per synthetic set (axis, random, surface).
    #[arg(long, default_value_t = 1 << 18)]
    pub synthetic_rays: usize,
    /// Interleaved timing rounds (best kept).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Agreement distance in world units (default: the LDC's eps).
    #[arg(long)]
    pub agree_eps: Option<f32>,
    /// Write the rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

pub fn bench(a: &LdcBenchArgs, quiet: bool) -> Result<()> {
    let mut ldc = a.ldc.settings()?;
    for &r in &a.resolutions {
        if r == 0 || r > MAX_RESOLUTION {
            bail!("--resolutions: each must be in 1..={MAX_RESOLUTION}, got {r}");
        }
    }
    ldc.resolution = a.resolutions.first().copied().unwrap_or(ldc.resolution);
    let setup = LdcBenchSetup {
        resolutions: a.resolutions.clone(),
        ldc,
        secondary: SecondaryOptions {
            effects: Effects::parse(&a.effects)?,
            bounces: a.bounces,
        },
        synthetic_rays: a.synthetic_rays.min(1 << 24),
        repeats: a.repeats,
        tolerance: a.agree_eps,
        view_roi: (a.ldc.roi_choice() == RoiChoice::View).then_some(a.ldc.ldc_roi_margin),
        ..LdcBenchSetup::default()
    };
    let scene = a.view.load_scene()?;
    let camera = pinhole(&a.view, &scene, a.width, a.height)?;
    let rows = bench::run(&scene, &camera, &setup)?;
    if !quiet {
        print_table1(&rows);
        print_classes(&rows);
    }
    if let Some(p) = &a.json {
        write_json(p, &serde_json::to_value(&rows)?)?;
    }
    Ok(())
}

/// Table 1 (one line per tracer and resolution on the view's rays), then every ray set.
fn print_table1(rows: &[LdcBenchRow]) {
    let Some(first) = rows.first() else {
        return;
    };
    println!(
        "{}: {}x{} view, {} threads, eps {}, {} test{}",
        first.scene,
        first.width,
        first.height,
        first.threads,
        first.eps,
        first.sample_test,
        match rows.iter().find(|r| r.roi) {
            Some(r) => format!(", region of interest {:?} .. {:?}", r.box_min, r.box_max),
            None => String::new(),
        }
    );
    println!(
        "| method | LDI res | layers (x/y/z) | MB | MB/layer | build ms (A) | assign / peel / orient / grid / setup ms | trace ms (B) | render ms | Mrays/s | vs BVH | agreement | PSNR dB | SSIM |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.rays_set == "view") {
        let res = if r.resolution == 0 {
            "-".to_string()
        } else {
            format!("{0}²", r.resolution)
        };
        let layers = if r.method == "bvh" {
            "-".to_string()
        } else {
            let [x, y, z] = r.layers_per_axis;
            format!("{} ({x}/{y}/{z})", r.layers)
        };
        println!(
            "| {} | {res} | {layers} | {:.1} | {:.2} | {:.1} | {:.1} / {:.1} / {:.1} / {:.1} / {:.1} | {:.1} | {:.1} | {:.2} | {:.2}x | {:.4} | {:.2} | {:.4} |",
            r.method,
            r.bytes as f64 / 1e6,
            r.bytes_per_layer / 1e6,
            r.ms_build,
            r.ms_assign,
            r.ms_peel,
            r.ms_orient,
            r.ms_grid,
            r.ms_setup,
            r.ms_trace,
            r.ms_render,
            r.mrays_per_s,
            r.trace_vs_bvh,
            r.agreement,
            r.psnr,
            r.ssim
        );
    }
    println!();
    println!(
        "| method | LDI res | rays | set | ms | Mrays/s | vs BVH | agreement | only bvh | only ldc | differ (early) | outside box | nodes/ray | steps/ray | tests/ray | truncated % |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.rays_set != "view") {
        println!(
            "| {} | {} | {} | {} | {:.1} | {:.2} | {:.2}x | {:.4} | {} | {} | {} ({}) | {} | {:.1} | {:.1} | {:.1} | {:.3} |",
            r.method,
            r.resolution,
            r.rays,
            r.rays_set,
            r.ms_trace,
            r.mrays_per_s,
            r.trace_vs_bvh,
            r.agreement,
            r.only_bvh,
            r.only_ldc,
            r.differ,
            r.early,
            r.outside,
            r.nodes_per_ray,
            r.steps_per_ray,
            r.tests_per_ray,
            r.pct_truncated
        );
    }
}

/// The LDC's disagreements per ray set and class (`parallax_path::secondary::classify`).
fn print_classes(rows: &[LdcBenchRow]) {
    println!();
    println!(
        "| LDI res | set | rays | disagree | truncated | outside | near | overhang | early | skipped | uncaptured | grazing | edge | gap |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.method == "ldc") {
        let c = &r.classes;
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.resolution,
            r.rays_set,
            r.rays,
            c.total(),
            c.truncated,
            c.outside,
            c.near,
            c.overhang,
            c.early,
            c.skipped,
            c.uncaptured,
            c.grazing,
            c.edge,
            c.gap
        );
    }
}

/// The demo's secondary-ray view: the built-in Cornell box's mirror and glass traced through
/// the BVH and through a 512² LDC, into `out/secondary_{bvh,ldc}.png`.
pub fn demo_secondary(out: &Path, width: u32, height: u32) -> Result<DemoPiece> {
    let t = std::time::Instant::now();
    let scene = parallax_scene::Scene::load("cornell")?;
    let desc = scene.camera(None)?;
    let camera = Pinhole::new(&desc, width.max(1), height.max(1))?;
    let view = parallax_raster::View::from_pinhole(&camera)?;
    let g = parallax_raster::capture_gbuffer(&scene, &view)?
        .layers
        .layers
        .remove(0);
    let settings = LdcSettings {
        resolution: 512,
        ..LdcSettings::default()
    };
    let cam = Camera::Pinhole(camera.clone());
    let topts = TracerOptions {
        ldc: settings,
        ..TracerOptions::default()
    };
    let reference = build_tracer(TracerKind::Bvh, &scene, &cam, &topts)?;
    let ldc = build_tracer(TracerKind::Ldc, &scene, &cam, &topts)?;
    let opts = SecondaryOptions::default();
    let c = compare(
        &scene,
        &camera,
        &g,
        &reference,
        std::slice::from_ref(&ldc),
        &opts,
        1,
        1e-3,
    )?;
    for (name, image) in &c.images {
        output::write_render(&out.join(format!("secondary_{name}.png")), image, None, &[])?;
    }
    let l = &c.tracers[1];
    Ok(DemoPiece {
        label: "secondary_bvh/ldc".into(),
        section: section::LDC,
        title: "Reflections, refractions and shadows through a layered depth cube".into(),
        what: format!(
            "built-in Cornell box: Whitted secondary rays traced through a 512² layered depth cube vs the same rays through the BVH ({:.2} dB, SSIM {:.4})",
            l.psnr, l.ssim
        ),
        size: format!("{}x{}", camera.width, camera.height),
        spp: "1".into(),
        mrays: None,
        ms: t.elapsed().as_secs_f64() * 1e3,
        images: vec!["secondary_ldc.png".into()],
        truth: Some("secondary_bvh.png".into()),
    })
}
