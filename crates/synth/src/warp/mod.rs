//! Warping a reference into a target pinhole view by tracing one ray per target pixel
//! (Widmer et al. 2015, §5.1): the colour of a pixel is the colour of the layer pixel its ray
//! hits; a miss takes the environment colour; an occlusion-volume crossing takes the colour of
//! the crossed layer pixel (the single-layer inpainting of §4.1) or, with
//! [`OcclusionFill::NearestBackground`], the nearest background pixel (Fig. 6e, below).
//!
//! **Colour resampling** ([`Resample`], default [`Resample::Bilinear`], the same for every
//! tracer): a hit lies at a sub-pixel position of the reference image, so its colour is
//! reconstructed there rather than taken from the nearest pixel centre. The hit position is
//! projected into the reference film ([`parallax_screen::UnitCube`]) and the 2x2 pixel centres
//! around it of the hit's layer are blended bilinearly, keeping only the neighbours that are
//! covered and lie on the hit pixel's surface (within [`SAME_SURFACE_PX`] pixel footprints of
//! the hit sample's tangent plane, normals within 60°), with the weights renormalised — the
//! depth-aware ("cross-bilateral") reconstruction filter of image-based rendering, e.g. Mark,
//! McMillan & Bishop 1997, "Post-Rendering 3D Warping", §4 (reconstruction), and Shade et al.
//! 1998, "Layered Depth Images", §4 (splatting with depth discontinuity handling), which do
//! not blend across depth discontinuities. Widmer et al. 2015 do not specify their colour
//! lookup; nearest is kept as [`Resample::Nearest`] for comparison. Occlusion-volume answers
//! keep the crossed pixel's colour (nearest).
//!
//! **Visible samples first** (bilinear only): a hit in layer 1 or deeper blends, instead of
//! its own layer's samples, the layer-0 samples of the 2x2 that lie on its surface when there
//! are any. Next to a contact edge (floor meeting a column, wall behind attached trim) the
//! layer-1 sample at a pixel centre lies inside or under the occluder and shades black,
//! while the eye's ray meets the visible part of the same surface in that pixel's footprint,
//! which layer 0's neighbours hold.
//!
//! **Layer-0 guard** (default on, only with 2+ layers; ours, not in Widmer et al. 2015): an
//! answer from layer 1 or deeper is re-checked against layer 0 in five switchable parts (a)-(e),
//! [`WarpOptions`]; what each does is in `warp/guard.rs`.
//!
//! **Occlusion-volume fill** ([`WarpOptions::fill`]). Fig. 6e fills single-layer misses and
//! occlusion-volume answers "with the nearest background pixels". [`OcclusionFill::Crossed`]
//! takes the colour of the pixel the tracer reports (for cascade-mode answers the pixel whose
//! plane the ray passed behind: the occluder's edge, a foreground colour).
//! [`OcclusionFill::NearestBackground`] (`background_fill`, the default; Fig. 6e shows it
//! for single-layer references, we also apply it to the occlusion-volume answers left with
//! 2 layers) walks from that pixel back along
//! the ray's screen direction in the reference (the epipolar line: the ray came from in front
//! of the background on that side of the silhouette) to the first pixel deeper than the
//! occluder edge by 1% (or uncovered: the environment), at most [`BACKGROUND_SEARCH_PX`]
//! pixels, else keeps the crossed pixel. An occlusion volume of layer 1 or deeper (the ray
//! passed behind that layer too; the per-pixel tracers min-max, Hi-Z and DDA report them) is
//! filled from layer 0's nearest background first (the visible background a single layer
//! would give), from its own layer only when layer 0 has none: hidden-layer samples next to
//! their own silhouettes are often dark contact or enclosed surfaces. Ours.
//! Misses keep the environment colour (our misses are
//! rays that never pass behind a layer: sky, or outside the reference frustum).
//!
//! **The per-pixel loop** (shared by every tracer, so its cost dilutes their speed ratios): per
//! chunk of 64 pixels of a row (`WARP_CHUNK`), pass 1 generates each pixel's ray ([`PixelRays`]:
//! the per-warp and per-row constants hoisted, no ray differentials), traces it and applies
//! the layer-0 guard; pass 2 colours the chunk's answers (`warp/resolve.rs`: flat per-layer
//! slices, no per-pixel lookups, an inline floor) and fills occlusion volumes. In pass 2 the
//! short, latency-bound colour lookups of neighbouring pixels overlap in the out-of-order
//! core instead of each waiting behind a whole trace. Output bit-identical to the one-pass
//! loop with `generate_ray` it replaced (same operations, same order).
//!
//! Besides colour, every pixel records what its ray found ([`HitKind`], shown like Fig. 6d:
//! misses red, occlusion volumes blue) and its intersection-test count (box + plane tests, or
//! steps for structures without tests — Fig. 1c's heatmap). Rows run in parallel (rayon), each
//! with its own [`TraceStats`], summed at the end.
//!
//! **Invariants:** the warp is deterministic and independent of the thread count (rows write
//! only their own pixels); every tracer sees the same pixel rays ([`PixelRays`]).
//!
//! **Parameters** ([`WarpOptions`], the same for every tracer): the colour resampling, the
//! five switchable parts of the layer-0 guard, and the occlusion-volume fill; defaults and
//! meanings in the table of [`crate::MethodOptions`].
//!
//! Measurements behind these choices: `docs/notes/synth.md`.

use std::time::Instant;

use glam::{Mat3, Vec2, Vec3};
use parallax_core::{Image, Ray, Rgb};
use parallax_scene::camera::Pinhole;
use parallax_screen::{ScreenTracer, TraceResult, TraceStats};
use rayon::prelude::*;

mod any_rays;
mod fill;
mod guard;
mod hit;
mod options;
mod rays;
mod resolve;

use crate::layers::Reference;
pub use any_rays::warp_rays;
pub use fill::BACKGROUND_SEARCH_PX;
pub use options::{OcclusionFill, WarpOptions};
pub use rays::RayWarp;

pub use hit::{HitKind, Resample, SAME_SURFACE_PX};

/// A synthesised view.
#[derive(Clone, Debug)]
pub struct WarpedView {
    pub image: Image<Rgb>,
    /// Per pixel, row-major.
    pub kinds: Vec<HitKind>,
    /// Intersection tests per pixel (0 for the mesh warp).
    pub work: Vec<u32>,
    pub stats: TraceStats,
    /// Wall-clock milliseconds of the synthesis (tracing + colour fetch).
    pub ms: f64,
}

impl WarpedView {
    /// Fraction of pixels whose answer came from layer 1 or deeper (the paper's "rays into
    /// the second layer", measured on the final answer).
    pub fn frac_deep(&self) -> f64 {
        let n = self
            .kinds
            .iter()
            .filter(|k| k.layer().is_some_and(|l| l >= 1))
            .count();
        n as f64 / self.kinds.len().max(1) as f64
    }

    /// Fractions of (hits, misses, occlusion volumes).
    pub fn kind_fractions(&self) -> (f64, f64, f64) {
        let n = self.kinds.len().max(1) as f64;
        let c = |f: fn(&HitKind) -> bool| self.kinds.iter().filter(|k| f(k)).count() as f64 / n;
        (
            c(|k| matches!(k, HitKind::Hit(_))),
            c(|k| matches!(k, HitKind::Miss)),
            c(|k| matches!(k, HitKind::Occlusion(_))),
        )
    }

    /// Fig. 6d: hits keep their colour, misses red, occlusion-volume crossings blue.
    pub fn hit_type_image(&self) -> Image<Rgb> {
        let data = self
            .image
            .data()
            .iter()
            .zip(&self.kinds)
            .map(|(c, k)| match k {
                HitKind::Hit(_) => *c,
                HitKind::Miss => Vec3::new(1.0, 0.0, 0.0),
                HitKind::Occlusion(_) => Vec3::new(0.0, 0.0, 1.0),
            })
            .collect();
        Image::from_vec(self.image.width(), self.image.height(), data).expect("same size")
    }

    /// Fig. 1c: intersection tests per ray, black = 0, white = `max` (the largest count when
    /// `None`). Returns the image and the scale used.
    pub fn heatmap(&self, max: Option<u32>) -> (Image<Rgb>, u32) {
        let m = max
            .unwrap_or_else(|| self.work.iter().copied().max().unwrap_or(0))
            .max(1);
        let data = self
            .work
            .iter()
            .map(|&w| Vec3::splat((w as f32 / m as f32).min(1.0)))
            .collect();
        let img = Image::from_vec(self.image.width(), self.image.height(), data).expect("size");
        (img, m)
    }

    /// % of rays whose traversal ran out of its step bound ([`TraceStats::truncated`]; the
    /// layer-0 guard's DDA included).
    pub fn pct_truncated(&self) -> f64 {
        100.0 * self.stats.truncated as f64 / self.stats.rays.max(1) as f64
    }

    /// Mean intersection tests (box + plane) per ray.
    pub fn tests_per_ray(&self) -> f64 {
        let s = &self.stats;
        (s.box_tests + s.plane_tests) as f64 / s.rays.max(1) as f64
    }

    /// Mean hierarchy nodes visited per ray (steps for flat structures).
    pub fn nodes_per_ray(&self) -> f64 {
        let s = &self.stats;
        let n = if s.nodes_visited > 0 {
            s.nodes_visited
        } else {
            s.steps
        };
        n as f64 / s.rays.max(1) as f64
    }
}

/// Traces every pixel-centre ray of `target` with `tracer` (built over `reference`'s layers)
/// and fetches colours from `reference` with [`Resample::default`].
pub fn warp_view(tracer: &dyn ScreenTracer, reference: &Reference, target: &Pinhole) -> WarpedView {
    warp_view_with(tracer, reference, target, &WarpOptions::default())
}

/// Pixels of a row traced before their colours are looked up (module docs, "The per-pixel
/// loop"); the answers live on the stack (64 x 32 B).
const WARP_CHUNK: usize = 64;

/// [`warp_view`] with a choice of colour resampling and crack guard.
pub fn warp_view_with(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    target: &Pinhole,
    opts: &WarpOptions,
) -> WarpedView {
    let (w, h) = (target.width, target.height);
    let n = w as usize * h as usize;
    let mut image = vec![Vec3::ZERO; n];
    let mut kinds = vec![HitKind::Miss; n];
    let mut work = vec![0u32; n];
    let rays = PixelRays::new(target);
    let per_ray = RayWarp::new(reference, opts);
    let start = Instant::now();
    let stats = image
        .par_chunks_mut(w as usize)
        .zip(kinds.par_chunks_mut(w as usize))
        .zip(work.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, ((img, kind), wk))| {
            let mut total = TraceStats::default();
            let row = rays.row(y as u32);
            let mut answers = [TraceResult::Miss; WARP_CHUNK];
            let chunks = img
                .chunks_mut(WARP_CHUNK)
                .zip(kind.chunks_mut(WARP_CHUNK))
                .zip(wk.chunks_mut(WARP_CHUNK));
            for (c, ((img, kind), wk)) in chunks.enumerate() {
                let x0 = (c * WARP_CHUNK) as u32;
                // Pass 1: trace the chunk (and guard the answers).
                for ((x, wk), answer) in (x0..).zip(wk.iter_mut()).zip(&mut answers) {
                    let mut s = TraceStats::default();
                    let r = per_ray.trace(tracer, &row.ray(x), &mut s);
                    let tests = s.box_tests + s.plane_tests;
                    *wk = (if tests > 0 { tests } else { s.steps }).min(u32::MAX as u64) as u32;
                    total += s;
                    *answer = r;
                }
                // Pass 2: colour the answers.
                for ((x, (img, kind)), &r) in (x0..).zip(img.iter_mut().zip(kind)).zip(&answers) {
                    (*img, *kind) = per_ray.colour_with(|| row.ray(x), r);
                }
            }
            total
        })
        .reduce(TraceStats::default, |a, b| a + b);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    WarpedView {
        image: Image::from_vec(w, h, image).expect("camera size is valid"),
        kinds,
        work,
        stats,
        ms,
    }
}

/// The warp's eye ray through each pixel centre of a target pinhole, with the per-warp and
/// per-row constants hoisted: bit-identical to `target.generate_ray(centre, ..).ray` (the same
/// operations in the same order), without the ray differentials and the `Option` the warp
/// does not use. Shared by the warp and `bench`'s trace-only pass (identical rays).
#[derive(Clone, Copy, Debug)]
pub struct PixelRays {
    origin: Vec3,
    basis: Mat3,
    width: f32,
    height: f32,
    tan_half_x: f32,
    tan_half_y: f32,
    shift: Vec2,
}

/// [`PixelRays`] of one row.
#[derive(Clone, Copy, Debug)]
pub struct RowRays<'a> {
    rays: &'a PixelRays,
    /// `(ndc_y + shift.y) * tan_half_y` of the row.
    dir_y: f32,
}

impl PixelRays {
    pub fn new(target: &Pinhole) -> Self {
        Self {
            origin: target.frame.position,
            basis: target.frame.basis,
            width: target.width as f32,
            height: target.height as f32,
            tan_half_x: target.tan_half_x(),
            tan_half_y: target.tan_half_y,
            shift: target.shift,
        }
    }

    /// The rays of row `y`.
    #[inline]
    pub fn row(&self, y: u32) -> RowRays<'_> {
        // Pinhole::camera_dir's y.
        let ndc_y = 1.0 - 2.0 * (y as f32 + 0.5) / self.height;
        RowRays {
            rays: self,
            dir_y: (ndc_y + self.shift.y) * self.tan_half_y,
        }
    }
}

impl RowRays<'_> {
    /// The ray through the centre of pixel `x` of the row.
    #[inline(always)]
    pub fn ray(&self, x: u32) -> Ray {
        let p = self.rays;
        // Pinhole::camera_dir, then generate_ray's normalisation and rotation.
        let ndc_x = 2.0 * (x as f32 + 0.5) / p.width - 1.0;
        let d = Vec3::new((ndc_x + p.shift.x) * p.tan_half_x, self.dir_y, -1.0);
        let len = d.length();
        Ray::new(p.origin, p.basis * (d / len))
    }
}
