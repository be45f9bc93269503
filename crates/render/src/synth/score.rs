//! Scoring synthesised views against the BVH reference render of the same camera.
//!
//! **Values:** both images go through the display transform the PNGs use (ACES filmic tone
//! curve of Narkowicz 2015 at exposure 0, then the sRGB OETF), so values lie in `[0, 1]` and
//! errors weigh as they look; PSNR with peak 1 over all three channels, SSIM as the mean of
//! the per-channel SSIMs (data range 1). The same for every method.

use parallax_bvh::Bvh;
use parallax_core::image::png::{ToneMapping, Tonemap, tonemap_image};
use parallax_core::metrics::{psnr_rgb, ssim_rgb};
use parallax_core::{Image, Rgb};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, Pinhole};
use serde::Serialize;

use super::SynthError;
use crate::reference::{self, RenderOptions};

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
pub fn score(image: &Image<Rgb>, truth: &Image<Rgb>) -> Result<Score, SynthError> {
    let a = tonemap_image(image, &SCORE_TONEMAP);
    let b = tonemap_image(truth, &SCORE_TONEMAP);
    Ok(Score {
        psnr: psnr_rgb(&a, &b, 1.0)?,
        ssim: ssim_rgb(&a, &b, 1.0)?,
    })
}

/// The ground truth of a pinhole view: [`reference::render`] with `spp` samples per pixel.
pub fn ground_truth(scene: &Scene, bvh: &Bvh, camera: &Pinhole, spp: u32, seed: u64) -> Image<Rgb> {
    let opts = RenderOptions {
        spp,
        seed,
        gbuffer: false,
    };
    reference::render(scene, bvh, &Camera::Pinhole(camera.clone()), &opts, &|_| {}).image
}
