//! `parallax warp`: stereo warping of a cyclopean reference (Widmer et al. 2015, §5.1, Table 2)
//! with any method, from a scene or from a colour + depth image pair; writes both eyes, their
//! hit-type images (Fig. 6d: misses red, occlusion volumes blue) and intersection heatmaps
//! (Fig. 1c), and scores the eyes against the BVH reference render of the eye cameras.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::exr;
use parallax_core::image::png::{self, ToneMapping};
use parallax_render::score::SCORE_TONEMAP;
use parallax_scene::camera::Pinhole;
use parallax_synth::bench::warp::{StereoSetup, eye_truths, score_pair};
use parallax_synth::capture_reference;
use parallax_synth::method::{Method, cube_near_name};
use parallax_synth::stereo::warp_stereo;
use parallax_synth::warp::WarpedView;

use crate::args::{MethodArgs, SynthArgs, SynthSize, ViewArgs};
use crate::output;
use crate::progress;

#[derive(Args, Debug)]
pub struct WarpArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    #[command(flatten)]
    pub choice: MethodArgs,
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
    /// Also write the eyes' linear colour as EXR (`left.exr`, `right.exr`).
    #[arg(long)]
    pub exr: bool,
}

/// Writes the colour, hit-type and heatmap PNGs of one view as `DIR/NAME*.png`, the colour
/// through `tm` (hit types through the scores' display transform).
pub fn write_view(
    dir: &Path,
    name: &str,
    v: &WarpedView,
    tm: &ToneMapping,
) -> Result<Vec<PathBuf>> {
    let p = dir.join(format!("{name}.png"));
    png::write_png(&p, &v.image, tm)?;
    let tm = SCORE_TONEMAP;
    let hits = dir.join(format!("{name}.hits.png"));
    png::write_png(&hits, &v.hit_type_image(), &tm)?;
    let heat = dir.join(format!("{name}.heat.png"));
    png::write_png(&heat, &v.heatmap(None).0, &ToneMapping::default())?;
    Ok(vec![p, hits, heat])
}

pub fn run(a: &WarpArgs, quiet: bool) -> Result<()> {
    a.view.check_ipd()?;
    let opts = a.synth.method_options()?;
    a.size.check_memory(a.choice.capture_layers())?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let pb = progress::bar(4, "warp", quiet);
    // Reference: from a scene, or from colour + depth.
    let (mut reference, desc, scene) = match (&a.color, &a.depth) {
        (Some(c), Some(d)) => {
            let (r, desc) = super::input::load_color_depth(&a.view, c, d, a.focal_px)?;
            (r, desc, None)
        }
        _ => {
            pb.set_message("reference");
            let scene = a.view.load_scene()?;
            let bvh = Bvh::try_build(&scene.mesh)?;
            let desc = a.view.camera_desc(&scene)?;
            let cam = Pinhole::new(&desc, a.size.width, a.size.height)?;
            let layers = a.choice.capture_layers();
            let shading = a.synth.shading();
            let r = capture_reference(&scene, &bvh, &cam, layers, shading, a.synth.seed)?;
            (r, desc, Some((scene, bvh)))
        }
    };
    pb.inc(1);
    pb.set_message(a.choice.method.name());
    let sv = warp_stereo(&mut reference, &desc, a.view.ipd, a.choice.method, &opts)?;
    pb.inc(1);
    // A user's content keeps its encoding (`super::input` module docs).
    let tm = super::input::output_tonemap(scene.is_none());
    let reference_png = a.out.join("reference.png");
    png::write_png(&reference_png, &reference.colors[0], &tm)?;
    let mut written = vec![reference_png];
    for (name, v) in ["left", "right"].iter().zip(&sv.views) {
        written.extend(write_view(&a.out, name, v, &tm)?);
        if a.exr {
            let p = a.out.join(format!("{name}.exr"));
            let rgb = |f: fn(&glam::Vec3) -> f32| v.image.data().iter().map(f).collect::<Vec<_>>();
            let (r, g, b) = (rgb(|c| c.x), rgb(|c| c.y), rgb(|c| c.z));
            let (w, h) = (v.image.width(), v.image.height());
            exr::write_exr(&p, w, h, &[("R", &r), ("G", &g), ("B", &b)])?;
            written.push(p);
        }
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
                shading: a.synth.shading(),
                seed: a.synth.seed,
                score: true,
                repeats: 1,
            };
            let truths = eye_truths(scene, bvh, &setup)?;
            written.push(output::write_png(&a.out.join("left.bvh.png"), &truths[0])?);
            written.push(output::write_png(&a.out.join("right.bvh.png"), &truths[1])?);
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
            a.choice.method,
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
            if a.choice.method == Method::Dda {
                "; raise --dda-max-steps (`parallax bench warp --dda-sweep ...` finds the minimal artifact-free value)"
            } else {
                ""
            }
        );
    }
    Ok(())
}
