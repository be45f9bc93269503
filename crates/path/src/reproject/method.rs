//! One reprojection method run over a sequence: per frame it turns the traced right eye and
//! the left eye's G-buffer into the three outputs of Mäkitalo et al. 2019, §4.1:
//!
//! - **stereo**: the left eye from the right eye's new 1-spp samples (backward reprojection,
//!   [`super::footprint`]); only the discarded left pixels are path traced;
//! - **temporal**: the right eye's 1-spp samples blended into its reprojected history
//!   ([`super::history`]);
//! - **stereo + temporal**: "we first apply temporal reprojection to the right eye, after which
//!   the stereo reprojection is done from right eye to left eye"; the left pixels the stereo
//!   tests discard are filled from the left eye's own history blended with a traced sample
//!   ([`Combine::Paper`]). [`Combine::Cascade`] instead keeps a full left history: every left
//!   pixel blends the stereo-reprojected right history (or its traced sample) into the left's
//!   reprojected history, so the left eye averages both eyes' histories.
//!
//! | field | type | paper | meaning |
//! |---|---|---|---|
//! | `kernel` | [`Kernel`] | bilinear | reconstruction weights of both reprojections |
//! | `blend` | [`Blend`] | `Fixed(0.2)` | temporal blend |
//! | `demodulate` | bool | false | reproject radiance divided by the source texel's albedo and multiply by the target's (texture detail is not blurred; as SVGF and BMFR treat albedo) |
//! | `combine` | [`Combine`] | `Paper` | how the left eye of stereo + temporal uses histories |
//! | `plane_test` | bool | false | position test against the target's tangent plane ([`Tests::plane`]) |
//!
//! **Invariants:** a method's outputs depend only on the inputs of this and earlier frames
//! (never on the thread count); a discarded left pixel is the path tracer's own sample of the
//! left eye's stream, bit for bit.

use std::borrow::Cow;
use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::buffers::EyeView;
use super::error::{Result, option_error};
use super::footprint::{
    BAND_ROWS, Footprint, Kernel, Outcome, Reprojector, Tests, footprints_with,
};
use super::history::{Accumulation, Alpha, Blend, History, accumulate_with};
use super::isa::Isa;
use super::sampler::{PaperSampler, TraceCost, thread_ns};

/// How stereo + temporal fills the left eye (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Combine {
    Paper,
    Cascade,
}

/// A reprojection method (module table).
#[derive(Clone, Debug, PartialEq)]
pub struct Method {
    pub name: String,
    pub kernel: Kernel,
    pub blend: Blend,
    pub demodulate: bool,
    pub combine: Combine,
    pub plane_test: bool,
}

impl Method {
    /// Mäkitalo et al. 2019 as published: bilinear weights, alpha 0.2, radiance reprojected
    /// as it is, the left eye's history only where the stereo tests discard.
    pub fn paper() -> Self {
        Self {
            name: "paper".into(),
            kernel: Kernel::BILINEAR,
            blend: Blend::PAPER,
            demodulate: false,
            combine: Combine::Paper,
            plane_test: false,
        }
    }

    /// The named presets: `paper` ([`Self::paper`]), `bmfr` (the paper with BMFR's running
    /// mean, floor 0.2), and `ours` ([`Self::ours`]).
    pub fn named(name: &str) -> Result<Self> {
        match name {
            "paper" => Ok(Self::paper()),
            "bmfr" => Ok(Self {
                name: "bmfr".into(),
                blend: Blend::RunningMean { floor: 0.2 },
                ..Self::paper()
            }),
            "ours" => Ok(Self::ours()),
            _ => option_error(format!(
                "unknown method {name:?}; expected one of {}",
                Self::NAMES.join(", ")
            )),
        }
    }

    /// Names [`Self::named`] knows.
    pub const NAMES: [&'static str; 3] = ["paper", "bmfr", "ours"];

    /// Our variant: both eyes keep a full history ([`Combine::Cascade`]), BMFR's running
    /// mean, radiance demodulated by albedo before it is reprojected, and the tangent-plane
    /// position test.
    pub fn ours() -> Self {
        Self {
            name: "ours".into(),
            kernel: Kernel::BILINEAR,
            blend: Blend::RunningMean { floor: 0.2 },
            demodulate: true,
            combine: Combine::Cascade,
            plane_test: true,
        }
    }

    /// Alpha in (0, 1], kernel radius in [1, 2].
    pub fn validate(&self) -> Result<()> {
        let a = self.blend.base_alpha();
        if !(a > 0.0 && a <= 1.0) {
            return option_error(format!("--alpha must be in (0, 1], got {a}"));
        }
        let r = self.kernel.radius;
        if !(1.0..=2.0).contains(&r) {
            return option_error(format!("--kernel-radius must be in [1, 2], got {r}"));
        }
        Ok(())
    }
}

/// The inputs every method of a frame shares.
pub struct FrameInputs<'a> {
    pub sampler: &'a PaperSampler<'a>,
    /// The traced eye's G-buffer and the radiance of its 1-spp samples.
    pub right: Arc<EyeView>,
    pub right_radiance: &'a [Vec3],
    /// The other eye's G-buffer and the radiance of its pixels that see the sky.
    pub left: Arc<EyeView>,
    pub left_background: &'a [Vec3],
    /// The stream of the left eye's samples (for the pixels traced after discarding).
    pub left_seed: u64,
    pub tests: Tests,
}

/// One output image of a frame.
#[derive(Clone, Debug)]
pub struct ModeFrame {
    /// Linear RGB, row-major.
    pub image: Vec<Vec3>,
    /// What became of each pixel.
    pub outcomes: Vec<Outcome>,
    /// Thread CPU nanoseconds of the reprojection passes this output needed.
    pub reproject_ns: u64,
}

impl ModeFrame {
    /// Pixels that needed a new sample (or restarted their history).
    pub fn discarded(&self) -> usize {
        self.outcomes.iter().filter(|o| o.is_discarded()).count()
    }
}

/// The three outputs of a frame.
pub struct MethodFrame {
    pub stereo: ModeFrame,
    pub temporal: ModeFrame,
    pub combined: ModeFrame,
    /// The left pixels traced after the stereo tests.
    pub left_traced: TraceCost,
}

/// A method with its histories.
pub struct MethodState {
    pub method: Method,
    right: Option<History>,
    left: Option<History>,
    /// The traced left samples (demodulated when the method demodulates) at their pixels;
    /// only this frame's discarded pixels are written and read, so it is kept between frames
    /// without clearing.
    traced: Vec<Vec3>,
    /// The build the passes run in ([`Isa::detect`] unless set with [`Self::with_isa`]).
    isa: Isa,
}

/// Runs `f(i)` for every pixel into a new image, parallel over bands, in the build of `isa`;
/// returns the image and the thread CPU nanoseconds.
fn per_pixel(n: usize, w: usize, isa: Isa, f: impl Fn(usize) -> Vec3 + Sync) -> (Vec<Vec3>, u64) {
    let mut out = vec![Vec3::ZERO; n];
    let ns: Vec<u64> = out
        .par_chunks_mut(w * BAND_ROWS)
        .enumerate()
        .map(|(b, chunk)| {
            let t0 = thread_ns();
            let base = b * w * BAND_ROWS;
            isa.run(
                #[inline(always)]
                || {
                    for (j, o) in chunk.iter_mut().enumerate() {
                        *o = f(base + j);
                    }
                },
            );
            thread_ns().saturating_sub(t0)
        })
        .collect();
    (out, ns.iter().sum())
}

/// The stereo value of left pixel `i`: `reused(footprint)` where the stereo tests kept a
/// neighbour, the environment where it sees the sky, else its traced sample.
#[inline(always)]
fn stereo_value(
    i: usize,
    fps: &[Footprint],
    background: &[Vec3],
    traced: &[Vec3],
    reused: impl FnOnce(&Footprint) -> Vec3,
) -> Vec3 {
    match fps[i].outcome {
        Outcome::Reused => reused(&fps[i]),
        Outcome::Background => background[i],
        _ => traced[i],
    }
}

impl MethodState {
    pub fn new(method: Method) -> Self {
        Self {
            method,
            right: None,
            left: None,
            traced: Vec::new(),
            isa: Isa::detect(),
        }
    }

    /// The same method with its passes run in the build of `isa` (the outputs are the same
    /// bit for bit in every build).
    pub fn with_isa(mut self, isa: Isa) -> Self {
        self.isa = isa;
        self
    }

    /// Drops the histories (the next frame starts a new sequence).
    pub fn reset(&mut self) {
        self.right = None;
        self.left = None;
    }

    /// Runs one frame. Every pass over the pixels does one job whole: the footprints, then
    /// one pass per output that gathers, blends and remodulates. Each output's cost counts the
    /// passes it needs on its own: stereo its footprints, traced samples' storing and image
    /// (and the demodulated right samples it gathers from); temporal the right eye's
    /// accumulation (which demodulates its new samples itself); stereo + temporal the stereo
    /// footprints, the traced samples' storing and both eyes' accumulations.
    pub fn step(&mut self, inp: &FrameInputs) -> MethodFrame {
        let m = &self.method;
        let k = m.kernel;
        let tests = Tests {
            plane: m.plane_test,
            ..inp.tests
        };
        let (left, right) = (&inp.left, &inp.right);
        let (n, w) = (left.len(), left.width() as usize);
        let rw = right.width();
        let demod = m.demodulate;
        let r_rad = inp.right_radiance;
        // Stereo: footprints of the left pixels in the right view, then the discarded pixels
        // traced.
        let mut fps = Vec::new();
        let fp_ns = footprints_with(left, right, k, tests, &mut fps, self.isa);
        let discarded: Vec<u32> = (0..n as u32)
            .filter(|&i| fps[i as usize].outcome.is_discarded())
            .collect();
        let mut traced_list = vec![Vec3::ZERO; discarded.len()];
        let left_traced =
            inp.sampler
                .trace_pixels(&left.camera, inp.left_seed, &discarded, &mut traced_list);
        let t0 = thread_ns();
        let traced = &mut self.traced;
        traced.resize(n, Vec3::ZERO);
        for (&i, v) in discarded.iter().zip(&traced_list) {
            traced[i as usize] = left.texels[i as usize].demodulate(*v, demod);
        }
        let traced = &*traced;
        let traced_ns = thread_ns().saturating_sub(t0);
        let background = inp.left_background;
        let (r_new, rnew_ns): (Cow<[Vec3]>, u64) = if demod {
            let (v, ns) = per_pixel(
                right.len(),
                right.width() as usize,
                self.isa,
                #[inline(always)]
                |i| right.texels[i].demodulate(r_rad[i], true),
            );
            (Cow::Owned(v), ns)
        } else {
            (Cow::Borrowed(r_rad), 0)
        };
        let (image, apply_ns) = per_pixel(
            n,
            w,
            self.isa,
            #[inline(always)]
            |i| {
                let v = stereo_value(
                    i,
                    &fps,
                    background,
                    traced,
                    #[inline(always)]
                    |f| f.gather(k, &r_new, rw),
                );
                left.texels[i].remodulate(v, demod)
            },
        );
        drop(r_new);
        let shared_ns = fp_ns + traced_ns;
        let stereo = ModeFrame {
            image,
            outcomes: fps.iter().map(|f| f.outcome).collect(),
            reproject_ns: shared_ns + rnew_ns + apply_ns,
        };

        // Temporal: the right eye's history.
        let how = Accumulation {
            kernel: k,
            tests,
            blend: m.blend,
            demodulated: demod,
        };
        let acc = accumulate_with(
            right,
            #[inline(always)]
            |i| right.texels[i].demodulate_lanes(r_rad[i], demod),
            self.right.as_ref(),
            &how,
            self.isa,
        );
        let temporal = ModeFrame {
            image: acc.image,
            outcomes: acc.outcomes,
            reproject_ns: acc.cpu_ns,
        };
        let r_acc = &acc.history;

        // Stereo + temporal.
        let (left_hist, image, left_ns) = match m.combine {
            Combine::Paper => self.paper_left(inp, &fps, r_acc),
            Combine::Cascade => {
                let a = accumulate_with(
                    left,
                    #[inline(always)]
                    |i| match fps[i].outcome {
                        Outcome::Reused => fps[i].gather(k, &r_acc.acc, rw),
                        Outcome::Background => background[i].extend(0.0),
                        _ => traced[i].extend(0.0),
                    },
                    self.left.as_ref(),
                    &how,
                    self.isa,
                );
                (a.history, a.image, a.cpu_ns)
            }
        };
        let combined = ModeFrame {
            image,
            outcomes: stereo.outcomes.clone(),
            reproject_ns: shared_ns + acc.cpu_ns + left_ns,
        };
        self.right = Some(acc.history);
        self.left = Some(left_hist);
        MethodFrame {
            stereo,
            temporal,
            combined,
            left_traced,
        }
    }

    /// The paper's left eye of stereo + temporal: the stereo-reprojected right history where
    /// the stereo tests keep a neighbour, else the traced sample blended into the left eye's
    /// own reprojected history.
    fn paper_left(
        &self,
        inp: &FrameInputs,
        fps: &[Footprint],
        r_acc: &History,
    ) -> (History, Vec<Vec3>, u64) {
        let m = &self.method;
        let (left, k) = (&inp.left, m.kernel);
        let (n, w) = (left.len(), left.width() as usize);
        let rw = inp.right.width();
        let prev = self.left.as_ref();
        let traced = &self.traced;
        let band = w * BAND_ROWS;
        let mut acc = vec![Vec4::ZERO; n];
        let mut image = vec![Vec3::ZERO; n];
        let tests = Tests {
            plane: m.plane_test,
            ..inp.tests
        };
        let rep = prev.map(|p| Reprojector::new(&p.view, k, tests));
        let alpha = Alpha::new(m.blend);
        let ns: Vec<u64> = acc
            .par_chunks_mut(band)
            .zip(image.par_chunks_mut(band))
            .enumerate()
            .map(|(b, (hist, img))| {
                let t0 = thread_ns();
                let base = b * band;
                self.isa.run(
                    #[inline(always)]
                    || {
                        for (j, (hj, ij)) in hist.iter_mut().zip(img).enumerate() {
                            let i = base + j;
                            let (c, cnt) = match fps[i].outcome {
                                Outcome::Reused => {
                                    let g = fps[i].gather(k, &r_acc.acc, rw);
                                    (g.truncate(), g.w.max(1.0))
                                }
                                Outcome::Background => (inp.left_background[i], 1.0),
                                _ => {
                                    let mut out = (traced[i], 1.0);
                                    if let (Some(p), Some(rep)) = (prev, &rep) {
                                        let f = rep.footprint(&left.texels[i]);
                                        if f.outcome == Outcome::Reused {
                                            let g = f.gather(k, &p.acc, p.view.width());
                                            let (h, hn) = (g.truncate(), g.w);
                                            let a = alpha.alpha(hn);
                                            out = (traced[i] * a + h * (1.0 - a), hn + 1.0);
                                        }
                                    }
                                    out
                                }
                            };
                            *hj = c.extend(cnt);
                            *ij = left.texels[i].remodulate(c, m.demodulate);
                        }
                    },
                );
                thread_ns().saturating_sub(t0)
            })
            .collect();
        (
            History {
                view: left.clone(),
                acc,
            },
            image,
            ns.iter().sum(),
        )
    }
}
