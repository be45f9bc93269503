//! A stereo sequence (Mäkitalo et al. 2019, §4.1): per frame the scene is posed, the right eye
//! is path traced at 1 spp (G-buffer + radiance), the left eye's G-buffer is taken from its
//! primary rays, and every method turns them into its stereo, temporal and stereo + temporal
//! frames; a callback sees each frame (to score it or write it).
//!
//! Streams: the right and left eye of frame `f` use seeds [`eye_seed`]`(seed, f, eye)`, so
//! every frame gets fresh noise and a rerun gets the same; references use
//! [`reference_seed`], another stream.
//!
//! | parameter | type | default (CLI) | meaning |
//! |---|---|---|---|
//! | `width`, `height` | u32 | 320 x 180 (bench) | film of ONE eye |
//! | `ipd` | f32 | 0.065 | eye separation (m): the paper's parallel rig, 6.5 cm |
//! | `frames` | u32 | 60 | frames from the start of the path |
//! | `seed` | u64 | 0 | seed of every stream |
//! | `materials` | [`MaterialMode`] | as-is | the scene's materials or all Lambertian |
//! | `max_position` | `Option<f32>` | from the scene scale | world-position limit (scene units); `None`: [`default_tests`] |
//! | `max_normal_deg` | `Option<f32>` | [`NORMAL_DEG`] | shading-normal limit (degrees) |
//!
//! Default limits ("the scene-specific limits used in our measurements were each decided
//! based on the scale of the particular scene"): the scene scale `s` is the median view depth
//! of the traced eye's first frame (what the viewer sees, robust to ground planes that reach
//! far beyond it); position limit `POSITION_FRACTION · s`, normal limit `NORMAL_DEG`.

use std::sync::Arc;

use glam::Vec3;
use parallax_core::sampling::rng::splitmix64;
use parallax_render::bsdf::MaterialMode;
use parallax_scene::CameraDesc;
use parallax_scene::camera::{Camera, CameraOptions, Eye, ModelKind, Pinhole, eye_camera};

use super::buffers::EyeView;
use super::dataset::FrameWorld;
use super::error::{Result, option_error};
use super::footprint::Tests;
use super::method::{FrameInputs, MethodFrame, MethodState};
use super::sampler::{PaperSampler, TraceCost};

/// Position limit as a fraction of the scene scale.
pub const POSITION_FRACTION: f32 = 0.03;
/// Normal limit (degrees).
pub const NORMAL_DEG: f32 = 25.0;

/// See the module table.
#[derive(Clone, Debug, PartialEq)]
pub struct RunOptions {
    pub width: u32,
    pub height: u32,
    pub ipd: f32,
    pub frames: u32,
    pub seed: u64,
    pub materials: MaterialMode,
    pub max_position: Option<f32>,
    pub max_normal_deg: Option<f32>,
}

impl RunOptions {
    /// Film and frame counts within range, limits finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.width > 8192 || self.height > 8192 {
            return option_error(format!(
                "--width and --height must be in 1..=8192, got {}x{}",
                self.width, self.height
            ));
        }
        if !(self.ipd.is_finite() && self.ipd >= 0.0) {
            return option_error(format!("--ipd must be finite and >= 0, got {}", self.ipd));
        }
        Tests {
            position: self.max_position.unwrap_or(0.0),
            normal_deg: self.max_normal_deg.unwrap_or(NORMAL_DEG),
            plane: false,
        }
        .validate()
    }
}

impl Tests {
    /// Finite, non-negative limits; the normal at most 180 degrees.
    pub fn validate(&self) -> Result<()> {
        if !(self.position.is_finite() && self.position >= 0.0) {
            return option_error(format!(
                "--max-position must be a finite distance >= 0, got {}",
                self.position
            ));
        }
        if !(self.normal_deg.is_finite() && (0.0..=180.0).contains(&self.normal_deg)) {
            return option_error(format!(
                "--max-normal-deg must be in [0, 180] degrees, got {}",
                self.normal_deg
            ));
        }
        Ok(())
    }
}

/// The default limits for a first traced frame (module docs); `None` if nothing was hit.
pub fn default_tests(view: &EyeView) -> Option<Tests> {
    let mut depths: Vec<f32> = view
        .texels
        .iter()
        .filter(|t| t.is_hit())
        .map(|t| t.depth)
        .collect();
    if depths.is_empty() {
        return None;
    }
    let mid = depths.len() / 2;
    let (_, median, _) = depths.select_nth_unstable_by(mid, f32::total_cmp);
    Some(Tests {
        position: POSITION_FRACTION * *median,
        normal_deg: NORMAL_DEG,
        plane: false,
    })
}

fn eye_index(eye: Eye) -> u64 {
    match eye {
        Eye::Left => 0,
        Eye::Right => 1,
    }
}

/// The stream of `eye` at frame `f`.
pub fn eye_seed(seed: u64, f: u32, eye: Eye) -> u64 {
    splitmix64(seed ^ splitmix64(((f as u64) << 1 | eye_index(eye)) + 1))
}

/// The stream of the reference render of `eye` at frame `f` (independent of [`eye_seed`]).
pub fn reference_seed(seed: u64, f: u32, eye: Eye) -> u64 {
    splitmix64(eye_seed(seed, f, eye) ^ 0x005E_ED0F_2EF5_EED5)
}

/// The pinhole of `eye` for head pose `head` and a `width x height` film (checked).
pub fn eye_pinhole(
    head: &CameraDesc,
    ipd: f32,
    eye: Eye,
    width: u32,
    height: u32,
) -> Result<Pinhole> {
    let desc = eye_camera(head, ipd, eye)?;
    match Camera::new(
        ModelKind::Pinhole,
        &desc,
        width,
        height,
        &CameraOptions::default(),
    )? {
        Camera::Pinhole(p) => Ok(p),
        _ => unreachable!("a pinhole was asked for"),
    }
}

/// What the callback sees of one frame.
pub struct Frame<'a> {
    pub index: u32,
    pub right: &'a EyeView,
    pub right_radiance: &'a [Vec3],
    pub left: &'a EyeView,
    pub right_seed: u64,
    pub left_seed: u64,
    /// The right eye's 1-spp trace (all pixels) and the left eye's primary rays.
    pub right_trace: TraceCost,
    pub left_gbuffer: TraceCost,
    pub tests: Tests,
    /// Per method, in the order given.
    pub methods: &'a [MethodFrame],
}

/// Runs `opts.frames` frames of `world` through every method (histories restart first);
/// `on_frame(frame, world)` is called after each frame, in order.
pub fn run(
    world: &mut dyn FrameWorld,
    opts: &RunOptions,
    methods: &mut [MethodState],
    on_frame: &mut dyn FnMut(&Frame, &dyn FrameWorld) -> Result<()>,
) -> Result<()> {
    if opts.frames == 0 || opts.frames > world.frames() {
        return option_error(format!(
            "--frames must be in 1..={} (the sequence's length), got {}",
            world.frames(),
            opts.frames
        ));
    }
    opts.validate()?;
    for m in methods.iter_mut() {
        m.reset();
    }
    let mut tests: Option<Tests> = None;
    for f in 0..opts.frames {
        world.pose(f)?;
        let head = world.head(f);
        let right_cam = eye_pinhole(&head, opts.ipd, Eye::Right, opts.width, opts.height)?;
        let left_cam = eye_pinhole(&head, opts.ipd, Eye::Left, opts.width, opts.height)?;
        let sampler = PaperSampler::new(world.scene(), world.tracer(), opts.materials);
        let (right_seed, left_seed) = (
            eye_seed(opts.seed, f, Eye::Right),
            eye_seed(opts.seed, f, Eye::Left),
        );
        let mut right = EyeView::new(right_cam);
        let mut right_radiance = vec![Vec3::ZERO; right.len()];
        let right_trace = sampler.trace_eye(right_seed, &mut right, &mut right_radiance);
        let mut left = EyeView::new(left_cam);
        let mut left_background = vec![Vec3::ZERO; left.len()];
        let left_gbuffer = sampler.trace_gbuffer(left_seed, &mut left, &mut left_background);
        let t = *tests.get_or_insert_with(|| {
            let scale = default_tests(&right).map_or(0.0, |d| d.position);
            Tests {
                position: opts.max_position.unwrap_or(scale),
                normal_deg: opts.max_normal_deg.unwrap_or(NORMAL_DEG),
                plane: false,
            }
        });
        let (right, left) = (Arc::new(right), Arc::new(left));
        let inputs = FrameInputs {
            sampler: &sampler,
            right: right.clone(),
            right_radiance: &right_radiance,
            left: left.clone(),
            left_background: &left_background,
            left_seed,
            tests: t,
        };
        let frames: Vec<MethodFrame> = methods.iter_mut().map(|m| m.step(&inputs)).collect();
        drop(inputs);
        drop(sampler);
        let frame = Frame {
            index: f,
            right: &right,
            right_radiance: &right_radiance,
            left: &left,
            right_seed,
            left_seed,
            right_trace,
            left_gbuffer,
            tests: t,
            methods: &frames,
        };
        on_frame(&frame, world)?;
    }
    Ok(())
}
