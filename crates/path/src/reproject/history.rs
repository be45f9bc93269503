//! Temporal accumulation (Mäkitalo et al. 2019, §4.1: "we accumulate data from earlier frames
//! with a 20% blending ratio, i.e., weighing the existing accumulated data with a factor of
//! 0.8, and combining it with the newest reprojected frame with a weight factor of 0.2"): the
//! previous frame's accumulated values are reprojected into the current view through the same
//! footprint tests as the stereo reprojection, and blended with the new value; where every
//! neighbour was discarded the history restarts from the new value.
//!
//! | [`Blend`] | `alpha` of the new value | source |
//! |---|---|---|
//! | `Fixed(a)` | `a` (the paper: 0.2) | Mäkitalo et al. 2019, §4.1 |
//! | `RunningMean { floor }` | `max(1 / (n + 1), floor)` with `n` the reprojected history length | BMFR's `accumulate_noisy_data` (Koskela et al. 2019), floor 0.2 |
//!
//! **Invariants:** a history's `acc[i].w` is the number of frames blended into pixel `i` (the
//! footprint-weighted mean of the reprojected counts, plus one), at least 1; a discarded pixel
//! restarts at 1 with the new value only. Colour and count sit in one `Vec4` so one gather
//! reads both (each lane summed exactly as a gather of the colour or the count alone).

use std::sync::Arc;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::buffers::EyeView;
use super::footprint::{BAND_ROWS, Footprint, Kernel, Outcome, Reprojector, Tests};
use super::isa::Isa;

/// Pixels whose footprints are computed before their gathers.
const CHUNK: usize = 16;
use super::sampler::thread_ns;

/// How the new value is blended into the reprojected history (module table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Blend {
    Fixed(f32),
    RunningMean { floor: f32 },
}

impl Blend {
    /// The paper's blend: alpha 0.2.
    pub const PAPER: Blend = Blend::Fixed(0.2);

    /// The weight of the new value over a history of `n` frames.
    #[inline]
    pub fn alpha(self, n: f32) -> f32 {
        match self {
            Blend::Fixed(a) => a,
            Blend::RunningMean { floor } => (1.0 / (n + 1.0)).max(floor),
        }
    }

    /// The alpha (or floor) this blend is built on.
    pub fn base_alpha(self) -> f32 {
        match self {
            Blend::Fixed(a) | Blend::RunningMean { floor: a } => a,
        }
    }

    /// `fixed` or `running-mean`.
    pub fn name(self) -> &'static str {
        match self {
            Blend::Fixed(_) => "fixed",
            Blend::RunningMean { .. } => "running-mean",
        }
    }
}

/// A [`Blend`] prepared for a pass: [`Blend::alpha`] bit for bit, with the running mean's
/// division skipped where its result cannot exceed the floor: `fl(1 / x)` does not grow with
/// `x > 0`, so `max(fl(1 / (n + 1)), floor)` is `floor` for every `n + 1 >= from`, the
/// smallest such `x`, found once.
#[derive(Clone, Copy, Debug)]
pub struct Alpha {
    blend: Blend,
    from: f32,
}

impl Alpha {
    pub fn new(blend: Blend) -> Self {
        let from = match blend {
            Blend::Fixed(_) => f32::INFINITY,
            Blend::RunningMean { floor } => Self::floor_from(floor),
        };
        Self { blend, from }
    }

    /// The smallest `x > 0` with `fl(1 / x) <= floor` (infinity where there is none or it
    /// is not finite).
    fn floor_from(floor: f32) -> f32 {
        if floor.is_nan() || floor <= 0.0 {
            return f32::INFINITY;
        }
        let mut x = 1.0 / floor;
        if !x.is_finite() {
            return f32::INFINITY;
        }
        while 1.0 / x > floor {
            x = x.next_up();
        }
        while 1.0 / x.next_down() <= floor {
            x = x.next_down();
        }
        x
    }

    /// [`Blend::alpha`]`(n)`.
    #[inline(always)]
    pub fn alpha(&self, n: f32) -> f32 {
        match self.blend {
            Blend::Fixed(a) => a,
            Blend::RunningMean { floor } => {
                let x = n + 1.0;
                if x >= self.from {
                    floor
                } else {
                    (1.0 / x).max(floor)
                }
            }
        }
    }
}

/// The accumulated values of one eye, in the view that saw them.
#[derive(Clone, Debug)]
pub struct History {
    pub view: Arc<EyeView>,
    /// Per pixel: the accumulated colour (xyz) and the number of frames in it (w).
    pub acc: Vec<Vec4>,
}

impl History {
    /// The accumulated colour of pixel `i`.
    #[inline]
    pub fn color(&self, i: usize) -> Vec3 {
        self.acc[i].truncate()
    }
}

/// How [`accumulate`] reprojects and blends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Accumulation {
    pub kernel: Kernel,
    pub tests: Tests,
    pub blend: Blend,
    /// The values are radiance divided by the albedo factor ([`super::buffers::Texel::demodulate`]);
    /// the image multiplies it back.
    pub demodulated: bool,
}

/// One accumulated frame: the new history, its image and what became of each pixel's old one.
pub struct Accumulated {
    pub history: History,
    /// The history's colour as radiance (remodulated by the view's albedo when the values
    /// are demodulated).
    pub image: Vec<Vec3>,
    /// Per pixel: [`Outcome::Reused`] where history was blended in ([`Outcome::Outside`]
    /// everywhere on the first frame).
    pub outcomes: Vec<Outcome>,
    /// Thread CPU nanoseconds of the pass (footprints, blend and image).
    pub cpu_ns: u64,
}

/// Blends `new(i)` (the value of `view`'s pixel `i` this frame, in lanes x, y, z; w is
/// ignored) into `prev` reprojected into `view`; one pass over the pixels: each pixel's
/// footprint in the previous view, the blend and the image (footprints are kept only for the
/// current run of 16 pixels, on the stack). The blend is done in the lanes of the
/// history's `Vec4` (each colour lane does the scalar blend's operations; the count lane is
/// then set), with the running mean's alpha from [`Alpha`]. Runs in the build of
/// [`Isa::detect`].
pub fn accumulate(
    view: &Arc<EyeView>,
    new: impl Fn(usize) -> Vec4 + Sync,
    prev: Option<&History>,
    how: &Accumulation,
) -> Accumulated {
    accumulate_with(view, new, prev, how, Isa::detect())
}

/// [`accumulate`] in the build of `isa` (every build's outputs are the same bit for bit).
pub fn accumulate_with(
    view: &Arc<EyeView>,
    new: impl Fn(usize) -> Vec4 + Sync,
    prev: Option<&History>,
    how: &Accumulation,
    isa: Isa,
) -> Accumulated {
    let n = view.len();
    let band = view.width() as usize * BAND_ROWS;
    let mut acc = vec![Vec4::ZERO; n];
    let mut image = vec![Vec3::ZERO; n];
    let mut outcomes = vec![Outcome::Outside; n];
    let (kernel, blend, demod) = (how.kernel, Alpha::new(how.blend), how.demodulated);
    let rep = prev.map(|p| Reprojector::new(&p.view, kernel, how.tests));
    let ns: Vec<u64> = acc
        .par_chunks_mut(band)
        .zip(image.par_chunks_mut(band))
        .zip(outcomes.par_chunks_mut(band))
        .enumerate()
        .map(|(b, ((hist, img), out))| {
            let t0 = thread_ns();
            let base = b * band;
            isa.run(
                #[inline(always)]
                || {
                    // Per run of CHUNK pixels: the footprints first, then the gathers and blends (the
                    // independent footprints overlap instead of waiting on each pixel's blend).
                    let mut fps = [Footprint::default(); CHUNK];
                    for (r, ((hr, ir), or)) in hist
                        .chunks_mut(CHUNK)
                        .zip(img.chunks_mut(CHUNK))
                        .zip(out.chunks_mut(CHUNK))
                        .enumerate()
                    {
                        let i0 = base + r * CHUNK;
                        let fps = &mut fps[..hr.len()];
                        if let Some(rep) = &rep {
                            let texels = &view.texels[i0..i0 + fps.len()];
                            for (f, t) in fps.iter_mut().zip(texels) {
                                *f = rep.footprint(t);
                            }
                        }
                        for (k, ((hj, ij), oj)) in hr.iter_mut().zip(ir).zip(or).enumerate() {
                            let i = i0 + k;
                            let t = &view.texels[i];
                            let v = new(i);
                            let (mut c, mut cnt) = (v, 1.0);
                            if let Some(p) = prev {
                                let f = &fps[k];
                                *oj = f.outcome;
                                if f.outcome == Outcome::Reused {
                                    // Colour (xyz) and count (w) of the reprojected history.
                                    let h = f.gather(kernel, &p.acc, p.view.width());
                                    let a = blend.alpha(h.w);
                                    cnt = h.w + 1.0;
                                    c = v * a + h * (1.0 - a);
                                }
                            }
                            let c = c.with_w(cnt);
                            *hj = c;
                            *ij = t.remodulate_lanes(c, demod);
                        }
                    }
                },
            );
            thread_ns().saturating_sub(t0)
        })
        .collect();
    Accumulated {
        history: History {
            view: view.clone(),
            acc,
        },
        image,
        outcomes,
        cpu_ns: ns.iter().sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_mean_averages_then_holds_the_floor() {
        let b = Blend::RunningMean { floor: 0.2 };
        assert_eq!(b.alpha(0.0), 1.0);
        assert_eq!(b.alpha(1.0), 0.5);
        assert!((b.alpha(3.0) - 0.25).abs() < 1e-7);
        assert_eq!(b.alpha(10.0), 0.2);
        assert_eq!(Blend::PAPER.alpha(100.0), 0.2);
        // A running mean of constant-history values is the plain mean of the frames.
        let mut mean = 0.0f32;
        let mut n = 0.0f32;
        for (k, v) in [3.0f32, 5.0, 10.0, 2.0].into_iter().enumerate() {
            let a = if k == 0 { 1.0 } else { b.alpha(n) };
            mean = v * a + mean * (1.0 - a);
            n += 1.0;
        }
        assert!((mean - 5.0).abs() < 1e-6);
    }

    #[test]
    fn prepared_alpha_equals_the_blend_bit_for_bit() {
        for blend in [
            Blend::PAPER,
            Blend::RunningMean { floor: 0.2 },
            Blend::RunningMean { floor: 0.3 },
            Blend::RunningMean { floor: 1.0 },
            Blend::RunningMean { floor: 1e-3 },
        ] {
            let a = Alpha::new(blend);
            let mut ns: Vec<f32> = (0..4000).map(|k| k as f32 * 0.01).collect();
            ns.extend([f32::INFINITY, 1e30, f32::NAN, -0.5, -1.0]);
            if a.from.is_finite() {
                // Every value within 64 ulps of the threshold.
                let t = a.from - 1.0;
                let mut lo = t;
                for _ in 0..64 {
                    lo = lo.next_down();
                }
                let mut x = lo;
                for _ in 0..128 {
                    ns.push(x);
                    x = x.next_up();
                }
            }
            for n in ns {
                assert_eq!(
                    a.alpha(n).to_bits(),
                    blend.alpha(n).to_bits(),
                    "{blend:?} n = {n}"
                );
            }
        }
        assert_eq!(Alpha::new(Blend::RunningMean { floor: 0.2 }).from, 5.0);
    }
}
