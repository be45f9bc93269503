//! Scoring an image against the BVH reference render of the same camera: the ground truth every
//! technique is measured against.
//!
//! **Values:** both images go through the display transform the PNGs use (ACES filmic tone
//! curve of Narkowicz 2015 at exposure 0, then the sRGB OETF), so values lie in `[0, 1]` and
//! errors weigh as they look; PSNR with peak 1 over all three channels, SSIM as the mean of
//! the per-channel SSIMs (data range 1). The same for every method.
//!
//! **Random streams** ([`Shading`]): a shaded reference (e.g. view synthesis's colour layers) and
//! its ground truth draw from the same streams, so the comparison measures the technique, not
//! Monte Carlo noise.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_core::image::png::{ToneMapping, Tonemap, tonemap_image};
use parallax_core::metrics::{psnr_rgb, ssim_rgb};
use parallax_core::sampling::Rng;
use parallax_core::{CoreError, Image, Rgb};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel, Pinhole};
use serde::Serialize;

use crate::reference::shade::Shader;
use crate::reference::{self, RenderOptions};
use crate::tiles::for_each_pixel;

/// Which random stream a shading point draws from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Shading {
    /// The same stream (of `seed`) for every shading point: noise-free, deterministic.
    #[default]
    Fixed,
    /// The reference renderer's per-pixel streams (`Rng::for_pixel(seed, x, y, layer)`).
    PerPixel,
}

impl Shading {
    /// The stream of pixel `(x, y)`, sample / layer `k`.
    #[inline]
    pub fn rng(self, seed: u64, x: u32, y: u32, k: u32) -> Rng {
        match self {
            Shading::Fixed => Rng::for_pixel(seed, 0, 0, 0),
            Shading::PerPixel => Rng::for_pixel(seed, x, y, k),
        }
    }
}

/// The display transform of the scores (and of the PNGs).
pub const SCORE_TONEMAP: ToneMapping = ToneMapping {
    exposure: 0.0,
    tonemap: Tonemap::AcesFilmic,
};

/// PSNR (dB) and SSIM of an image against its ground truth.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Score {
    pub psnr: f64,
    pub ssim: f64,
}

/// Scores `image` against `truth` (see the module docs).
pub fn score(image: &Image<Rgb>, truth: &Image<Rgb>) -> Result<Score, CoreError> {
    let a = tonemap_image(image, &SCORE_TONEMAP);
    let b = tonemap_image(truth, &SCORE_TONEMAP);
    Ok(Score {
        psnr: psnr_rgb(&a, &b, 1.0)?,
        ssim: ssim_rgb(&a, &b, 1.0)?,
    })
}

/// The ground truth of a pinhole view: the BVH reference renderer's shading of the
/// pixel-centre rays with the random streams of `shading` ([`Shading::PerPixel`] is exactly
/// [`crate::reference::render()`] at one sample per pixel).
pub fn ground_truth(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    shading: Shading,
    seed: u64,
) -> Image<Rgb> {
    if shading == Shading::PerPixel {
        let opts = RenderOptions {
            spp: 1,
            seed,
            gbuffer: false,
        };
        let cam = Camera::Pinhole(camera.clone());
        return reference::render(scene, bvh, &cam, &opts, &|_| {}).image;
    }
    let shader = Shader::new(scene, bvh);
    let (w, h) = (camera.width, camera.height);
    let mut out = vec![Rgb::ZERO; w as usize * h as usize];
    for_each_pixel(
        w,
        h,
        &mut out,
        |x, y, c| {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            if let Some(cr) = camera.generate_ray(film, Vec2::splat(0.5), 1) {
                let mut rng = shading.rng(seed, x, y, 0);
                let mut rays = 0;
                *c = shader.radiance(cr.ray, &mut rng, &mut rays);
            }
        },
        &|_| {},
    );
    Image::from_vec(w, h, out).expect("camera size is valid")
}
