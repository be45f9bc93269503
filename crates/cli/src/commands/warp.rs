//! `parallax warp`: stereo warping of a cyclopean reference (Widmer et al. 2015, §5.1, Table 2)
//! with any method, from a scene or from a colour + depth image pair; writes both eyes, their
//! hit-type images (Fig. 6d: misses red, occlusion volumes blue) and intersection heatmaps
//! (Fig. 1c), and scores the eyes against the BVH reference render of the eye cameras.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail, ensure};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::png::{self, ToneMapping};
use parallax_core::{Image, Rgb};
use parallax_render::score::SCORE_TONEMAP;
use parallax_scene::camera::Pinhole;
use parallax_synth::CubeNear;
use parallax_synth::bench::warp::{StereoSetup, eye_truths, score_pair};
use parallax_synth::input::{
    Intrinsics, input_desc, read_color, read_depth, reference_from_images,
};
use parallax_synth::method::NormalSource;
use parallax_synth::method::{Method, MethodOptions, cube_near_name, parse_cube_near};
use parallax_synth::stereo::warp_stereo;
use parallax_synth::warp::{OcclusionFill, Resample, WarpOptions, WarpedView};
use parallax_synth::{Shading, capture_reference};

use crate::args::ViewArgs;
use crate::progress;

/// Options of the synthesis methods (shared by `warp`, `upsample` and the synthesis benches).
#[derive(Args, Clone, Debug)]
pub struct SynthArgs {
    /// Shading of reference layers and ground truth: fixed (one random stream for every
    /// shading point: noise-free, comparable) or per-pixel (the reference renderer's streams).
    #[arg(long, default_value = "fixed", value_parser = parse_shading)]
    pub shading: Shading,
    /// Seed of the shading streams.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Per-pixel plane normals of the tracers: gbuffer, gbuffer-flagged (with the crack flag O
    /// at plane gaps, for the quad-tree's crack dilation) or depth (reconstructed, Widmer's).
    #[arg(long, default_value = "gbuffer")]
    pub normals: String,
    /// DDA: march step bound. Default for stereo (`warp`, `bench warp | compression`): 260,
    /// minimal artifact-free at 1600x900 from a 0.1 m camera near plane (measured; --near
    /// fitted needs only 16); for upsampling (`upsample`, `bench upsample`): 1400 (700
    /// measured at 800x450, doubled for 1600x900). The paper used 200 / 500 at its
    /// resolution. Sweep with `bench warp | upsample --dda-sweep`.
    #[arg(long)]
    pub dda_max_steps: Option<u32>,
    /// Near plane of the reference's unit cube, where every traced ray starts: `fitted` (half
    /// the nearest captured depth, our global empty-space skip) or a camera near plane in
    /// metres, e.g. `0.1` (Widmer et al. 2015's NDC cube = the camera frustum, the setting of
    /// their Tables 2-3; `camera` = 0.1).
    #[arg(long, default_value = "fitted", value_parser = parse_near)]
    pub near: CubeNear,
    /// Quad-tree: normal threshold gamma_norm as an angle in degrees (cos of it is used).
    #[arg(long, default_value_t = 3.0)]
    pub gamma_norm_deg: f32,
    /// Quad-tree: plane-distance threshold gamma_dist, in z units of Widmer's NDC cube (the camera frustum from a 0.1 m near plane, where the paper states its 1e-5), rescaled to the cube in use.
    #[arg(long, default_value_t = 1e-5)]
    pub gamma_dist: f32,
    /// Quad-tree: depth-adaptive thresholds (§6).
    #[arg(long)]
    pub adaptive: bool,
    /// Quad-tree: single-layer inpainting traversal (§4.1).
    #[arg(long)]
    pub inpaint: bool,
    /// Mesh warp: tear triangles whose corner depths differ by more than this fraction
    /// (default: never, background triangles stretch over disocclusions).
    #[arg(long)]
    pub mesh_max_rel_jump: Option<f32>,
    /// Tracers: nearest-pixel colour of a hit instead of depth-aware bilinear resampling.
    #[arg(long)]
    pub nearest: bool,
    /// Tracers: no layer-0 guard of answers from deeper layers (neither part).
    #[arg(long)]
    pub no_layer0_guard: bool,
    /// Tracers: no side-entry part (a) of the layer-0 guard.
    #[arg(long)]
    pub no_side_entry_guard: bool,
    /// Tracers: no DDA re-check parts (b) and (c) of the layer-0 guard.
    #[arg(long)]
    pub no_dda_recheck: bool,
    /// Tracers: colour of occlusion-volume answers: crossed (the reported pixel) or
    /// background (nearest background pixel along the epipolar line, Widmer Fig. 6e).
    #[arg(long)]
    pub ov_fill: Option<String>,
    /// Do not render the BVH ground truth (no PSNR / SSIM).
    #[arg(long)]
    pub no_score: bool,
}

fn parse_near(s: &str) -> Result<CubeNear, String> {
    parse_cube_near(s).map_err(|e| e.to_string())
}

fn parse_shading(s: &str) -> Result<Shading, String> {
    match s {
        "fixed" => Ok(Shading::Fixed),
        "per-pixel" | "perpixel" => Ok(Shading::PerPixel),
        _ => Err(format!(
            "unknown shading {s:?}; expected fixed or per-pixel"
        )),
    }
}

/// Default DDA max steps of the upsampling commands (see `--dda-max-steps`).
pub const DDA_MAX_STEPS_UPSAMPLE: u32 = 1400;

impl SynthArgs {
    /// The method options of temporal upsampling (the upsampling DDA default).
    pub fn upsample_options(&self) -> Result<MethodOptions> {
        let mut o = self.method_options()?;
        o.dda_max_steps = self.dda_max_steps.unwrap_or(DDA_MAX_STEPS_UPSAMPLE);
        Ok(o)
    }

    /// The method options (stereo warping defaults).
    pub fn method_options(&self) -> Result<MethodOptions> {
        let normals = match self.normals.as_str() {
            "gbuffer" => NormalSource::GBuffer,
            "gbuffer-flagged" => NormalSource::gbuffer_flagged(),
            "depth" => NormalSource::Depth {
                max_rel_error: parallax_raster::normals::DEFAULT_MAX_REL_ERROR,
            },
            o => bail!("unknown --normals {o:?}; expected gbuffer, gbuffer-flagged or depth"),
        };
        ensure!(
            self.gamma_norm_deg.is_finite() && (0.0..=90.0).contains(&self.gamma_norm_deg),
            "--gamma-norm-deg must be in 0..=90, got {}",
            self.gamma_norm_deg
        );
        ensure!(
            self.gamma_dist.is_finite() && self.gamma_dist >= 0.0,
            "--gamma-dist must be >= 0, got {}",
            self.gamma_dist
        );
        let jump = self.mesh_max_rel_jump.unwrap_or(f32::INFINITY);
        ensure!(jump >= 0.0, "--mesh-max-rel-jump must be >= 0, got {jump}");
        Ok(MethodOptions {
            normals,
            dda_max_steps: self
                .dda_max_steps
                .unwrap_or(MethodOptions::default().dda_max_steps),
            gamma_norm: self.gamma_norm_deg.to_radians().cos(),
            gamma_dist: self.gamma_dist,
            adaptive: self.adaptive,
            max_levels: None,
            inpaint: self.inpaint,
            mesh_max_rel_jump: jump,
            warp: WarpOptions {
                resample: if self.nearest {
                    Resample::Nearest
                } else {
                    Resample::Bilinear
                },
                side_entry_guard: !(self.no_layer0_guard || self.no_side_entry_guard),
                dda_recheck: !(self.no_layer0_guard || self.no_dda_recheck),
                fill: match self.ov_fill.as_deref() {
                    None => WarpOptions::default().fill,
                    Some("crossed") => OcclusionFill::Crossed,
                    Some("background") => OcclusionFill::NearestBackground,
                    Some(o) => bail!("unknown --ov-fill {o:?}; expected crossed or background"),
                },
                ..WarpOptions::default()
            },
            cube_near: self.near,
        })
    }
}

/// Parses a method name with a CLI-friendly error.
pub fn parse_method(s: &str) -> Result<Method, String> {
    s.parse::<Method>().map_err(|e| e.to_string())
}

#[derive(Args, Debug)]
pub struct WarpArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    /// Image width of each eye (and of the reference).
    #[arg(long, default_value_t = 1600)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 900)]
    pub height: u32,
    /// Depth layers of the reference (1..=8).
    #[arg(long, default_value_t = 2)]
    pub layers: usize,
    /// quadtree, dda, minmax, hiz, mesh or brute.
    #[arg(long, default_value = "quadtree", value_parser = parse_method)]
    pub method: Method,
    /// Output folder.
    #[arg(long, default_value = "out/warp")]
    pub out: PathBuf,
    /// Instead of a scene: a colour image (EXR R,G,B linear, or PNG sRGB) ... The reference is
    /// then one layer at the image's size (--width/--height/--layers ignored), posed at
    /// --eye/--target/--up or the identity pose (origin, looking down -Z), not scored.
    #[arg(long, requires = "depth")]
    pub color: Option<PathBuf>,
    /// ... and its view depth (EXR channel Z, depth, Y or R).
    #[arg(long, requires = "color")]
    pub depth: Option<PathBuf>,
    /// Colour + depth input: focal length in pixels (else --fov-y, default 60 degrees).
    #[arg(long, conflicts_with = "fov_y")]
    pub focal_px: Option<f32>,
}

/// Writes the colour, hit-type and heatmap PNGs of one view as `DIR/NAME*.png`.
pub fn write_view(dir: &Path, name: &str, v: &WarpedView) -> Result<Vec<PathBuf>> {
    let tm = SCORE_TONEMAP;
    let p = dir.join(format!("{name}.png"));
    png::write_png(&p, &v.image, &tm)?;
    let hits = dir.join(format!("{name}.hits.png"));
    png::write_png(&hits, &v.hit_type_image(), &tm)?;
    let heat = dir.join(format!("{name}.heat.png"));
    png::write_png(&heat, &v.heatmap(None).0, &ToneMapping::default())?;
    Ok(vec![p, hits, heat])
}

fn write_png(path: &Path, img: &Image<Rgb>) -> Result<PathBuf> {
    png::write_png(path, img, &SCORE_TONEMAP)?;
    Ok(path.to_path_buf())
}

pub fn run(a: &WarpArgs, quiet: bool) -> Result<()> {
    ensure!(
        (1..=8).contains(&a.layers),
        "--layers must be in 1..=8, got {}",
        a.layers
    );
    ensure!(
        a.view.ipd.is_finite() && a.view.ipd >= 0.0,
        "--ipd must be finite and >= 0, got {}",
        a.view.ipd
    );
    let opts = a.synth.method_options()?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let pb = progress::bar(4, "warp", quiet);
    // Reference: from a scene, or from colour + depth.
    let (mut reference, desc, scene) = match (&a.color, &a.depth) {
        (Some(c), Some(d)) => {
            let color = read_color(c).with_context(|| format!("reading {}", c.display()))?;
            let depth = read_depth(d).with_context(|| format!("reading {}", d.display()))?;
            let intr = match a.focal_px {
                Some(f) => Intrinsics::FocalPx(f),
                None => Intrinsics::FovYDeg(a.view.fov_y.unwrap_or(60.0)),
            };
            let pose = match (&a.view.eye, &a.view.target) {
                (Some(_), Some(_)) => {
                    let scene = parallax_scene::Scene::default();
                    let d = a.view.camera_desc(&scene)?;
                    Some((d.eye, d.target, d.up))
                }
                _ => None,
            };
            let desc = input_desc(intr, color.height(), pose)?;
            let r = reference_from_images(color, &depth, &desc, Rgb::ZERO)?;
            (r, desc, None)
        }
        _ => {
            pb.set_message("reference");
            let scene = a.view.load_scene()?;
            let bvh = Bvh::try_build(&scene.mesh)?;
            let desc = a.view.camera_desc(&scene)?;
            let cam = Pinhole::new(&desc, a.width, a.height)?;
            // The mesh warp uses layer 0 only.
            let layers = if a.method == Method::Mesh {
                1
            } else {
                a.layers
            };
            let r = capture_reference(&scene, &bvh, &cam, layers, a.synth.shading, a.synth.seed)?;
            (r, desc, Some((scene, bvh)))
        }
    };
    pb.inc(1);
    pb.set_message(a.method.name());
    let sv = warp_stereo(&mut reference, &desc, a.view.ipd, a.method, &opts)?;
    pb.inc(1);
    let mut written = vec![write_png(
        &a.out.join("reference.png"),
        &reference.colors[0],
    )?];
    for (name, v) in ["left", "right"].iter().zip(&sv.views) {
        written.extend(write_view(&a.out, name, v)?);
    }
    pb.inc(1);
    let score = match (&scene, a.synth.no_score) {
        (Some((scene, bvh)), false) => {
            pb.set_message("BVH eyes");
            let setup = StereoSetup {
                desc,
                width: reference.width(),
                height: reference.height(),
                ipd: a.view.ipd,
                shading: a.synth.shading,
                seed: a.synth.seed,
                score: true,
                repeats: 1,
            };
            let truths = eye_truths(scene, bvh, &setup)?;
            written.push(write_png(&a.out.join("left.bvh.png"), &truths[0])?);
            written.push(write_png(&a.out.join("right.bvh.png"), &truths[1])?);
            Some(score_pair(&sv, &truths)?)
        }
        _ => None,
    };
    pb.finish_and_clear();
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        let t = reference.times;
        let rays: u64 = sv.views.iter().map(|v| v.stats.rays).sum();
        let ms: f64 = sv.views.iter().map(|v| v.ms).sum();
        let (h, m, o) = sv.views[0].kind_fractions();
        println!(
            "{} {} layer(s) {}x{} ipd {}, cube near {} ({:.3} m): T_ref {:.1} ms (capture {:.1}, shade {:.1}, build {:.1}), T_eye {:.1} ms, {:.2} Mrays/s, left eye hit {:.1}% miss {:.1}% occlusion {:.1}%, {:.2}% from layer 2+",
            a.method,
            reference.layers.len(),
            reference.width(),
            reference.height(),
            a.view.ipd,
            cube_near_name(reference.cube_near),
            reference.cube.near,
            t.total_ms(),
            t.capture_ms,
            t.shade_ms,
            t.build_ms,
            sv.ms_eye(),
            if rays > 0 {
                rays as f64 / (ms * 1e3)
            } else {
                0.0
            },
            h * 100.0,
            m * 100.0,
            o * 100.0,
            sv.views[0].frac_deep() * 100.0,
        );
        if let Some(s) = score {
            println!(
                "vs BVH eye views: PSNR {:.2} dB, SSIM {:.4}",
                s.psnr, s.ssim
            );
        }
    }
    let truncated = sv.views[0].pct_truncated().max(sv.views[1].pct_truncated());
    if truncated > 0.0 {
        eprintln!(
            "warning: {truncated:.2}% of an eye's rays hit the traversal's step bound and ended as misses or occlusion volumes{}",
            if a.method == Method::Dda {
                "; raise --dda-max-steps (`parallax bench warp --dda-sweep ...` finds the minimal artifact-free value)"
            } else {
                ""
            }
        );
    }
    Ok(())
}

/// `demo`'s stereo pair: the cyclopean view warped to both eyes (ipd 0.065, 2 layers) with
/// the quad-tree.
pub fn demo_stereo(
    scene: &parallax_scene::Scene,
    bvh: &Bvh,
    desc: &parallax_scene::CameraDesc,
    w: u32,
    h: u32,
    out: &Path,
    quiet: bool,
) -> Result<()> {
    let method = Method::QuadTree;
    let cam = Pinhole::new(desc, w, h)?;
    let mut r = capture_reference(scene, bvh, &cam, 2, Shading::Fixed, 1)?;
    let sv = warp_stereo(&mut r, desc, 0.065, method, &MethodOptions::default())?;
    let left = write_png(&out.join("stereo_warp_left.png"), &sv.views[0].image)?;
    let right = write_png(&out.join("stereo_warp_right.png"), &sv.views[1].image)?;
    if !quiet {
        println!(
            "| stereo warp ({method}, 2 layers) | pinhole | {w}x{h} x2 | - | - | {:.0} | {}, {} |",
            r.times.total_ms() + 2.0 * sv.ms_eye(),
            left.display(),
            right.display()
        );
    }
    Ok(())
}
