//! Effective samples per pixel (Mäkitalo et al. 2019, §3 and §4.1): "the spp of a purely ray
//! traced image that would effectively yield the same error as the reprojected image". The
//! error is the RMSE against a high-spp reference of the same frame; the error curve is that of
//! plain path tracing of the same frame at 1, 2, ..., N spp; "for the RMSE value obtained for
//! each frame, we find the n and n + 1 spp datasets, between whose corresponding RMSE values
//! the obtained RMSE lies, and interpolate the effective spp based on that".
//!
//! **Interpolation: linear in 1 / MSE.** For independent samples the MSE of an n-spp image is
//! `σ² / n`, so `1 / MSE` is linear in `n` and the interpolation is exact. Below one sample
//! the curve is continued to the origin (`1 / MSE = 0` at 0 spp). Beyond the curve's last
//! point the value is extrapolated along the line through the origin and that point, and
//! flagged.
//!
//! **The reference's own noise.** The reference `R` is the mean of other samples of the same
//! estimator (independent of the curve and of the measured image), so every measured MSE is
//! the true one plus the reference's noise variance `v_R` (the per-pixel variance of its mean,
//! averaged over pixels and channels). [`ErrorCurve`] stores `v_R` and subtracts it from every
//! MSE before interpolating; `v_R` against the measured MSEs is what the bench reports to show
//! that the reference is good enough.
//!
//! MSEs are over all `3 · w · h` linear RGB values, summed in a fixed order (rows, then the
//! row sums in sequence), so they do not depend on the thread count.

use glam::Vec3;
use rayon::prelude::*;

/// Mean squared error over all channel values of two images of the same size, in f64, in a
/// fixed summation order.
pub fn mse(a: &[Vec3], b: &[Vec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    if a.is_empty() {
        return 0.0;
    }
    const CHUNK: usize = 1024;
    let partial: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(x, y)| {
            x.iter()
                .zip(y)
                .map(|(p, q)| (p.as_dvec3() - q.as_dvec3()).length_squared())
                .sum()
        })
        .collect();
    partial.iter().sum::<f64>() / (3 * a.len()) as f64
}

/// The n-spp error curve of one frame and eye.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorCurve {
    /// `mse[n - 1]`: measured MSE of the n-spp image, n = 1..=N (reference noise included).
    pub mse: Vec<f64>,
    /// The reference's noise variance `v_R` (module docs).
    pub reference_noise: f64,
}

/// An effective spp and whether it lies beyond the curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffectiveSpp {
    pub spp: f64,
    /// True when the error is below the curve's last point (extrapolated).
    pub extrapolated: bool,
}

impl ErrorCurve {
    /// Largest n of the curve.
    pub fn max_spp(&self) -> u32 {
        self.mse.len() as u32
    }

    /// `1 / (MSE - v_R)`, infinite when the difference is not positive.
    fn inverse(&self, mse: f64) -> f64 {
        let m = mse - self.reference_noise;
        if m > 0.0 { 1.0 / m } else { f64::INFINITY }
    }

    /// The effective spp of an image whose measured MSE against the reference is `mse`.
    pub fn effective_spp(&self, mse: f64) -> EffectiveSpp {
        let target = self.inverse(mse);
        let mut prev = 0.0; // 1 / MSE at n = 0
        for (k, &m) in self.mse.iter().enumerate() {
            let cur = self.inverse(m);
            if cur >= target {
                let n = k as f64; // the curve point below: n spp
                let spp = if cur > prev {
                    n + (target - prev) / (cur - prev)
                } else {
                    n + 1.0
                };
                return EffectiveSpp {
                    spp,
                    extrapolated: false,
                };
            }
            prev = prev.max(cur);
        }
        let last = self.max_spp() as f64;
        EffectiveSpp {
            spp: if prev > 0.0 {
                target / prev * last
            } else {
                0.0
            },
            extrapolated: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    fn curve(sigma2: f64, n: u32, noise: f64) -> ErrorCurve {
        ErrorCurve {
            mse: (1..=n).map(|k| sigma2 / k as f64 + noise).collect(),
            reference_noise: noise,
        }
    }

    #[test]
    fn exact_curves_give_exact_counts_between_and_beyond_the_points() {
        let c = curve(0.5, 32, 0.001);
        for k in [0.25, 1.0, 1.5, 2.0, 7.3, 16.0, 31.9] {
            let e = c.effective_spp(0.5 / k + 0.001);
            assert!((e.spp - k).abs() < 1e-9 && !e.extrapolated, "{k}: {e:?}");
        }
        let e = c.effective_spp(0.5 / 50.0 + 0.001);
        assert!(e.extrapolated && (e.spp - 50.0).abs() < 1e-9, "{e:?}");
        assert!(c.effective_spp(0.0005).spp.is_infinite());
    }

    /// A synthetic "renderer": pixel truths in [0.05, 1.05) per channel, and 1-spp samples
    /// `truth · 2u` (mean the truth, relative standard deviation 58%, like the multiplicative
    /// noise of a path tracer), each sample from its own seeded stream.
    struct Synthetic {
        truth: Vec<Vec3>,
    }

    impl Synthetic {
        fn new(pixels: u32) -> Self {
            let truth = (0..pixels)
                .map(|i| {
                    let mut r = Rng::for_pixel(7, i, 0, 0);
                    Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) + Vec3::splat(0.05)
                })
                .collect();
            Self { truth }
        }

        /// The mean of samples `samples` of `stream` at every pixel.
        fn mean(&self, stream: u64, samples: std::ops::Range<u32>) -> Vec<Vec3> {
            let n = samples.len() as f32;
            self.truth
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    let mut acc = Vec3::ZERO;
                    for s in samples.clone() {
                        let mut r = Rng::for_pixel(stream, i as u32, 1, s);
                        acc += t * 2.0 * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
                    }
                    acc / n
                })
                .collect()
        }
    }

    /// The done-when test of the metric: an image averaged from k independent 1-spp samples
    /// scores k within 5% for k = 1..16, with the curve and the reference built as
    /// [`super::super::reference`] builds them (a progressive render for the curve, a
    /// finite-spp reference whose noise is estimated and subtracted).
    #[test]
    fn k_sample_means_of_synthetic_noise_score_k_within_five_percent() {
        let px = 96 * 64;
        let syn = Synthetic::new(px);
        let reference_spp = 512u32;
        let reference = syn.mean(1, 0..reference_spp);
        // The reference's noise: sample variance of the per-pixel mean, from the known model
        // estimated the way the film does it (second moment over a subset of samples).
        let second = syn.truth.iter().enumerate().map(|(i, &t)| {
            let mut m1 = Vec3::ZERO;
            let mut m2 = Vec3::ZERO;
            for s in 0..reference_spp {
                let mut r = Rng::for_pixel(1, i as u32, 1, s);
                let v = t * 2.0 * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
                m1 += v;
                m2 += v * v;
            }
            let n = reference_spp as f32;
            let var = (m2 / n - (m1 / n) * (m1 / n)) * (n / (n - 1.0));
            (var / n).as_dvec3().element_sum()
        });
        let reference_noise = second.sum::<f64>() / (3 * px) as f64;
        let curve = ErrorCurve {
            mse: (1..=32)
                .map(|n| mse(&syn.mean(2, 0..n), &reference))
                .collect(),
            reference_noise,
        };
        for k in 1..=16u32 {
            let image = syn.mean(100 + k as u64, 0..k);
            let e = curve.effective_spp(mse(&image, &reference));
            assert!(!e.extrapolated);
            assert!(
                (e.spp / k as f64 - 1.0).abs() < 0.05,
                "k = {k}: effective spp {:.3}",
                e.spp
            );
        }
    }

    #[test]
    fn mse_is_over_channels() {
        let a = vec![Vec3::ZERO; 4];
        let b = vec![Vec3::new(1.0, 0.0, 0.0); 4];
        assert_eq!(mse(&a, &b), 1.0 / 3.0);
        assert_eq!(mse(&[], &[]), 0.0);
    }
}
