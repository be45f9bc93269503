//! The ground truth of depth of field and the pixels where layers matter.
//!
//! - [`thin_lens_truth`]: the BVH reference renderer's shading of `spp` thin-lens rays per
//!   pixel (lens samples stratified as [`super::lens_strata`], jittered; pixel-centre film
//!   position as the depth-of-field image uses), averaged: at high `spp` the converged image
//!   every method is scored against (Widmer et al. 2015 compare against the correct defocus
//!   of two layers, Fig. 9; we compare against the triangles). Shading draws from the streams
//!   of [`Shading`], so with [`Shading::Fixed`] the only noise left is the lens sampling's.
//! - [`discontinuity_mask`] and [`masked_psnr`]: the pixels within the circle of confusion of
//!   a large depth discontinuity of the reference's layer 0 (depth ratio above
//!   [`EDGE_RATIO`] between 4-neighbours, or covered next to uncovered) — where rays travel
//!   into occluded parts of the scene (§5.2, Fig. 9) — and the PSNR over them.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_core::image::png::tonemap_image;
use parallax_core::sampling::Rng;
use parallax_core::{Image, Rgb};
use parallax_render::reference::shade::Shader;
use parallax_render::score::{SCORE_TONEMAP, Shading};
use parallax_render::tiles::for_each_pixel;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, ThinLens};

use super::lens_strata;
use crate::SynthError;
use crate::layers::Reference;

/// Salt of the truth's lens-sample streams (independent of the depth-of-field image's).
const TRUTH_SALT: u64 = 0x7472_7574_685f_646f;

/// Neighbouring layer-0 depths differing by more than this ratio are a large discontinuity.
pub const EDGE_RATIO: f32 = 1.5;

/// The BVH thin-lens image of `lens` with `spp` stratified lens samples per pixel (module
/// docs).
pub fn thin_lens_truth(
    scene: &Scene,
    bvh: &Bvh,
    lens: &ThinLens,
    spp: u32,
    shading: Shading,
    seed: u64,
) -> Result<Image<Rgb>, SynthError> {
    if !(1..=super::MAX_PRIMARY * super::MAX_SECONDARY).contains(&spp) {
        return Err(SynthError::Invalid(format!(
            "ground-truth lens samples must be in 1..={}, got {spp}",
            super::MAX_PRIMARY * super::MAX_SECONDARY
        )));
    }
    let shader = Shader::new(scene, bvh);
    let (w, h) = (lens.width(), lens.height());
    let (cols, rows) = lens_strata(spp);
    let cell = Vec2::new(1.0 / cols as f32, 1.0 / rows as f32);
    let mut out = vec![Rgb::ZERO; w as usize * h as usize];
    for_each_pixel(
        w,
        h,
        &mut out,
        |x, y, c| {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let mut lens_rng = Rng::for_pixel(seed ^ TRUTH_SALT, x, y, 0);
            let mut sum = Rgb::ZERO;
            for i in 0..spp {
                let corner = Vec2::new((i % cols) as f32, (i / cols) as f32);
                let u = (corner + lens_rng.next_vec2()) * cell;
                if let Some(cr) = lens.generate_ray(film, u, 0) {
                    let mut rng = shading.rng(seed, x, y, i);
                    let mut rays = 0;
                    sum += shader.radiance(cr.ray, &mut rng, &mut rays);
                }
            }
            *c = sum / spp as f32;
        },
        &|_| {},
    );
    Ok(Image::from_vec(w, h, out)?)
}

/// Pixels of the `w x h` view (its pixel `(x, y)` is `(x + guard, y + guard)` of
/// `reference`) within `radius` pixels (max norm) of a large layer-0 depth discontinuity
/// (module docs). Row-major.
pub fn discontinuity_mask(
    reference: &Reference,
    guard: u32,
    w: u32,
    h: u32,
    radius: u32,
) -> Vec<bool> {
    let g = &reference.layers[0];
    let (rw, rh) = (g.width(), g.height());
    let depth = |x: u32, y: u32| {
        let d = g.depth[g.index(x, y)];
        if d.is_finite() && d > 0.0 {
            d
        } else {
            f32::INFINITY
        }
    };
    let jump = |a: f32, b: f32| {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        hi > lo * EDGE_RATIO
    };
    // Edge pixels of the view (both sides of a jump).
    let mut edge = vec![false; w as usize * h as usize];
    for y in 0..h {
        for x in 0..w {
            let (rx, ry) = (x + guard, y + guard);
            if rx >= rw || ry >= rh {
                continue;
            }
            let d = depth(rx, ry);
            let mut e = false;
            if rx + 1 < rw {
                e |= jump(d, depth(rx + 1, ry));
            }
            if rx > 0 {
                e |= jump(d, depth(rx - 1, ry));
            }
            if ry + 1 < rh {
                e |= jump(d, depth(rx, ry + 1));
            }
            if ry > 0 {
                e |= jump(d, depth(rx, ry - 1));
            }
            edge[(y * w + x) as usize] = e;
        }
    }
    dilate(&edge, w, h, radius)
}

/// Max-norm dilation of `mask` by `r` pixels (separable: rows, then columns).
fn dilate(mask: &[bool], w: u32, h: u32, r: u32) -> Vec<bool> {
    let (w, h, r) = (w as usize, h as usize, r as usize);
    let pass = |src: &[bool], len: usize, lines: usize, at: &dyn Fn(usize, usize) -> usize| {
        let mut dst = vec![false; src.len()];
        for l in 0..lines {
            // Distance to the last set element seen, forwards then backwards.
            let mut last: Option<usize> = None;
            for i in 0..len {
                if src[at(l, i)] {
                    last = Some(i);
                }
                if last.is_some_and(|j| i - j <= r) {
                    dst[at(l, i)] = true;
                }
            }
            let mut next: Option<usize> = None;
            for i in (0..len).rev() {
                if src[at(l, i)] {
                    next = Some(i);
                }
                if next.is_some_and(|j| j - i <= r) {
                    dst[at(l, i)] = true;
                }
            }
        }
        dst
    };
    let rows = pass(mask, w, h, &|y, x| y * w + x);
    pass(&rows, h, w, &|x, y| y * w + x)
}

/// PSNR (dB, the display values of [`parallax_render::score`]) of `image` against `truth`
/// over the pixels where `mask` is set; NaN when none is.
pub fn masked_psnr(
    image: &Image<Rgb>,
    truth: &Image<Rgb>,
    mask: &[bool],
) -> Result<f64, SynthError> {
    if (image.width(), image.height()) != (truth.width(), truth.height())
        || mask.len() != image.len()
    {
        return Err(SynthError::Invalid("masked PSNR: sizes differ".into()));
    }
    let a = tonemap_image(image, &SCORE_TONEMAP);
    let b = tonemap_image(truth, &SCORE_TONEMAP);
    let (mut se, mut n) = (0.0f64, 0u64);
    for ((p, q), &m) in a.data().iter().zip(b.data()).zip(mask) {
        if m {
            let d = (*p - *q).as_dvec3();
            se += d.length_squared();
            n += 3;
        }
    }
    if n == 0 {
        return Ok(f64::NAN);
    }
    let mse = se / n as f64;
    Ok(if mse > 0.0 {
        -10.0 * mse.log10()
    } else {
        f64::INFINITY
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dilation_is_max_norm() {
        let (w, h) = (7, 5);
        let mut m = vec![false; 35];
        m[2 * 7 + 3] = true;
        let d = dilate(&m, w, h, 1);
        let set: Vec<usize> = (0..35).filter(|&i| d[i]).collect();
        assert_eq!(set, vec![9, 10, 11, 16, 17, 18, 23, 24, 25]);
        assert_eq!(dilate(&m, w, h, 0), m);
    }
}
