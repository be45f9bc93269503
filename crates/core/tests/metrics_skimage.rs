//! PSNR and SSIM against an independent implementation.
//!
//! The constants below were computed with scikit-image 0.26.0 (numpy 2.4.6, scipy 1.17.1)
//! on the same images, built in float32 from the integer formulas below and cast to float64:
//!
//! ```python
//! from skimage.metrics import structural_similarity, peak_signal_noise_ratio
//! structural_similarity(p, q, gaussian_weights=True, sigma=1.5,
//!                       use_sample_covariance=False, data_range=1.0)
//! # RGB: the same call with channel_axis=-1 on (H, W, 3) arrays
//! peak_signal_noise_ratio(p, q, data_range=1.0)   # and data_range=2.0 once
//! ```

use parallax_core::Image;
use parallax_core::glam::Vec3;
use parallax_core::metrics::{luminance, psnr, psnr_rgb, ssim, ssim_rgb};

const W: u32 = 32;
const H: u32 = 24;

fn img(f: impl Fn(i64, i64) -> (i64, i64)) -> Image<f32> {
    Image::from_fn(W, H, |x, y| {
        let (k, d) = f(x as i64, y as i64);
        k as f32 / d as f32
    })
    .unwrap()
}

fn ka(x: i64, y: i64) -> i64 {
    (7 * x * x + 13 * y + 3 * x * y) % 256
}

fn images() -> [Image<f32>; 5] {
    let a = img(|x, y| (ka(x, y), 255));
    let b = img(|x, y| ((ka(x, y) + (5 * x + 11 * y) % 9 - 4).clamp(0, 255), 255));
    let e = img(|x, y| ((ka(x, y) + (5 * x + 11 * y) % 81 - 40).clamp(0, 255), 255));
    let c = img(|x, y| (8 * x + 3 * y, 320));
    let d = img(|x, y| (8 * x + 3 * y + 16 * ((x / 4 + y / 4) % 2), 320));
    [a, b, c, d, e]
}

#[test]
fn ssim_and_psnr_match_scikit_image() {
    let [a, b, c, d, e] = images();
    // (pair, skimage SSIM, skimage PSNR with data_range=1.0)
    let cases = [
        ("ab", &a, &b, 0.9993879900253413, 39.93347961879124),
        ("cd", &c, &d, 0.8707474945551683, 29.03089991912909),
        ("ac", &a, &c, 0.010821116014177342, 8.677322265036878),
        ("ae", &a, &e, 0.9559179423690007, 21.124442342285292),
    ];
    for (name, p, q, want_ssim, want_psnr) in cases {
        let s = ssim(p, q, 1.0).unwrap();
        let r = psnr(p, q, 1.0).unwrap();
        assert!(
            (s - want_ssim).abs() < 1e-7,
            "{name}: ssim {s} vs skimage {want_ssim}"
        );
        assert!(
            (r - want_psnr).abs() < 1e-4,
            "{name}: psnr {r} vs skimage {want_psnr}"
        );
    }
    let r2 = psnr(&a, &b, 2.0).unwrap();
    assert!((r2 - 45.954079532070864).abs() < 1e-4, "psnr peak 2: {r2}");
}

#[test]
fn rgb_metrics_match_scikit_image() {
    let [a, b, c, d, _] = images();
    let rgb = |r: &Image<f32>, g: &Image<f32>, bl: &Image<f32>| {
        Image::from_fn(W, H, |x, y| {
            Vec3::new(*r.get(x, y), *g.get(x, y), *bl.get(x, y))
        })
        .unwrap()
    };
    let (p, q) = (rgb(&a, &c, &d), rgb(&b, &d, &c));
    let s = ssim_rgb(&p, &q, 1.0).unwrap();
    assert!((s - 0.9136276597118926).abs() < 1e-7, "rgb ssim {s}");
    let r = psnr_rgb(&p, &q, 1.0).unwrap();
    assert!((r - 30.618901709169254).abs() < 1e-4, "rgb psnr {r}");
    // Luminance SSIM is a different (documented) score, still high for similar images.
    let l = ssim(&luminance(&p), &luminance(&q), 1.0).unwrap();
    assert!(l > 0.5 && (l - s).abs() > 1e-3, "luminance ssim {l}");
}
