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
//! **Invariants:** a history's `count[i]` is the number of frames blended into pixel `i` (the
//! footprint-weighted mean of the reprojected counts, plus one), at least 1; a discarded pixel
//! restarts at 1 with the new value only.

use std::sync::Arc;

use glam::Vec3;
use rayon::prelude::*;

use super::buffers::EyeView;
use super::footprint::{BAND_ROWS, Footprint, Kernel, Outcome, Tests, footprints};
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

/// The accumulated values of one eye, in the view that saw them.
#[derive(Clone, Debug)]
pub struct History {
    pub view: Arc<EyeView>,
    pub color: Vec<Vec3>,
    pub count: Vec<f32>,
}

impl History {
    /// A history that starts now: every pixel holds `color`, one frame.
    pub fn start(view: Arc<EyeView>, color: Vec<Vec3>) -> Self {
        let n = color.len();
        Self {
            view,
            color,
            count: vec![1.0; n],
        }
    }
}

/// One accumulated frame: the new history and what became of each pixel's old one.
pub struct Accumulated {
    pub history: History,
    /// Per pixel: [`Outcome::Reused`] where history was blended in ([`Outcome::Outside`]
    /// everywhere on the first frame).
    pub footprints: Vec<Footprint>,
    /// Thread CPU nanoseconds of the footprints and the blend.
    pub cpu_ns: u64,
}

/// Blends `new` (the values of `view`'s pixels this frame) into `prev` reprojected into `view`.
pub fn accumulate(
    view: &Arc<EyeView>,
    new: &[Vec3],
    prev: Option<&History>,
    kernel: Kernel,
    tests: Tests,
    blend: Blend,
) -> Accumulated {
    assert_eq!(new.len(), view.len());
    let Some(prev) = prev else {
        return Accumulated {
            history: History::start(view.clone(), new.to_vec()),
            footprints: vec![
                Footprint {
                    outcome: Outcome::Outside,
                    ..Footprint::default()
                };
                view.len()
            ],
            cpu_ns: 0,
        };
    };
    let mut fps = Vec::new();
    let mut cpu_ns = footprints(view, &prev.view, kernel, tests, &mut fps);
    let w = view.width() as usize;
    let pw = prev.view.width();
    let mut color = vec![Vec3::ZERO; new.len()];
    let mut count = vec![1.0f32; new.len()];
    let ns: Vec<u64> = color
        .par_chunks_mut(w * BAND_ROWS)
        .zip(count.par_chunks_mut(w * BAND_ROWS))
        .zip(
            fps.par_chunks(w * BAND_ROWS)
                .zip(new.par_chunks(w * BAND_ROWS)),
        )
        .map(|((c, n), (f, v))| {
            let t0 = thread_ns();
            for i in 0..c.len() {
                if f[i].outcome == Outcome::Reused {
                    let h = f[i].gather(kernel, &prev.color, pw);
                    let hn = f[i].gather(kernel, &prev.count, pw);
                    let a = blend.alpha(hn);
                    c[i] = v[i] * a + h * (1.0 - a);
                    n[i] = hn + 1.0;
                } else {
                    c[i] = v[i];
                }
            }
            thread_ns().saturating_sub(t0)
        })
        .collect();
    cpu_ns += ns.iter().sum::<u64>();
    Accumulated {
        history: History {
            view: view.clone(),
            color,
            count,
        },
        footprints: fps,
        cpu_ns,
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
}
