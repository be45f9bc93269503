//! `parallax vr`: one HVVR frame (Hunt et al. 2018) for a headset preset — both eyes rendered
//! directly into the display's (distorted) sample pattern with MSAA or SSAA, written as
//! `left.png`, `right.png` and `pattern.png` (the left eye's sample pattern), with stage timings
//! and shade counts on stdout; with `--frames N`, a sequence of a turning head, the beam
//! caster's hierarchy built once and moved per frame.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::png::{self, ToneMapping, Tonemap};
use parallax_scene::animation::Animation;
use parallax_scene::camera::{CameraModel, ModelKind};
use parallax_vr::SampleSet;
use parallax_vr::frame::{
    EyeFrame, EyeState, FrameOptions, UpdateTimings, Visibility, render_eye_with, update_scene,
};
use parallax_vr::patterns::eye_set;
use parallax_vr::presets::{Dof, HeadsetSpec, Preset, eye_cameras};
use parallax_vr::reconstruct::pattern_image;
use parallax_vr::resolve::ShadingMode;
use parallax_vr::shade::ShadeOptions;
use serde::Serialize;

use crate::args::{ViewArgs, msaa_spp};
use crate::output;

#[derive(Args, Debug)]
pub struct VrArgs {
    /// Scene and head pose (`--camera` or `--eye/--target/--up`). `--model`, `--fov-y`,
    /// `--fov` and `--ipd` apply to `--preset custom` only; the other presets fix them.
    #[command(flatten)]
    pub view: ViewArgs,
    /// Headset: rift-cv1, vive, wide-210x130 (fisheye) or custom (from the camera flags).
    #[arg(long, default_value = "rift-cv1", value_parser = Preset::parse)]
    pub preset: Preset,
    /// Subsamples per pixel: 1, 4, 8, 16 or 32.
    #[arg(long, default_value_t = 8, value_parser = msaa_spp)]
    pub msaa: u32,
    /// Shade every subsample (SSAA) instead of once per triangle per pixel (MSAA).
    #[arg(long)]
    pub ssaa: bool,
    /// Foveated sample pattern around `--gaze` (linear acuity model, HVVR §2.3).
    #[arg(long)]
    pub foveated: bool,
    /// Gaze point in normalised film coordinates x,y in [-1, 1] (0,0 = centre).
    #[arg(long, num_args = 1..=2, value_delimiter = ',', allow_negative_numbers = true, requires = "foveated")]
    pub gaze: Option<Vec<f32>>,
    /// Depth of field: aperture (pupil) diameter in metres, e.g. 0.003. Renders a thin lens.
    #[arg(long, allow_negative_numbers = true)]
    pub dof_aperture: Option<f32>,
    /// Depth of field: focus distance in metres (default: distance from eye to target).
    #[arg(long, allow_negative_numbers = true, requires = "dof_aperture")]
    pub dof_focus: Option<f32>,
    /// Subpixel rendering: one sample per colour channel, each through the lens's distortion of
    /// its own wavelength (distorted presets). Without it, the green channel's rays colour the
    /// whole pixel.
    #[arg(long)]
    pub subpixel: bool,
    /// Visibility method: beam (HVVR's beam caster, the default), beam-exact (its set-up test with the full exact band: bit-identical to per-ray), beam-watertight (beam caster with the BVH's watertight sample test) or per-ray (BVH per subsample ray, the baseline).
    #[arg(long, default_value = "beam", value_parser = Visibility::parse)]
    pub visibility: Visibility,
    /// Per-eye width override (default: the preset's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Per-eye height override (default: the preset's).
    #[arg(long)]
    pub height: Option<u32>,
    /// Trace shadow rays (HVVR shades without them).
    #[arg(long)]
    pub shadows: bool,
    /// Animate the scene to this time (s) and refit the BVH first (HVVR §5.2): a glTF file's own
    /// clips and skins when it has them, else the rigid props.
    #[arg(long)]
    pub time: Option<f32>,
    /// Output folder.
    #[arg(long, default_value = "out/vr")]
    pub out: PathBuf,
    /// Write timings and counts as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Frames to render while the head turns by `--turn` degrees about the up axis: the beam
    /// caster's hierarchy is built for the first frame and moved for the others (HVVR §5.1),
    /// and each frame's timings are printed. Files `left_000.png`, `right_000.png`, ... when
    /// more than one.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
    /// Head turn over the frames in degrees (positive: to the left), with `--frames`.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub turn: f32,
}

/// The headset of the flags: the preset, or `custom` from the camera flags; size overrides.
pub fn headset(a: &VrArgs) -> Result<HeadsetSpec> {
    let mut spec = a.preset.spec();
    if a.preset == Preset::Custom {
        let opts = a.view.camera_options()?;
        if a.view.model == ModelKind::ThinLens {
            bail!("--preset custom: use --dof-aperture / --dof-focus for a thin lens");
        }
        spec.model = a.view.model;
        if let Some(f) = a.view.fov_y {
            spec.fov_y_deg = f;
        }
        spec.fov_deg = opts.fov_deg;
        spec.ipd = a.view.ipd;
    }
    if let Some(w) = a.width {
        spec.width = w;
    }
    if let Some(h) = a.height {
        spec.height = h;
    }
    Ok(spec)
}

/// The DoF of the flags (focus defaults to the head's target distance).
fn dof(a: &VrArgs, target_distance: f32) -> Result<Option<Dof>> {
    let Some(aperture) = a.dof_aperture else {
        return Ok(None);
    };
    let d = Dof {
        aperture,
        focus: a.dof_focus.unwrap_or(target_distance),
    };
    d.validate().map_err(anyhow::Error::msg)?;
    Ok(Some(d))
}

#[derive(Serialize)]
struct VrStats {
    scene: String,
    preset: String,
    width: u32,
    height: u32,
    spp: u32,
    shading: String,
    visibility: String,
    samples: u64,
    rays: u64,
    update: Option<UpdateTimings>,
    build_ms: f64,
    eyes: Vec<parallax_vr::frame::EyeTimings>,
    shades: u64,
    shades_per_nonempty_pixel: f64,
    mrays_per_s: f64,
    /// With `--frames` above 1: every frame's head turn and eye timings (the fields above
    /// describe the last frame).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    frames: Vec<FrameStats>,
}

/// One frame of a `--frames` sequence.
#[derive(Serialize)]
struct FrameStats {
    turn_deg: f32,
    eyes: [parallax_vr::frame::EyeTimings; 2],
}

pub fn run(a: &VrArgs, quiet: bool) -> Result<()> {
    if let Some(g) = &a.gaze {
        let [x, y] = match g.as_slice() {
            [x, y] => [*x, *y],
            _ => bail!("--gaze expects x,y in [-1, 1]"),
        };
        if !(x.abs() <= 1.0 && y.abs() <= 1.0) {
            bail!("--gaze must be in [-1, 1] x [-1, 1], got {x},{y}");
        }
    }
    let gaze = match (&a.gaze, a.foveated) {
        (_, false) => None,
        (None, true) => Some([0.0, 0.0]),
        (Some(g), true) => Some([g[0], g[1]]),
    };
    let spec = headset(a)?;
    if a.subpixel && spec.model != ModelKind::Distorted {
        bail!(
            "--subpixel needs a distorted eye model (preset rift-cv1 or vive, or custom with \
             --model distorted); {} is {}",
            spec.name,
            spec.model.name()
        );
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let mut scene = a.view.load_scene()?;
    let head = a.view.camera_desc(&scene)?;
    let dof = dof(a, (head.target - head.eye).length())?;
    if dof.is_some() && a.subpixel {
        bail!("--subpixel and depth of field do not compose yet (the thin lens is undistorted)");
    }
    if !(a.turn.is_finite() && a.turn.abs() <= 360.0) {
        bail!(
            "--turn must be a finite angle of at most 360 degrees, got {}",
            a.turn
        );
    }
    let t = Instant::now();
    let mut bvh = Bvh::try_build(&scene.mesh)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let update = match a.time {
        Some(time) => {
            let anim = Animation::for_scene(&scene);
            let u = update_scene(&anim, &mut scene.mesh, &mut bvh, time)?;
            if !quiet {
                println!(
                    "animate ({}): {} objects ({} vertices) to t = {time} s in {:.2} ms, refit {:.2} ms",
                    anim.kind(),
                    anim.moving_objects(),
                    anim.moving_vertices(&scene.mesh),
                    u.animate_ms,
                    u.refit_ms
                );
            }
            Some(u)
        }
        None => None,
    };
    let opts = FrameOptions {
        spp: a.msaa,
        mode: if a.ssaa {
            ShadingMode::Ssaa
        } else {
            ShadingMode::Msaa
        },
        visibility: a.visibility,
        shade: ShadeOptions { shadows: a.shadows },
    };
    let tm = ToneMapping {
        exposure: 0.0,
        tonemap: Tonemap::AcesFilmic,
    };
    let mut eyes: Vec<EyeFrame> = Vec::with_capacity(2);
    // Each eye's beam-caster hierarchy and visibility buffer, kept from frame to frame.
    let mut states = if a.frames > 1 {
        [EyeState::moving(), EyeState::moving()]
    } else {
        [EyeState::new(), EyeState::new()]
    };
    let mut frames = Vec::new();
    for f in 0..a.frames {
        let deg = if a.frames > 1 {
            a.turn * f as f32 / (a.frames - 1) as f32
        } else {
            0.0
        };
        let cameras = eye_cameras(&spec, &head.turned(deg), dof)?;
        // The last frame's sample sets, given the moved cameras below (the pattern depends on
        // the intrinsics, which a head turn keeps).
        let mut last: [Option<SampleSet>; 2] = [None, None];
        for ((state, eye), l) in states.iter_mut().zip(eyes.drain(..)).zip(&mut last) {
            *l = Some(state.recycle(eye));
        }
        for (e, (name, cam)) in ["left", "right"].into_iter().zip(cameras).enumerate() {
            let t = Instant::now();
            let set = match last[e].take() {
                Some(mut set) => {
                    set.camera = cam;
                    set
                }
                None => eye_set(cam, a.msaa, a.subpixel, gaze)?,
            };
            let samples_ms = t.elapsed().as_secs_f64() * 1e3;
            let mut eye = render_eye_with(&scene, &bvh, set, &opts, &mut states[e])?;
            eye.timings.samples_ms = samples_ms;
            let file = if a.frames > 1 {
                format!("{name}_{f:03}.png")
            } else {
                format!("{name}.png")
            };
            png::write_png(a.out.join(file), &eye.image, &tm)?;
            eyes.push(eye);
        }
        if a.frames > 1 {
            let row = FrameStats {
                turn_deg: deg,
                eyes: [eyes[0].timings, eyes[1].timings],
            };
            if !quiet {
                let [l, r] = row.eyes;
                println!(
                    "frame {f:3}: head turned {deg:6.2} deg, visibility {:.1} + {:.1} ms \
                     (hierarchy {} {:.2} + {:.2} ms), shade {:.1} + {:.1} ms",
                    l.visibility_ms,
                    r.visibility_ms,
                    if f == 0 { "built" } else { "moved" },
                    l.hierarchy_ms,
                    r.hierarchy_ms,
                    l.shade_ms,
                    r.shade_ms
                );
            }
            frames.push(row);
        }
    }
    let pattern = a.out.join("pattern.png");
    png::write_png(
        &pattern,
        &pattern_image(&eyes[0].set),
        &ToneMapping::default(),
    )?;
    let samples: u64 = eyes.iter().map(|e| e.set.samples.len() as u64).sum();
    let rays: u64 = eyes.iter().map(|e| e.set.ray_count() as u64).sum();
    let shades: u64 = eyes.iter().map(|e| e.resolved.shades).sum();
    let nonempty: u64 = eyes.iter().map(|e| e.resolved.nonempty).sum();
    let vis_ms: f64 = eyes.iter().map(|e| e.timings.visibility_ms).sum();
    let stats = VrStats {
        scene: scene.name.clone(),
        preset: spec.name.clone(),
        width: eyes[0].set.camera.width(),
        height: eyes[0].set.camera.height(),
        spp: a.msaa,
        shading: opts.mode.name().into(),
        visibility: a.visibility.name().into(),
        samples,
        rays,
        update,
        build_ms,
        eyes: eyes.iter().map(|e| e.timings).collect(),
        shades,
        shades_per_nonempty_pixel: shades as f64 / nonempty.max(1) as f64,
        mrays_per_s: rays as f64 / (vis_ms.max(1e-9) * 1e3),
        frames,
    };
    output::write_json(a.stats.as_deref(), &stats)?;
    if !quiet {
        println!(
            "{}: preset {} ({}), {}x{} per eye, {} {}x, {} visibility, BVH {:.1} ms",
            stats.scene,
            spec.name,
            eyes[0].set.camera.kind().name(),
            stats.width,
            stats.height,
            stats.shading,
            stats.spp,
            stats.visibility,
            build_ms
        );
        println!(
            "| eye | samples | rays | samples ms | visibility ms | shade ms | reconstruct ms | shades | shades/non-empty px |"
        );
        println!("|---|---|---|---|---|---|---|---|---|");
        for (name, e) in ["left", "right"].iter().zip(&eyes) {
            println!(
                "| {name} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {:.3} |",
                e.set.samples.len(),
                e.set.ray_count(),
                e.timings.samples_ms,
                e.timings.visibility_ms,
                e.timings.shade_ms,
                e.timings.reconstruct_ms,
                e.resolved.shades,
                e.resolved.shades_per_nonempty()
            );
        }
        println!(
            "both eyes: {rays} rays, {:.2} Mrays/s visibility, {shades} shades ({:.3} per non-empty pixel)",
            stats.mrays_per_s, stats.shades_per_nonempty_pixel
        );
        if a.frames > 1 {
            println!(
                "wrote {} (left_000.png .. left_{last:03}.png, the right eye's likewise, \
                 pattern.png); the table above is the last frame's",
                a.out.display(),
                last = a.frames - 1
            );
        } else {
            println!(
                "wrote {} (left.png, right.png, pattern.png)",
                a.out.display()
            );
        }
    }
    Ok(())
}
