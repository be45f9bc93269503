//! Light fields from colour + depth layers (Widmer et al. 2015, §5.3, "image retargeting for
//! multi-view displays"): many views of one reference (or one reference per eye) synthesised
//! by tracing every output pixel's ray through the reference's layers with any screen-space
//! tracer, coloured as the stereo warp colours its rays ([`crate::warp::RayWarp`]).
//!
//! - [`quilt`]: a Looking Glass quilt — `cols x rows` off-axis views over a horizontal view
//!   cone, tiled bottom-left to top-right, named `_qs{cols}x{rows}a{aspect}`;
//! - [`near_eye`]: near-eye light-field elemental images (Lanman & Luebke 2013), one set per
//!   eye from that eye's reference;
//! - here: the references (widened by [`crate::margin`] so the off-axis views stay inside
//!   them), the renders of both kinds, and the BVH reference of the same rays
//!   ([`bvh_view`]: the ground truth each view is scored against, and the baseline each
//!   view's time is compared with — trace-only and shaded).
//!
//! **Antialiased views** ([`render_views_aa`], `parallax lightfield --spp`): a light-field
//! display shows filtered views, so a view may be rendered with `s x s` rays per pixel — the
//! pixel centres of the same camera at `s` times the size ([`supersampled`]: same frame,
//! field of view and off-axis shift) — and box-filtered to the tile ([`box_filter`]). The
//! ground truth of such a view is the BVH render of the same `s x s` rays with the same
//! filter, so synthesis and truth differ only in how each ray is answered.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `scale` | u32 | 3 (CLI) | reference size / tile size, `1..=`[`MAX_REFERENCE_SCALE`] |
//! | `s` | u32 | 1 | rays per pixel side of an antialiased view, `1..=`[`MAX_SPP_SIDE`] (`--spp` = `s²`) |
//!
//! **Invariant:** a quilt tile is exactly the warp of the reference to that tile's view
//! camera (at `s` times its size, box-filtered; tested), and every image is bit-identical for
//! any thread count.

pub mod near_eye;
pub mod quilt;

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::{Image, Ray, Rgb};
use parallax_render::reference::shade::Shader;
use parallax_render::score::Shading;
use parallax_render::tiles::for_each_pixel;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraFrame, Pinhole};
use parallax_screen::ScreenTracer;
use rayon::prelude::*;

use crate::SynthError;
use crate::layers::{Reference, capture_reference};
use crate::margin::{margin_px, widened};
use crate::warp::{PixelRays, WarpOptions, WarpedView, warp_rays, warp_view_with};
use near_eye::NearEye;
use quilt::{QuiltViews, assemble};

/// Relative widening of a near-eye reference's field of view beyond its rays' extremes (the
/// lenslet centres lie a few mm off the eye: near surfaces shift by a few pixels).
pub const NEAR_EYE_FOV_MARGIN: f32 = 0.05;

/// The reference of a quilt: the centre view at `scale` times the tile size (the same field
/// of view), widened horizontally by the largest parallax of the outermost views over the
/// scene ([`margin_px`]; a pixel vertically), with `layers` layers. Returns it and its
/// horizontal margin in its own pixels.
///
/// A reference finer than the tiles lowers the resampling error of every view: the colour
/// of a view pixel is interpolated between reference samples, while the ground truth
/// samples the view's own pixel centre; an odd `scale` puts reference pixel centres on the
/// tiles' pixel centres (`parallax lightfield` uses 3; measured in `docs/notes/synth.md`).
#[allow(clippy::too_many_arguments)]
pub fn quilt_reference(
    scene: &Scene,
    bvh: &Bvh,
    views: &QuiltViews,
    scale: u32,
    layers: usize,
    shading: Shading,
    seed: u64,
) -> Result<(Reference, u32), SynthError> {
    if !(1..=MAX_REFERENCE_SCALE).contains(&scale) {
        return Err(SynthError::Invalid(format!(
            "the reference scale must be in 1..={MAX_REFERENCE_SCALE}, got {scale}"
        )));
    }
    let c = &views.centre;
    let centre = Pinhole::from_frame(c.frame, c.width * scale, c.height * scale, c.tan_half_y);
    let gx = margin_px(bvh, &centre, views.max_offset(), views.focus);
    let cam = widened(&centre, gx, 1);
    Ok((
        capture_reference(scene, bvh, &cam, layers, shading, seed)?,
        gx,
    ))
}

/// Largest reference scale of [`quilt_reference`].
pub const MAX_REFERENCE_SCALE: u32 = 8;

/// Every view of `views` traced through `tracer` (built over `reference`), in view order.
pub fn render_views(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    views: &QuiltViews,
    opts: &WarpOptions,
) -> Vec<WarpedView> {
    (0..views.spec.views())
        .map(|i| warp_view_with(tracer, reference, &views.camera(i), opts))
        .collect()
}

/// The quilt image of rendered views (view order).
pub fn quilt_image(views: &QuiltViews, rendered: &[WarpedView]) -> Result<Image<Rgb>, SynthError> {
    let images: Vec<Image<Rgb>> = rendered.iter().map(|v| v.image.clone()).collect();
    assemble(&views.spec, &images)
}

/// Largest rays per pixel side of an antialiased view (`--spp` up to 64).
pub const MAX_SPP_SIDE: u32 = 8;

/// The side `s` of an `s x s` grid of rays per pixel from a ray count `spp` (a square in
/// `1..=MAX_SPP_SIDE²`).
pub fn spp_side(spp: u32) -> Result<u32, SynthError> {
    let s = (spp as f64).sqrt().round() as u32;
    if s * s != spp || !(1..=MAX_SPP_SIDE).contains(&s) {
        return Err(SynthError::Invalid(format!(
            "rays per pixel must be a square s x s with s in 1..={MAX_SPP_SIDE} (1, 4, 9, ..., {}), got {spp}",
            MAX_SPP_SIDE * MAX_SPP_SIDE
        )));
    }
    Ok(s)
}

/// `camera` at `s` times its size: the same frame, field of view and off-axis shift, so its
/// pixel centres are an `s x s` grid inside each of `camera`'s pixels.
pub fn supersampled(camera: &Pinhole, s: u32) -> Pinhole {
    Pinhole {
        width: camera.width * s,
        height: camera.height * s,
        ..camera.clone()
    }
}

/// The mean of every `s x s` block of `image` (whose size is a multiple of `s`).
pub fn box_filter(image: &Image<Rgb>, s: u32) -> Result<Image<Rgb>, SynthError> {
    let (w, h) = (image.width(), image.height());
    if s == 0 || w % s != 0 || h % s != 0 {
        return Err(SynthError::Invalid(format!(
            "box filter: a {w}x{h} image is not made of {s}x{s} blocks"
        )));
    }
    let norm = 1.0 / (s * s) as f32;
    Ok(Image::from_fn(w / s, h / s, |x, y| {
        let mut sum = Rgb::ZERO;
        for j in 0..s {
            for i in 0..s {
                sum += *image.get(x * s + i, y * s + j);
            }
        }
        sum * norm
    })?)
}

/// A view rendered with `s x s` rays per pixel: the warp of the supersampled camera (its
/// answers and time) and its box-filtered image at tile size.
#[derive(Clone, Debug)]
pub struct AaView {
    pub rays: WarpedView,
    pub image: Image<Rgb>,
}

/// Every view of `views` with `s x s` rays per pixel, box-filtered (`s = 1`: the images of
/// [`render_views`]).
pub fn render_views_aa(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    views: &QuiltViews,
    opts: &WarpOptions,
    s: u32,
) -> Result<Vec<AaView>, SynthError> {
    (0..views.spec.views())
        .map(|i| {
            let cam = supersampled(&views.camera(i), s);
            let rays = warp_view_with(tracer, reference, &cam, opts);
            let image = box_filter(&rays.image, s)?;
            Ok(AaView { rays, image })
        })
        .collect()
}

/// The reference of one eye of a near-eye display: the eye's pinhole `width` pixels wide
/// covering every display pixel's ray ([`NearEye::reference_camera`]).
#[allow(clippy::too_many_arguments)]
pub fn near_eye_reference(
    scene: &Scene,
    bvh: &Bvh,
    display: &NearEye,
    eye: CameraFrame,
    width: u32,
    layers: usize,
    shading: Shading,
    seed: u64,
) -> Result<Reference, SynthError> {
    let cam = display.reference_camera(eye, width, NEAR_EYE_FOV_MARGIN)?;
    capture_reference(scene, bvh, &cam, layers, shading, seed)
}

/// The elemental image set of one eye at `eye`: every display pixel's ray traced through
/// `tracer` (built over that eye's `reference`).
pub fn render_elemental(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    display: &NearEye,
    eye: &CameraFrame,
    opts: &WarpOptions,
) -> Result<WarpedView, SynthError> {
    display.validate()?;
    warp_rays(
        tracer,
        reference,
        display.display_w,
        display.display_h,
        |x, y| Some(display.ray(eye, x, y)),
        opts,
    )
}

/// The BVH reference of a view whose pixel `(x, y)` looks along `ray(x, y)`.
#[derive(Clone, Debug)]
pub struct BvhView {
    /// The reference renderer's shading of every ray (the ground truth).
    pub image: Image<Rgb>,
    /// Milliseconds of the shaded render (closest hit + shading with shadow rays).
    pub ms_render: f64,
    /// Milliseconds of tracing the rays alone (closest hit, nothing else): the visibility
    /// the layers replace.
    pub ms_trace: f64,
}

/// [`BvhView`] of `ray` over a `width x height` image, shading streams of `shading`
/// (`Shading::PerPixel` is the reference renderer's stream of the pixel, sample 0): for a
/// pinhole's pixel-centre rays the image is `parallax_render::score::ground_truth`'s.
pub fn bvh_view(
    scene: &Scene,
    bvh: &Bvh,
    width: u32,
    height: u32,
    ray: impl Fn(u32, u32) -> Option<Ray> + Sync,
    shading: Shading,
    seed: u64,
) -> Result<BvhView, SynthError> {
    parallax_core::image::check_size(width, height)?;
    let t = Instant::now();
    let hits: u64 = (0..height)
        .into_par_iter()
        .map(|y| {
            (0..width)
                .filter_map(|x| ray(x, y))
                .filter(|r| bvh.closest_hit(r).is_some())
                .count() as u64
        })
        .sum();
    std::hint::black_box(hits);
    let ms_trace = t.elapsed().as_secs_f64() * 1e3;
    let shader = Shader::new(scene, bvh);
    let mut out = vec![scene.environment; width as usize * height as usize];
    let t = Instant::now();
    for_each_pixel(
        width,
        height,
        &mut out,
        |x, y, c| {
            if let Some(r) = ray(x, y) {
                let mut rng = shading.rng(seed, x, y, 0);
                let mut rays = 0;
                *c = shader.radiance(r, &mut rng, &mut rays);
            }
        },
        &|_| {},
    );
    let ms_render = t.elapsed().as_secs_f64() * 1e3;
    Ok(BvhView {
        image: Image::from_vec(width, height, out)?,
        ms_render,
        ms_trace,
    })
}

/// [`bvh_pinhole`] with `s x s` rays per pixel, box-filtered ([`render_views_aa`]'s truth);
/// the times are those of all the rays.
pub fn bvh_pinhole_aa(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    s: u32,
    shading: Shading,
    seed: u64,
) -> Result<BvhView, SynthError> {
    let b = bvh_pinhole(scene, bvh, &supersampled(camera, s), shading, seed)?;
    Ok(BvhView {
        image: box_filter(&b.image, s)?,
        ..b
    })
}

/// [`bvh_view`] of a pinhole's pixel-centre rays.
pub fn bvh_pinhole(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    shading: Shading,
    seed: u64,
) -> Result<BvhView, SynthError> {
    let rays = PixelRays::new(camera);
    bvh_view(
        scene,
        bvh,
        camera.width,
        camera.height,
        |x, y| Some(rays.row(y).ray(x)),
        shading,
        seed,
    )
}
