//! Image metrics: MSE / RMSE, PSNR and SSIM.
//!
//! **Values:** every metric works on the numbers it is given. Pass linear images to measure
//! linear error (the default in parallax's tests), or display values from
//! [`crate::image::png::tonemap_image`] to measure what a PNG shows.
//!
//! **RGB:** the `_rgb` variants treat the three channels as separate samples: MSE / PSNR
//! over all `3 · w · h` values, SSIM as the mean of the three per-channel SSIMs — the same
//! as scikit-image with `channel_axis=-1`. Use [`luminance`] first for a luma-only score.
//!
//! **SSIM** follows Wang, Bovik, Sheikh & Simoncelli 2004, "Image quality assessment: from
//! error visibility to structural similarity" (§III-B/C) with the Gaussian-weighted variant
//! of their implementation, matched to `skimage.metrics.structural_similarity(...,
//! gaussian_weights=True, sigma=1.5, use_sample_covariance=False)`: an 11-tap separable
//! Gaussian (σ = 1.5, truncated at 3.5σ, radius 5), population (not sample) covariances,
//! `C1 = (K1 L)²`, `C2 = (K2 L)²` with `K1 = 0.01`, `K2 = 0.03`, `L` = data range. Borders
//! use mirror reflection (`d c b a | a b c d`, SciPy's `reflect`), and the mean skips a
//! border of `radius` pixels on each side, as scikit-image does — so the mean only sees
//! windows that lie fully inside the image. **Small images:** along an axis with at most
//! `2 · radius` pixels (where scikit-image refuses to run) nothing is skipped and the
//! mirrored windows are averaged instead.

use glam::Vec3;
use rayon::prelude::*;

use crate::image::{Image, Rgb};
use crate::{CoreError, Result};

fn same_size<A, B>(a: &Image<A>, b: &Image<B>) -> Result<()> {
    if a.width() != b.width() || a.height() != b.height() {
        return Err(CoreError::SizeMismatch {
            a_width: a.width(),
            a_height: a.height(),
            b_width: b.width(),
            b_height: b.height(),
        });
    }
    Ok(())
}

/// Mean squared error over all pixels (f64 accumulation).
pub fn mse(a: &Image<f32>, b: &Image<f32>) -> Result<f64> {
    same_size(a, b)?;
    let sum: f64 = a
        .data()
        .par_iter()
        .zip(b.data())
        .map(|(&x, &y)| (x as f64 - y as f64).powi(2))
        .sum();
    Ok(sum / a.len() as f64)
}

/// Root mean squared error.
pub fn rmse(a: &Image<f32>, b: &Image<f32>) -> Result<f64> {
    mse(a, b).map(f64::sqrt)
}

/// PSNR in dB: `10 log10(peak² / MSE)`; `+inf` for identical images. `peak` is the value
/// range (1.0 for images in `[0, 1]`).
pub fn psnr(a: &Image<f32>, b: &Image<f32>, peak: f64) -> Result<f64> {
    mse(a, b).map(|m| psnr_from_mse(m, peak))
}

fn psnr_from_mse(mse: f64, peak: f64) -> f64 {
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (peak * peak / mse).log10()
    }
}

/// MSE over all channel values of two RGB images.
pub fn mse_rgb(a: &Image<Rgb>, b: &Image<Rgb>) -> Result<f64> {
    same_size(a, b)?;
    let sum: f64 = a
        .data()
        .par_iter()
        .zip(b.data())
        .map(|(x, y)| (x.as_dvec3() - y.as_dvec3()).length_squared())
        .sum();
    Ok(sum / (3 * a.len()) as f64)
}

/// RMSE over all channel values.
pub fn rmse_rgb(a: &Image<Rgb>, b: &Image<Rgb>) -> Result<f64> {
    mse_rgb(a, b).map(f64::sqrt)
}

/// PSNR over all channel values (`peak` as in [`psnr`]).
pub fn psnr_rgb(a: &Image<Rgb>, b: &Image<Rgb>, peak: f64) -> Result<f64> {
    mse_rgb(a, b).map(|m| psnr_from_mse(m, peak))
}

/// Rec. 709 / sRGB-primaries relative luminance `0.2126 R + 0.7152 G + 0.0722 B`.
pub fn luminance(img: &Image<Rgb>) -> Image<f32> {
    const W: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);
    img.map(|c| c.dot(W))
}

/// SSIM parameters; [`SsimParams::new`] gives the standard ones for a data range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SsimParams {
    /// Dynamic range `L` of the values (1.0 for `[0, 1]` images).
    pub data_range: f64,
    pub k1: f64,
    pub k2: f64,
    /// Gaussian standard deviation in pixels.
    pub sigma: f64,
    /// Window radius in pixels (window side `2 r + 1`).
    pub radius: usize,
}

impl SsimParams {
    /// Wang et al.'s constants: σ = 1.5, radius 5 (11 x 11), K1 = 0.01, K2 = 0.03.
    pub fn new(data_range: f64) -> Self {
        Self {
            data_range,
            k1: 0.01,
            k2: 0.03,
            sigma: 1.5,
            radius: 5,
        }
    }

    /// Normalised 1-D Gaussian taps `exp(-x² / 2σ²)`, `x = -r..=r`.
    fn kernel(&self) -> Vec<f64> {
        let r = self.radius as i64;
        let mut k: Vec<f64> = (-r..=r)
            .map(|x| (-0.5 * (x * x) as f64 / (self.sigma * self.sigma)).exp())
            .collect();
        let sum: f64 = k.iter().sum();
        k.iter_mut().for_each(|v| *v /= sum);
        k
    }
}

/// Mirror index for SciPy's `reflect` mode (`d c b a | a b c d | d c b a`), any offset.
#[inline]
fn reflect(i: i64, n: i64) -> usize {
    let period = 2 * n;
    let m = i.rem_euclid(period);
    (if m >= n { period - 1 - m } else { m }) as usize
}

/// Window moments per pixel: `[μa, μb, E[a²], E[b²], E[ab]]`.
type Moments = [f64; 5];

/// The SSIM map (same size as the inputs; border windows mirror the image).
pub fn ssim_map(a: &Image<f32>, b: &Image<f32>, p: &SsimParams) -> Result<Image<f32>> {
    same_size(a, b)?;
    let (w, h) = (a.width() as usize, a.height() as usize);
    let k = p.kernel();
    let r = p.radius as i64;
    let (ad, bd) = (a.data(), b.data());

    // Horizontal pass of the five products (separable Gaussian).
    let mut horiz: Vec<Moments> = vec![[0.0; 5]; w * h];
    horiz.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let base = y * w;
        for (x, out) in row.iter_mut().enumerate() {
            let mut m = [0.0; 5];
            for (t, &kt) in k.iter().enumerate() {
                let xi = reflect(x as i64 + t as i64 - r, w as i64);
                let (va, vb) = (ad[base + xi] as f64, bd[base + xi] as f64);
                m[0] += kt * va;
                m[1] += kt * vb;
                m[2] += kt * va * va;
                m[3] += kt * vb * vb;
                m[4] += kt * va * vb;
            }
            *out = m;
        }
    });

    // Vertical pass, then the SSIM formula (Wang et al. 2004, eq. 13).
    let c1 = (p.k1 * p.data_range).powi(2);
    let c2 = (p.k2 * p.data_range).powi(2);
    let mut out = Image::new(a.width(), a.height(), 0.0f32)?;
    out.data_mut()
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let mut m = [0.0; 5];
                for (t, &kt) in k.iter().enumerate() {
                    let yi = reflect(y as i64 + t as i64 - r, h as i64);
                    let s = &horiz[yi * w + x];
                    for c in 0..5 {
                        m[c] += kt * s[c];
                    }
                }
                let [ua, ub, uaa, ubb, uab] = m;
                let (va, vb, vab) = (uaa - ua * ua, ubb - ub * ub, uab - ua * ub);
                let num = (2.0 * ua * ub + c1) * (2.0 * vab + c2);
                let den = (ua * ua + ub * ub + c1) * (va + vb + c2);
                *o = (num / den) as f32;
            }
        });
    Ok(out)
}

/// Mean SSIM with explicit parameters (border handling: see the module docs).
pub fn ssim_with(a: &Image<f32>, b: &Image<f32>, p: &SsimParams) -> Result<f64> {
    let map = ssim_map(a, b, p)?;
    let (w, h) = (map.width() as usize, map.height() as usize);
    let crop = |n: usize| {
        if n > 2 * p.radius {
            p.radius..n - p.radius
        } else {
            0..n
        }
    };
    let (xs, ys) = (crop(w), crop(h));
    let count = (xs.len() * ys.len()) as f64;
    let sum: f64 = ys
        .flat_map(|y| map.data()[y * w + xs.start..y * w + xs.end].iter())
        .map(|&v| v as f64)
        .sum();
    Ok(sum / count)
}

/// Mean SSIM with the standard parameters for values spanning `data_range`.
pub fn ssim(a: &Image<f32>, b: &Image<f32>, data_range: f64) -> Result<f64> {
    ssim_with(a, b, &SsimParams::new(data_range))
}

/// Mean of the per-channel SSIMs of two RGB images.
pub fn ssim_rgb(a: &Image<Rgb>, b: &Image<Rgb>, data_range: f64) -> Result<f64> {
    same_size(a, b)?;
    let p = SsimParams::new(data_range);
    let mut total = 0.0;
    for c in 0..3 {
        let ca = a.map(|v| v[c]);
        let cb = b.map(|v| v[c]);
        total += ssim_with(&ca, &cb, &p)?;
    }
    Ok(total / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The slow twin: a direct 2-D Gaussian window per pixel with the same mirroring.
    fn ssim_map_direct(a: &Image<f32>, b: &Image<f32>, p: &SsimParams) -> Vec<f64> {
        let (w, h) = (a.width() as i64, a.height() as i64);
        let k = p.kernel();
        let r = p.radius as i64;
        let c1 = (p.k1 * p.data_range).powi(2);
        let c2 = (p.k2 * p.data_range).powi(2);
        let mut out = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let mut m = [0.0f64; 5];
                for dy in -r..=r {
                    for dx in -r..=r {
                        let wt = k[(dy + r) as usize] * k[(dx + r) as usize];
                        let (xi, yi) = (reflect(x + dx, w) as u32, reflect(y + dy, h) as u32);
                        let (va, vb) = (*a.get(xi, yi) as f64, *b.get(xi, yi) as f64);
                        let v = [va, vb, va * va, vb * vb, va * vb];
                        for c in 0..5 {
                            m[c] += wt * v[c];
                        }
                    }
                }
                let [ua, ub, uaa, ubb, uab] = m;
                let num = (2.0 * ua * ub + c1) * (2.0 * (uab - ua * ub) + c2);
                let den = (ua * ua + ub * ub + c1) * (uaa - ua * ua + ubb - ub * ub + c2);
                out.push(num / den);
            }
        }
        out
    }

    fn pattern(w: u32, h: u32, s: u32) -> Image<f32> {
        Image::from_fn(w, h, |x, y| {
            ((x * 37 + y * 91 + s * x * y) % 101) as f32 / 100.0
        })
        .unwrap()
    }

    #[test]
    fn separable_ssim_equals_direct_window() {
        // 13 x 4 exercises mirroring past both ends (4 < radius) and the small-image path.
        for (w, h) in [(13, 9), (13, 4), (3, 2)] {
            let (a, b) = (pattern(w, h, 1), pattern(w, h, 5));
            let p = SsimParams::new(1.0);
            let fast = ssim_map(&a, &b, &p).unwrap();
            let slow = ssim_map_direct(&a, &b, &p);
            for (f, s) in fast.data().iter().zip(&slow) {
                assert!((*f as f64 - s).abs() < 1e-6, "{w}x{h}: {f} vs {s}");
            }
            // Small axes average the whole map.
            if w <= 10 || h <= 10 {
                let mean_x = |x0: usize, x1: usize, y0: usize, y1: usize| {
                    let mut acc = 0.0;
                    for y in y0..y1 {
                        for x in x0..x1 {
                            acc += slow[y * w as usize + x];
                        }
                    }
                    acc / ((x1 - x0) * (y1 - y0)) as f64
                };
                let (w, h) = (w as usize, h as usize);
                let xs = if w > 10 { (5, w - 5) } else { (0, w) };
                let ys = if h > 10 { (5, h - 5) } else { (0, h) };
                let expect = mean_x(xs.0, xs.1, ys.0, ys.1);
                assert!((ssim_with(&a, &b, &p).unwrap() - expect).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn reflect_matches_scipy_mode() {
        let n = 4;
        let got: Vec<usize> = (-6..10).map(|i| reflect(i, n)).collect();
        // scipy 'reflect' of [0 1 2 3]: ... 1 0 | 0 1 2 3 | 3 2 ...
        assert_eq!(got, vec![2, 3, 3, 2, 1, 0, 0, 1, 2, 3, 3, 2, 1, 0, 0, 1]);
    }

    #[test]
    fn identical_images_are_perfect_and_sizes_must_match() {
        let a = pattern(16, 12, 3);
        assert!((ssim(&a, &a, 1.0).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(psnr(&a, &a, 1.0).unwrap(), f64::INFINITY);
        assert_eq!(rmse(&a, &a).unwrap(), 0.0);
        let b = pattern(16, 11, 3);
        assert!(matches!(
            ssim(&a, &b, 1.0),
            Err(CoreError::SizeMismatch { .. })
        ));
        assert!(matches!(
            psnr(&a, &b, 1.0),
            Err(CoreError::SizeMismatch { .. })
        ));
    }

    #[test]
    fn rmse_and_psnr_of_a_constant_offset() {
        let a = Image::new(8, 8, 0.5f32).unwrap();
        let b = Image::new(8, 8, 0.6f32).unwrap();
        assert!((rmse(&a, &b).unwrap() - 0.1).abs() < 1e-6);
        assert!((psnr(&a, &b, 1.0).unwrap() - 20.0).abs() < 1e-4);
        assert!((psnr(&a, &b, 2.0).unwrap() - (20.0 + 20.0 * 2f64.log10())).abs() < 1e-4);
        let ca = a.map(|&v| Rgb::splat(v));
        let cb = b.map(|&v| Rgb::new(v, 0.5, 0.5));
        // One channel of three differs by 0.1: MSE = 0.01 / 3.
        assert!((mse_rgb(&ca, &cb).unwrap() - 0.01 / 3.0).abs() < 1e-8);
    }
}
