//! `parallax lightfield --kind quilt|near-eye`: light fields synthesised from the colour +
//! depth layers of a reference by tracing every output pixel's ray through them (Widmer et
//! al. 2015, §5.3): a Looking Glass quilt of off-axis views, or near-eye elemental images
//! per eye (Lanman & Luebke 2013). From a scene each view / eye is scored against the BVH
//! render of the same rays and timed against it; colour + depth input works as for `warp`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail, ensure};
use clap::{Args, ValueEnum};
use parallax_bvh::Bvh;
use parallax_core::image::png::{self, ToneMapping};
use parallax_core::{Image, Rgb};
use parallax_render::score::score;
use parallax_scene::camera::{Eye, StereoRig};
use parallax_synth::lightfield::near_eye::NearEye;
use parallax_synth::lightfield::quilt::{PRESETS, QuiltSpec, QuiltViews};
use parallax_synth::lightfield::{
    bvh_pinhole_aa, bvh_view, near_eye_reference, quilt_reference, render_elemental,
    render_views_aa, spp_side,
};
use parallax_synth::method::{Method, Synthesizer};
use parallax_synth::{MethodOptions, Reference};
use serde::Serialize;

use super::bench_synth::cell;
use crate::args::ViewArgs;
use crate::args::{SynthArgs, parse_method};
use crate::output::write_json;
use crate::progress;

/// What to synthesise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Kind {
    Quilt,
    NearEye,
}

#[derive(Args, Debug)]
pub struct LightFieldArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    /// quilt (Looking Glass) or near-eye (elemental images per eye).
    #[arg(long, value_enum, default_value = "quilt")]
    pub kind: Kind,
    /// Depth layers of each reference (1..=8).
    #[arg(long, default_value_t = 2)]
    pub layers: usize,
    /// quadtree, dda, minmax, hiz or brute.
    #[arg(long, default_value = "quadtree", value_parser = parse_method)]
    pub method: Method,
    /// Quilt: device preset (portrait, go, 16-landscape, 8.9in).
    #[arg(long, default_value = "portrait")]
    pub preset: String,
    /// Quilt: tile columns (overrides the preset).
    #[arg(long)]
    pub cols: Option<u32>,
    /// Quilt: tile rows (overrides the preset).
    #[arg(long)]
    pub rows: Option<u32>,
    /// Quilt: tile width in pixels (overrides the preset).
    #[arg(long)]
    pub view_width: Option<u32>,
    /// Quilt: tile height in pixels (overrides the preset).
    #[arg(long)]
    pub view_height: Option<u32>,
    /// Quilt: horizontal view cone in degrees, in (0, 180).
    #[arg(long, default_value_t = 35.0)]
    pub view_cone: f32,
    /// Quilt: the reference is this many times the tile size (same field of view): a finer
    /// reference lowers the resampling error of every view; an odd scale puts the
    /// reference's pixel centres on the tiles' (3: about the Looking Glass Portrait's panel
    /// for its 420x560 tiles).
    #[arg(long, default_value_t = 3)]
    pub ref_scale: u32,
    /// Quilt: rays per pixel, an s x s grid (1, 4, 9, ..., 64) box-filtered, used identically
    /// for the synthesised views and their BVH truth (antialiased views, as a light-field
    /// display shows them).
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Near-eye: display pixels per eye, W,H.
    #[arg(long, value_delimiter = ',', num_args = 2, default_values_t = [1280, 720])]
    pub display: Vec<u32>,
    /// Near-eye: display pixel pitch in micrometres.
    #[arg(long, default_value_t = 12.0)]
    pub pixel_pitch_um: f32,
    /// Near-eye: microlens pitch in millimetres.
    #[arg(long, default_value_t = 1.0)]
    pub lens_pitch_mm: f32,
    /// Near-eye: lenslet focal length (= lens-display gap) in millimetres.
    #[arg(long, default_value_t = 3.3)]
    pub focal_mm: f32,
    /// Near-eye: eye relief (eye to lens array) in millimetres.
    #[arg(long, default_value_t = 35.0)]
    pub eye_relief_mm: f32,
    /// Near-eye: width of each eye's reference in pixels (default: the display width).
    #[arg(long)]
    pub ref_width: Option<u32>,
    /// Output folder.
    #[arg(long, default_value = "out/lightfield")]
    pub out: PathBuf,
    /// File name stem of the quilt (the suffix `_qs{cols}x{rows}a{aspect}` is appended).
    #[arg(long, default_value = "quilt")]
    pub name: String,
    /// Per-view / per-eye rows as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Instead of a scene: a colour image (EXR R,G,B linear, or PNG sRGB) as the reference
    /// (quilt: the centre view; near-eye: both eyes unless --color-right is given), one
    /// layer at its size, posed at --eye/--target/--up or the identity pose; not scored.
    #[arg(long, requires = "depth")]
    pub color: Option<PathBuf>,
    /// ... and its view depth (EXR channel Z, depth, Y or R).
    #[arg(long, requires = "color")]
    pub depth: Option<PathBuf>,
    /// Near-eye colour + depth input: the right eye's colour (the pose is the left input's
    /// moved by --ipd along its right axis).
    #[arg(long, requires_all = ["depth_right", "color"])]
    pub color_right: Option<PathBuf>,
    /// ... and its view depth.
    #[arg(long, requires = "color_right")]
    pub depth_right: Option<PathBuf>,
    /// Colour + depth input: focal length in pixels (else --fov-y, default 60 degrees).
    #[arg(long, conflicts_with = "fov_y")]
    pub focal_px: Option<f32>,
}

/// One view of a quilt or one eye of a near-eye set.
#[derive(Clone, Debug, Default, Serialize)]
pub struct LightFieldRow {
    pub kind: String,
    /// View index (quilt) or eye (0 left, 1 right).
    pub view: u32,
    pub method: String,
    pub layers: usize,
    /// Quilt: sideways offset of the view (m); near-eye: the eye's offset.
    pub offset_m: f32,
    pub width: u32,
    pub height: u32,
    /// Synthesis of the view through the layers (ms).
    pub ms_view: f64,
    /// The BVH's closest hits of the same rays alone, and its shaded render (ms).
    pub ms_bvh_trace: f64,
    pub ms_bvh_render: f64,
    pub mrays_per_s: f64,
    pub pct_layer2: f64,
    pub pct_miss: f64,
    pub pct_occlusion: f64,
    pub psnr: f64,
    pub ssim: f64,
}

fn spec(a: &LightFieldArgs) -> Result<QuiltSpec> {
    let mut s = QuiltSpec::preset(&a.preset)
        .with_context(|| format!("--preset: one of {}", PRESETS.join(", ")))?;
    if let Some(c) = a.cols {
        s.cols = c;
    }
    if let Some(r) = a.rows {
        s.rows = r;
    }
    if a.view_width.is_some() || a.view_height.is_some() {
        s.view_w = a.view_width.unwrap_or(s.view_w);
        s.view_h = a.view_height.unwrap_or(s.view_h);
        s.aspect = s.view_w as f32 / s.view_h.max(1) as f32;
    }
    s.view_cone_deg = a.view_cone;
    s.validate()?;
    Ok(s)
}

fn display(a: &LightFieldArgs) -> Result<NearEye> {
    let [w, h] = a.display[..] else {
        bail!("--display expects W,H")
    };
    let d = NearEye {
        display_w: w,
        display_h: h,
        pixel_pitch_m: a.pixel_pitch_um * 1e-6,
        lens_pitch_m: a.lens_pitch_mm * 1e-3,
        focal_m: a.focal_mm * 1e-3,
        eye_relief_m: a.eye_relief_mm * 1e-3,
    };
    d.validate()?;
    Ok(d)
}

fn build(method: Method, r: &mut Reference, opts: &MethodOptions) -> Result<Synthesizer> {
    ensure!(
        method.is_tracer(),
        "the mesh warp is not a tracer: no light field"
    );
    r.fit_cube(opts.cube_near)?;
    let t = Instant::now();
    let s = Synthesizer::build(method, r, opts)?;
    r.times.build_ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(s)
}

/// Writes `img` as `out/name` through `tm` (a user's content keeps its encoding,
/// `super::input` module docs).
fn save(
    out: &Path,
    name: &str,
    img: &Image<Rgb>,
    tm: &ToneMapping,
    written: &mut Vec<PathBuf>,
) -> Result<()> {
    let p = out.join(name);
    png::write_png(&p, img, tm).with_context(|| format!("writing {}", p.display()))?;
    written.push(p);
    Ok(())
}

pub fn run(a: &LightFieldArgs, quiet: bool) -> Result<()> {
    ensure!(
        (1..=8).contains(&a.layers),
        "--layers must be in 1..=8, got {}",
        a.layers
    );
    let opts = a.synth.method_options()?;
    spp_side(a.spp).context("--spp")?;
    ensure!(
        a.spp == 1 || a.kind == Kind::Quilt,
        "--spp is for quilts (near-eye elemental images are rendered with one ray per pixel)"
    );
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let rows = match a.kind {
        Kind::Quilt => quilt(a, &opts, quiet)?,
        Kind::NearEye => near_eye(a, &opts, quiet)?,
    };
    if !quiet {
        println!(
            "| {} | offset m | size | T_view ms | BVH trace ms | BVH render ms | Mrays/s | % layer 2+ | % miss | % occl. | PSNR dB | SSIM |",
            if a.kind == Kind::Quilt { "view" } else { "eye" }
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
        for r in &rows {
            println!(
                "| {} | {:+.4} | {}x{} | {:.1} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {} | {} |",
                r.view,
                r.offset_m,
                r.width,
                r.height,
                r.ms_view,
                cell(r.ms_bvh_trace, 1),
                cell(r.ms_bvh_render, 1),
                r.mrays_per_s,
                r.pct_layer2,
                r.pct_miss,
                r.pct_occlusion,
                cell(r.psnr, 2),
                cell(r.ssim, 4)
            );
        }
    }
    write_json(a.json.as_deref(), &rows)
}

fn row(
    kind: &str,
    i: u32,
    a: &LightFieldArgs,
    layers: usize,
    offset: f32,
    v: &parallax_synth::WarpedView,
) -> LightFieldRow {
    let (_, miss, occl) = v.kind_fractions();
    LightFieldRow {
        kind: kind.into(),
        view: i,
        method: a.method.name().into(),
        layers,
        offset_m: offset,
        width: v.image.width(),
        height: v.image.height(),
        ms_view: v.ms,
        ms_bvh_trace: f64::NAN,
        ms_bvh_render: f64::NAN,
        mrays_per_s: v.image.len() as f64 / (v.ms * 1e3).max(1e-9),
        pct_layer2: 100.0 * v.frac_deep(),
        pct_miss: 100.0 * miss,
        pct_occlusion: 100.0 * occl,
        psnr: f64::NAN,
        ssim: f64::NAN,
    }
}

fn quilt(a: &LightFieldArgs, opts: &MethodOptions, quiet: bool) -> Result<Vec<LightFieldRow>> {
    let spec = spec(a)?;
    let pb = progress::bar(spec.views() as u64 + 2, "quilt", quiet);
    let (mut reference, views, scene) = match (&a.color, &a.depth) {
        (Some(c), Some(d)) => {
            let (r, desc) = super::input::load_color_depth(&a.view, c, d, a.focal_px)?;
            let views = QuiltViews::new(spec, &desc, a.view.focus)?;
            (r, views, None)
        }
        _ => {
            let scene = a.view.load_scene()?;
            let bvh = Bvh::try_build(&scene.mesh)?;
            let desc = a.view.camera_desc(&scene)?;
            let views = QuiltViews::new(spec, &desc, a.view.focus)?;
            let (r, _) = quilt_reference(
                &scene,
                &bvh,
                &views,
                a.ref_scale,
                a.layers,
                a.synth.shading(),
                a.synth.seed,
            )?;
            (r, views, Some((scene, bvh)))
        }
    };
    pb.inc(1);
    let synth = build(a.method, &mut reference, opts)?;
    let side = spp_side(a.spp)?;
    let rendered = render_views_aa(
        synth.tracer().expect("a tracer"),
        &reference,
        &views,
        &opts.warp,
        side,
    )?;
    pb.inc(1);
    let images: Vec<Image<Rgb>> = rendered.iter().map(|v| v.image.clone()).collect();
    let q = parallax_synth::lightfield::quilt::assemble(&views.spec, &images)?;
    let tm = super::input::output_tonemap(scene.is_none());
    let mut written = Vec::new();
    save(
        &a.out,
        &format!("{}{}.png", a.name, spec.suffix()),
        &q,
        &tm,
        &mut written,
    )?;
    save(
        &a.out,
        "reference.png",
        &reference.colors[0],
        &tm,
        &mut written,
    )?;
    let layers = reference.layers.len();
    let mut rows: Vec<LightFieldRow> = rendered
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let mut r = row(
                "quilt",
                i as u32,
                a,
                layers,
                views.offset(i as u32),
                &v.rays,
            );
            (r.width, r.height) = (v.image.width(), v.image.height());
            r
        })
        .collect();
    if let (Some((scene, bvh)), false) = (&scene, a.synth.no_score) {
        let mut truths = Vec::new();
        for (i, r) in rows.iter_mut().enumerate() {
            pb.set_message(format!("BVH view {i}"));
            let b = bvh_pinhole_aa(
                scene,
                bvh,
                &views.camera(i as u32),
                side,
                a.synth.shading(),
                a.synth.seed,
            )?;
            let s = score(&rendered[i].image, &b.image)?;
            (r.psnr, r.ssim, r.ms_bvh_trace, r.ms_bvh_render) =
                (s.psnr, s.ssim, b.ms_trace, b.ms_render);
            truths.push(b.image);
            pb.inc(1);
        }
        let qt = parallax_synth::lightfield::quilt::assemble(&views.spec, &truths)?;
        save(
            &a.out,
            &format!("{}.bvh{}.png", a.name, spec.suffix()),
            &qt,
            &tm,
            &mut written,
        )?;
    }
    pb.finish_and_clear();
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        let t = reference.times;
        println!(
            "{} {} layer(s), {} views of {}x{} at {} ray(s) per pixel over {} deg, focal plane {:.2} m, reference {}x{}: T_ref {:.1} ms (capture {:.1}, shade {:.1}, build {:.1}), all views {:.1} ms",
            a.method,
            layers,
            spec.views(),
            spec.view_w,
            spec.view_h,
            a.spp,
            spec.view_cone_deg,
            views.focus,
            reference.width(),
            reference.height(),
            t.total_ms(),
            t.capture_ms,
            t.shade_ms,
            t.build_ms,
            rendered.iter().map(|v| v.rays.ms).sum::<f64>()
        );
    }
    Ok(rows)
}

fn near_eye(a: &LightFieldArgs, opts: &MethodOptions, quiet: bool) -> Result<Vec<LightFieldRow>> {
    let d = display(a)?;
    ensure!(
        a.view.ipd.is_finite() && a.view.ipd >= 0.0,
        "--ipd must be finite and >= 0, got {}",
        a.view.ipd
    );
    let pb = progress::bar(4, "near-eye", quiet);
    let ref_w = a.ref_width.unwrap_or(d.display_w);
    let mut written = Vec::new();
    let mut rows = Vec::new();
    // (reference, eye frame) per eye, and the scene when rendered.
    let (eyes, scene) = match (&a.color, &a.depth) {
        (Some(c), Some(dp)) => {
            let (left, _) = super::input::load_color_depth(&a.view, c, dp, a.focal_px)?;
            let right = match (&a.color_right, &a.depth_right) {
                (Some(c), Some(dp)) => {
                    super::input::load_color_depth(&a.view, c, dp, a.focal_px)?.0
                }
                _ => left.clone(),
            };
            let frame = left.camera.frame;
            let right_frame = parallax_scene::camera::CameraFrame {
                position: frame.position + frame.right() * a.view.ipd,
                ..frame
            };
            (vec![(left, frame), (right, right_frame)], None)
        }
        _ => {
            let scene = a.view.load_scene()?;
            let bvh = Bvh::try_build(&scene.mesh)?;
            let desc = a.view.camera_desc(&scene)?;
            let rig = StereoRig::new(&desc, d.display_w, d.display_h, a.view.ipd)?;
            let mut eyes = Vec::new();
            for e in [Eye::Left, Eye::Right] {
                let frame = rig.eye(e).frame;
                let r = near_eye_reference(
                    &scene,
                    &bvh,
                    &d,
                    frame,
                    ref_w,
                    a.layers,
                    a.synth.shading(),
                    a.synth.seed,
                )?;
                eyes.push((r, frame));
            }
            (eyes, Some((scene, bvh)))
        }
    };
    pb.inc(1);
    let tm = super::input::output_tonemap(scene.is_none());
    let mut t_ref = 0.0;
    for (k, (mut r, frame)) in eyes.into_iter().enumerate() {
        let synth = build(a.method, &mut r, opts)?;
        t_ref += r.times.total_ms();
        let v = render_elemental(
            synth.tracer().expect("a tracer"),
            &r,
            &d,
            &frame,
            &opts.warp,
        )?;
        let name = if k == 0 { "left" } else { "right" };
        save(
            &a.out,
            &format!("elemental_{name}.png"),
            &v.image,
            &tm,
            &mut written,
        )?;
        let offset = if k == 0 { -0.5 } else { 0.5 } * a.view.ipd;
        let mut row = row("near-eye", k as u32, a, r.layers.len(), offset, &v);
        if let (Some((scene, bvh)), false) = (&scene, a.synth.no_score) {
            pb.set_message(format!("BVH {name}"));
            let b = bvh_view(
                scene,
                bvh,
                d.display_w,
                d.display_h,
                |x, y| Some(d.ray(&frame, x, y)),
                a.synth.shading(),
                a.synth.seed,
            )?;
            let s = score(&v.image, &b.image)?;
            (row.psnr, row.ssim, row.ms_bvh_trace, row.ms_bvh_render) =
                (s.psnr, s.ssim, b.ms_trace, b.ms_render);
            save(
                &a.out,
                &format!("elemental_{name}.bvh.png"),
                &b.image,
                &tm,
                &mut written,
            )?;
        }
        rows.push(row);
        pb.inc(1);
    }
    pb.finish_and_clear();
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        let n = d.lenslets();
        println!(
            "{} {} layer(s), near-eye display {}x{} px at {} um, lenslets {} mm (f {} mm) at {} mm eye relief: {}x{} elemental images of {:.1} px, T_ref {:.1} ms (both eyes)",
            a.method,
            a.layers,
            d.display_w,
            d.display_h,
            a.pixel_pitch_um,
            a.lens_pitch_mm,
            a.focal_mm,
            a.eye_relief_mm,
            n.x,
            n.y,
            d.elemental_px(),
            t_ref
        );
    }
    Ok(rows)
}
