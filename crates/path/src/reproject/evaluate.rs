//! Scoring a stereo sequence as Mäkitalo et al. 2019 do (§4.2, Tables 1-2): per frame and
//! method, the stereo output (left eye) and the stereo + temporal output (left eye) are scored
//! against the left eye's reference, the temporal output (right eye) against the right eye's;
//! each score is an effective spp ([`super::metric`]) and a discarded fraction.
//!
//! Discarded fractions follow the paper's Table 1: stereo over every frame (left pixels that
//! needed a new sample), temporal over frames `1..` (the first frame has no history; the
//! paper's N = 59); stereo + temporal reports the left pixels it traced (the stereo discards).
//! Pixels that see the sky are never discarded (their value is the environment).
//!
//! Costs are thread CPU time summed over the workers, for the reprojection passes of a mode
//! (footprints, gathers, blends; not the tracing of the discarded pixels) and for the 1-spp
//! trace of the whole right eye, so their ratio does not depend on how busy the machine is.
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `run` | [`RunOptions`] | film, frames, seed, materials, limits |
//! | `reference` | [`ReferenceSpec`] | reference spp and the error curve's largest n |
//! | `cache` | [`ReferenceCache`] | where references are kept between runs |
//!
//! **Invariants:** every score is a function of the options and the scene alone (references
//! are either rendered or read back bit for bit), so two runs agree at any thread count.

use super::dataset::FrameWorld;
use super::error::{Result, option_error};
use super::fingerprint::Fingerprint;
use super::footprint::Tests;
use super::method::{Method, MethodState, ModeFrame};
use super::metric::mse;
use super::reference::{ReferenceCache, ReferenceSpec, cache_key, render_reference};
use super::sequence::{Frame, RunOptions, reference_seed, run};
use parallax_scene::camera::{Eye, Pinhole};

/// One of the paper's three reprojection schemes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    Stereo,
    Temporal,
    StereoTemporal,
}

impl Mode {
    pub const ALL: [Mode; 3] = [Mode::Stereo, Mode::Temporal, Mode::StereoTemporal];

    /// `stereo`, `temporal`, `stereo+temporal` (the JSON rows' `mode`).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Stereo => "stereo",
            Mode::Temporal => "temporal",
            Mode::StereoTemporal => "stereo+temporal",
        }
    }

    /// The eye the mode's output belongs to.
    pub fn eye(self) -> Eye {
        match self {
            Mode::Temporal => Eye::Right,
            _ => Eye::Left,
        }
    }
}

/// What [`evaluate`] needs (module table).
#[derive(Clone, Debug)]
pub struct EvalOptions {
    pub run: RunOptions,
    pub reference: ReferenceSpec,
    pub cache: ReferenceCache,
}

/// One frame's score of one method and mode.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameScore {
    pub frame: u32,
    pub effective_spp: f64,
    /// The error was below the curve's last point (extrapolated count).
    pub extrapolated: bool,
    /// RMSE against the reference (reference noise included).
    pub rmse: f64,
    /// Percent of the eye's pixels discarded; `None` where the mode's Table 1 skips the frame.
    pub discard_pct: Option<f64>,
    pub reproject_ns: u64,
}

/// The per-frame scores of one method and mode.
#[derive(Clone, Debug)]
pub struct Series {
    pub method: String,
    pub mode: Mode,
    pub frames: Vec<FrameScore>,
}

/// Average, minimum and maximum.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub avg: f64,
    pub min: f64,
    pub max: f64,
}

impl Stats {
    /// Stats of `values` (all zero when empty).
    pub fn of(values: impl IntoIterator<Item = f64>) -> Stats {
        let (mut n, mut sum, mut min, mut max) = (0usize, 0.0, f64::INFINITY, f64::NEG_INFINITY);
        for v in values {
            n += 1;
            sum += v;
            min = min.min(v);
            max = max.max(v);
        }
        if n == 0 {
            return Stats::default();
        }
        Stats {
            avg: sum / n as f64,
            min,
            max,
        }
    }
}

impl Series {
    pub fn effective_spp(&self) -> Stats {
        Stats::of(self.frames.iter().map(|f| f.effective_spp))
    }

    pub fn discard_pct(&self) -> Stats {
        Stats::of(self.frames.iter().filter_map(|f| f.discard_pct))
    }

    /// Mean reprojection ms per frame.
    pub fn ms_reproject(&self) -> f64 {
        Stats::of(self.frames.iter().map(|f| f.reproject_ns as f64 * 1e-6)).avg
    }

    /// Frames whose count was extrapolated beyond the curve.
    pub fn extrapolated(&self) -> usize {
        self.frames.iter().filter(|f| f.extrapolated).count()
    }
}

/// The scores of a sequence.
#[derive(Clone, Debug)]
pub struct Evaluation {
    pub label: String,
    /// Per method (in the order given), per mode ([`Mode::ALL`] order).
    pub series: Vec<Series>,
    /// Mean ms (thread CPU, summed over workers) of the right eye's 1-spp trace per frame.
    pub ms_trace_1spp: f64,
    /// The limits used.
    pub tests: Tests,
    /// Largest ratio over frames and eyes of the reference's noise variance to the smallest
    /// noise-free MSE measured against it (how much the reference's own noise could matter).
    pub reference_noise_ratio: f64,
    pub references_rendered: usize,
    pub references_cached: usize,
}

impl Evaluation {
    /// The series of `method` in `mode`.
    pub fn series(&self, method: &str, mode: Mode) -> Option<&Series> {
        self.series
            .iter()
            .find(|s| s.method == method && s.mode == mode)
    }
}

fn pct(part: usize, n: usize) -> f64 {
    100.0 * part as f64 / n.max(1) as f64
}

/// Runs `methods` over `world`'s sequence and scores every frame (module docs);
/// `progress(samples)` counts reference pixel samples rendered or read.
pub fn evaluate(
    world: &mut dyn FrameWorld,
    opts: &EvalOptions,
    methods: &[Method],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Evaluation> {
    opts.reference.validate()?;
    if opts.run.frames < 2 {
        return option_error(format!(
            "--frames must be at least 2 for the temporal modes (got {})",
            opts.run.frames
        ));
    }
    for m in methods {
        m.validate()?;
    }
    let mut states: Vec<MethodState> = methods.iter().cloned().map(MethodState::new).collect();
    let mut series: Vec<Series> = methods
        .iter()
        .flat_map(|m| {
            Mode::ALL.map(|mode| Series {
                method: m.name.clone(),
                mode,
                frames: Vec::new(),
            })
        })
        .collect();
    let static_scene =
        (!world.geometry_moves()).then(|| *Fingerprint::new().scene_content(world.scene()));
    let mut trace_ns = 0u64;
    let mut tests = None;
    let (mut rendered, mut cached, mut noise_ratio) = (0usize, 0usize, 0.0f64);
    let spec = opts.reference;
    let run_opts = &opts.run;
    let mut on_frame = |frame: &Frame, w: &dyn FrameWorld| -> Result<()> {
        trace_ns += frame.right_trace.cpu_ns;
        tests = Some(frame.tests);
        let scene_fp = static_scene.unwrap_or_else(|| *Fingerprint::new().scene_content(w.scene()));
        let mut reference = |camera: &Pinhole, eye: Eye| {
            let seed = reference_seed(run_opts.seed, frame.index, eye);
            let key = cache_key(
                &scene_fp,
                w.scene(),
                camera,
                frame.index,
                spec,
                seed,
                run_opts.materials,
            );
            let pixels = camera.width as usize * camera.height as usize;
            let r = opts.cache.get_or_render(&key, pixels, spec, || {
                render_reference(
                    w.scene(),
                    w.tracer(),
                    camera,
                    run_opts.materials,
                    spec,
                    seed,
                    progress,
                )
            })?;
            if r.cached {
                cached += 1;
                progress(pixels as u64 * spec.spp as u64);
            } else {
                rendered += 1;
            }
            Ok::<_, super::error::ReprojectError>(r)
        };
        let right_ref = reference(&frame.right.camera, Eye::Right)?;
        let left_ref = reference(&frame.left.camera, Eye::Left)?;
        let n = frame.left.len();
        for (mi, mf) in frame.methods.iter().enumerate() {
            for (k, mode) in Mode::ALL.into_iter().enumerate() {
                let (out, r): (&ModeFrame, _) = match mode {
                    Mode::Stereo => (&mf.stereo, &left_ref),
                    Mode::Temporal => (&mf.temporal, &right_ref),
                    Mode::StereoTemporal => (&mf.combined, &left_ref),
                };
                let e = mse(&out.image, &r.image);
                let eff = r.curve.effective_spp(e);
                let v = r.curve.reference_noise;
                if e > v {
                    noise_ratio = noise_ratio.max(v / (e - v));
                }
                let skip = mode == Mode::Temporal && frame.index == 0;
                series[mi * Mode::ALL.len() + k].frames.push(FrameScore {
                    frame: frame.index,
                    effective_spp: eff.spp,
                    extrapolated: eff.extrapolated,
                    rmse: e.sqrt(),
                    discard_pct: (!skip).then(|| pct(out.discarded(), n)),
                    reproject_ns: out.reproject_ns,
                });
            }
        }
        Ok(())
    };
    run(world, run_opts, &mut states, &mut on_frame)?;
    Ok(Evaluation {
        label: world.label(),
        series,
        ms_trace_1spp: trace_ns as f64 * 1e-6 / opts.run.frames as f64,
        tests: tests.expect("at least one frame ran"),
        reference_noise_ratio: noise_ratio,
        references_rendered: rendered,
        references_cached: cached,
    })
}
