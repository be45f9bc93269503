//! `parallax capture`: rasterized captures (what the image-space tracers trace) written as EXR
//! layers and PNG previews, with `--stats` JSON (triangles, fragments, ms per stage, bytes).
//!
//! | `--view` | written to `--out DIR` |
//! |---|---|
//! | `pinhole` | `layer{k}.exr` (R,G,B = albedo, `depth`, `normal.X/Y/Z`, `id`), `layer{k}.png` (albedo), `layer{k}.depth.png` |
//! | `stereo` | the same in `left/` and `right/` |
//! | `cube` | the same in `px/ nx/ py/ ny/ pz/ nz/` (faces `--width` square) |
//! | `dirt` | `bounds.exr` (`zmin`, `zmax` per cell), `bounds.depth.png` (zmin), `lengths.png` (heatmap of list lengths) |
//! | `ldc` | per axis `ldi_x/y/z.exr` (first sample per pixel: `depth` from the box face, `normal.X/Y/Z`, R,G,B = albedo, `id`; plus `complexity` = samples per pixel), `ldi_x/y/z.complexity.png`; `--width` = pixels along the scene box's longest side |

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, ensure};
use clap::{Args, ValueEnum};
use glam::Vec3;
use parallax_core::Image;
use parallax_core::image::GBuffer;
use parallax_core::image::exr::write_exr;
use parallax_core::image::png::{
    ToneMapping, write_depth_png, write_png, write_png_linear_clamped,
};
use parallax_raster::dirt::{DirtCapture, DirtOptions};
use parallax_raster::ldc::{LayeredDepthCube, LdcOptions, Ldi};
use parallax_raster::{LayerCapture, RasterOptions, View, capture_layers};
use parallax_scene::Scene;
use parallax_scene::camera::{CubeMap, Eye, Pinhole, StereoRig};
use serde_json::{Value, json};

use crate::args::ViewArgs;
use crate::progress;

/// Largest `--layers` (the rasterizer's k-buffer limit).
const MAX_LAYERS: usize = 64;
/// Largest total of captured G-buffer samples (`pixels * layers * views`): bounds memory.
const MAX_SAMPLES: u64 = 1 << 28;

/// The capture kinds of `--view`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CaptureView {
    Pinhole,
    Stereo,
    Cube,
    Ldc,
    Dirt,
}

#[derive(Args, Debug)]
pub struct CaptureArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    /// What to capture.
    #[arg(
        long = "view",
        value_name = "VIEW",
        value_enum,
        default_value = "pinhole"
    )]
    pub kind: CaptureView,
    /// Depth layers per view (1..=64; layer k = k-th surface along the pixel ray).
    #[arg(long, default_value_t = 1)]
    pub layers: usize,
    /// Minimum view-depth separation between consecutive layers in metres (deep G-buffers).
    #[arg(long, default_value_t = 0.0)]
    pub min_separation: f32,
    /// Width in pixels (per eye for stereo, face size for cube).
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    /// Height in pixels (ignored by cube).
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// DIRT: tile size S in pixels (one list per S x S tile).
    #[arg(long, default_value_t = 1)]
    pub tile: u32,
    /// DIRT: depth buckets B per list.
    #[arg(long, default_value_t = 8)]
    pub buckets: u32,
    /// Output folder.
    #[arg(long, default_value = "out/capture")]
    pub out: PathBuf,
    /// Write statistics (triangles, fragments, ms per stage, bytes) as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
}

/// Totals over the captured views.
#[derive(Default)]
struct Totals {
    fragments: u64,
    bytes: u64,
    stages: BTreeMap<&'static str, f64>,
    views: Vec<Value>,
}

impl Totals {
    fn add_stage(&mut self, name: &'static str, ms: f64) {
        *self.stages.entry(name).or_default() += ms;
    }

    fn add_layers(&mut self, name: &str, c: &LayerCapture) {
        let s = &c.stats;
        self.fragments += s.raster.fragments as u64;
        self.bytes += c.bytes() as u64;
        self.add_stage("setup", s.raster.setup_ms);
        self.add_stage("bin", s.raster.bin_ms);
        self.add_stage("raster", s.raster.raster_ms);
        self.add_stage("resolve", s.resolve_ms);
        self.views.push(json!({ "view": name, "capture": s }));
    }
}

fn check_args(a: &CaptureArgs) -> Result<()> {
    ensure!(
        (1..=MAX_LAYERS).contains(&a.layers),
        "--layers must be in 1..={MAX_LAYERS}, got {}",
        a.layers
    );
    let views: u64 = match a.kind {
        CaptureView::Stereo => 2,
        CaptureView::Cube => 6,
        _ => 1,
    };
    let height = if a.kind == CaptureView::Cube {
        a.width
    } else {
        a.height
    };
    ensure!(
        a.width > 0 && height > 0,
        "--width and --height must be > 0"
    );
    let samples = a.width as u64 * height as u64 * a.layers as u64 * views;
    ensure!(
        samples <= MAX_SAMPLES,
        "{}x{} x {} layers x {views} views is {samples} samples, more than the {MAX_SAMPLES} allowed",
        a.width,
        height,
        a.layers
    );
    ensure!(
        a.min_separation.is_finite() && a.min_separation >= 0.0,
        "--min-separation must be finite and >= 0"
    );
    Ok(())
}

pub fn run(a: &CaptureArgs, quiet: bool) -> Result<()> {
    check_args(a)?;
    let start = Instant::now();
    let mut totals = Totals::default();
    let t = Instant::now();
    let scene = a.view.load_scene()?;
    totals.add_stage("load", ms(t));
    let desc = a.view.camera_desc(&scene)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let opts = RasterOptions {
        layers: a.layers,
        min_separation: a.min_separation,
        ..RasterOptions::default()
    };
    let mut written = Vec::new();
    match a.kind {
        CaptureView::Pinhole => {
            let cam = Pinhole::new(&desc, a.width, a.height)?;
            let views = [("pinhole".to_string(), cam, a.out.clone())];
            capture_views(&scene, &views, &opts, quiet, &mut totals, &mut written)?;
        }
        CaptureView::Stereo => {
            let rig = StereoRig::new(&desc, a.width, a.height, a.view.ipd)?;
            let views = [
                (
                    "left".into(),
                    rig.eye(Eye::Left).clone(),
                    a.out.join("left"),
                ),
                (
                    "right".into(),
                    rig.eye(Eye::Right).clone(),
                    a.out.join("right"),
                ),
            ];
            capture_views(&scene, &views, &opts, quiet, &mut totals, &mut written)?;
        }
        CaptureView::Cube => {
            let cube = CubeMap::new(&desc, a.width)?;
            let views: Vec<(String, Pinhole, PathBuf)> = ["px", "nx", "py", "ny", "pz", "nz"]
                .iter()
                .enumerate()
                .map(|(i, n)| (n.to_string(), cube.face_camera(i), a.out.join(n)))
                .collect();
            capture_views(&scene, &views, &opts, quiet, &mut totals, &mut written)?;
        }
        CaptureView::Dirt => {
            let cam = Pinhole::new(&desc, a.width, a.height)?;
            let dopts = DirtOptions {
                tile_size: a.tile,
                buckets: a.buckets,
                ..DirtOptions::default()
            };
            let pb = progress::bar(1, "dirt", quiet);
            let d = DirtCapture::build(&scene.mesh, &cam, &dopts).context("building DIRT")?;
            pb.finish_and_clear();
            let s = d.stats();
            totals.fragments += s.fragments;
            totals.bytes += d.bytes();
            totals.add_stage("setup", s.setup_ms);
            totals.add_stage("fill", s.fill_ms);
            totals.add_stage("assemble", s.assemble_ms);
            totals.add_stage("mip", s.mip_ms);
            totals.views.push(json!({ "view": "dirt", "dirt": s }));
            let t = Instant::now();
            write_dirt(&a.out, &d, &mut written)?;
            totals.add_stage("write", ms(t));
        }
        CaptureView::Ldc => {
            let pb = progress::bar(1, "ldc", quiet);
            let ldc = LayeredDepthCube::build(&scene, a.width, &LdcOptions::default())
                .context("building the layered depth cube")?;
            pb.finish_and_clear();
            totals.fragments += ldc.stats.samples as u64;
            totals.bytes += ldc.bytes() as u64;
            totals.add_stage("assign", ldc.stats.assign_ms);
            for l in &ldc.stats.ldis {
                totals.add_stage("setup", l.capture.raster.setup_ms);
                totals.add_stage("bin", l.capture.raster.bin_ms);
                totals.add_stage("raster", l.capture.raster.raster_ms);
                totals.add_stage("fill", l.capture.fill_ms);
                totals.add_stage("resolve", l.capture.resolve_ms);
                totals.add_stage("coarse", l.coarse_ms);
            }
            totals
                .views
                .push(json!({ "view": "ldc", "ldc": ldc.stats }));
            let t = Instant::now();
            for ldi in &ldc.ldis {
                write_ldi(&a.out, ldi, &mut written)?;
            }
            totals.add_stage("write", ms(t));
        }
    }
    let stats = json!({
        "scene": scene.name,
        "view": format!("{:?}", a.kind).to_lowercase(),
        "width": a.width,
        "height": if a.kind == CaptureView::Cube { a.width } else { a.height },
        "layers": if a.kind == CaptureView::Dirt { Value::Null } else { json!(a.layers) },
        "triangles": scene.mesh.triangle_count(),
        "fragments": totals.fragments,
        "bytes": totals.bytes,
        "ms": totals.stages,
        "total_ms": ms(start),
        "threads": rayon::current_num_threads(),
        "views": totals.views,
    });
    if let Some(p) = &a.stats {
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
        std::fs::write(p, serde_json::to_string_pretty(&stats)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        println!(
            "{}: {} triangles, {} fragments, {:.1} KiB, total {:.1} ms",
            scene.name,
            scene.mesh.triangle_count(),
            totals.fragments,
            totals.bytes as f64 / 1024.0,
            ms(start)
        );
    }
    Ok(())
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Captures `views` (name, camera, folder) and writes their layers.
fn capture_views(
    scene: &Scene,
    views: &[(String, Pinhole, PathBuf)],
    opts: &RasterOptions,
    quiet: bool,
    totals: &mut Totals,
    written: &mut Vec<PathBuf>,
) -> Result<()> {
    let pb = progress::bar(views.len() as u64, "capture", quiet);
    for (name, cam, dir) in views {
        let view = View::from_pinhole(cam).with_context(|| format!("view {name}"))?;
        let c = capture_layers(scene, &view, opts).with_context(|| format!("capturing {name}"))?;
        totals.add_layers(name, &c);
        let t = Instant::now();
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for (k, g) in c.layers.layers.iter().enumerate() {
            write_layer(dir, &format!("layer{k}"), g, written)?;
        }
        totals.add_stage("write", ms(t));
        pb.inc(1);
    }
    pb.finish_and_clear();
    Ok(())
}

fn split3(v: &[Vec3]) -> [Vec<f32>; 3] {
    [
        v.iter().map(|c| c.x).collect(),
        v.iter().map(|c| c.y).collect(),
        v.iter().map(|c| c.z).collect(),
    ]
}

/// `DIR/NAME.exr` (R,G,B = albedo, depth, normal.X/Y/Z, id = primitive id or -1),
/// `DIR/NAME.png` (albedo, sRGB) and `DIR/NAME.depth.png`.
fn write_layer(dir: &Path, name: &str, g: &GBuffer, written: &mut Vec<PathBuf>) -> Result<()> {
    let (w, h) = (g.width(), g.height());
    let [r, gr, b] = split3(&g.albedo);
    let [nx, ny, nz] = split3(&g.normal);
    let id: Vec<f32> = g
        .primitive_id
        .iter()
        .map(|&i| {
            if i == parallax_core::NO_ID {
                -1.0
            } else {
                i as f32
            }
        })
        .collect();
    let exr = dir.join(format!("{name}.exr"));
    let channels: [(&str, &[f32]); 8] = [
        ("R", &r),
        ("G", &gr),
        ("B", &b),
        ("depth", &g.depth),
        ("normal.X", &nx),
        ("normal.Y", &ny),
        ("normal.Z", &nz),
        ("id", &id),
    ];
    write_exr(&exr, w, h, &channels).with_context(|| format!("writing {}", exr.display()))?;
    let colour = dir.join(format!("{name}.png"));
    let albedo = Image::from_vec(w, h, g.albedo.clone())?;
    write_png(&colour, &albedo, &ToneMapping::default())
        .with_context(|| format!("writing {}", colour.display()))?;
    let depth = dir.join(format!("{name}.depth.png"));
    write_depth_png(&depth, &g.depth_image()?)
        .with_context(|| format!("writing {}", depth.display()))?;
    written.extend([exr, colour, depth]);
    Ok(())
}

/// Black (0) -> blue -> red -> yellow -> white (max).
fn heat(t: f32) -> Vec3 {
    const STOPS: [Vec3; 5] = [
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::ONE,
    ];
    let x = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    STOPS[i].lerp(STOPS[i + 1], x - i as f32)
}

/// `bounds.exr` (`zmin`, `zmax` per cell; `+inf`/`-inf` for empty cells), `bounds.depth.png`
/// (zmin) and `lengths.png` (entries per cell, black = empty, white = the longest list).
fn write_dirt(dir: &Path, d: &DirtCapture, written: &mut Vec<PathBuf>) -> Result<()> {
    let (cw, ch) = d.cells();
    let mut zmin = Vec::with_capacity((cw * ch) as usize);
    let mut zmax = Vec::with_capacity((cw * ch) as usize);
    let mut len = Vec::with_capacity((cw * ch) as usize);
    for cy in 0..ch {
        for cx in 0..cw {
            let (lo, hi) = d.depth_bounds(cx, cy);
            zmin.push(lo);
            zmax.push(hi);
            len.push(d.cell_entries(cx, cy).len());
        }
    }
    let exr = dir.join("bounds.exr");
    write_exr(&exr, cw, ch, &[("zmin", &zmin), ("zmax", &zmax)])
        .with_context(|| format!("writing {}", exr.display()))?;
    let depth = dir.join("bounds.depth.png");
    write_depth_png(&depth, &Image::from_vec(cw, ch, zmin)?)
        .with_context(|| format!("writing {}", depth.display()))?;
    let longest = len.iter().copied().max().unwrap_or(0).max(1) as f32;
    let heatmap = Image::from_vec(
        cw,
        ch,
        len.iter().map(|&n| heat(n as f32 / longest)).collect(),
    )?;
    let lengths = dir.join("lengths.png");
    write_png_linear_clamped(&lengths, &heatmap)
        .with_context(|| format!("writing {}", lengths.display()))?;
    written.extend([exr, depth, lengths]);
    Ok(())
}

/// `DIR/ldi_{x,y,z}.exr`: the first (nearest) sample of every pixel of one layered depth image
/// and its depth complexity, and `DIR/ldi_{x,y,z}.complexity.png` (samples per pixel, scaled to
/// the maximum).
fn write_ldi(dir: &Path, ldi: &Ldi, written: &mut Vec<PathBuf>) -> Result<()> {
    let c = &ldi.capture;
    let (w, h) = (c.width(), c.height());
    let n = w as usize * h as usize;
    let mut depth = vec![f32::INFINITY; n];
    let mut normal = vec![Vec3::ZERO; n];
    let mut albedo = vec![Vec3::ZERO; n];
    let mut id = vec![-1.0f32; n];
    let mut complexity = vec![0.0f32; n];
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let r = c.range(x, y);
            complexity[i] = r.len() as f32;
            if let Some(first) = r.clone().next() {
                depth[i] = c.depth[first];
                normal[i] = c.normal[first];
                albedo[i] = c.albedo[first];
                id[i] = c.primitive_id[first] as f32;
            }
        }
    }
    let name = format!("ldi_{}", ["x", "y", "z"][ldi.axis]);
    let [r, g, b] = split3(&albedo);
    let [nx, ny, nz] = split3(&normal);
    let exr = dir.join(format!("{name}.exr"));
    let channels: [(&str, &[f32]); 9] = [
        ("R", &r),
        ("G", &g),
        ("B", &b),
        ("depth", &depth),
        ("normal.X", &nx),
        ("normal.Y", &ny),
        ("normal.Z", &nz),
        ("id", &id),
        ("complexity", &complexity),
    ];
    write_exr(&exr, w, h, &channels).with_context(|| format!("writing {}", exr.display()))?;
    written.push(exr);
    let max = complexity.iter().copied().fold(1.0f32, f32::max);
    let heat = Image::from_vec(
        w,
        h,
        complexity.iter().map(|&k| Vec3::splat(k / max)).collect(),
    )?;
    let png = dir.join(format!("{name}.complexity.png"));
    write_png_linear_clamped(&png, &heat).with_context(|| format!("writing {}", png.display()))?;
    written.push(png);
    Ok(())
}
