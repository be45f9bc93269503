//! Warping a reference into a target pinhole view by tracing one ray per target pixel
//! (Widmer et al. 2015, §5.1): the colour of a pixel is the colour of the layer pixel its ray
//! hits; a miss takes the environment colour; an occlusion-volume crossing takes the colour of
//! the crossed layer pixel (the single-layer inpainting of §4.1, "fill both with the nearest
//! background pixels", Fig. 6e — here the crossed pixel itself, not a dilated search).
//!
//! Besides colour, every pixel records what its ray found ([`HitKind`], shown like Fig. 6d:
//! misses red, occlusion volumes blue) and its intersection-test count (box + plane tests, or
//! steps for structures without tests — Fig. 1c's heatmap). Rows run in parallel (rayon), each
//! with its own [`TraceStats`], summed at the end.

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_core::{Image, Rgb};
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_screen::{ScreenTracer, TraceResult, TraceStats};
use rayon::prelude::*;

use super::layers::Reference;

/// What a target pixel's ray found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// A captured surface of this layer.
    Hit(u8),
    /// Nothing: left the reference frustum (environment colour).
    Miss,
    /// An occlusion volume of this layer (inpainted).
    Occlusion(u8),
}

impl HitKind {
    /// The layer the answer came from (`None` for a miss).
    pub fn layer(self) -> Option<u8> {
        match self {
            HitKind::Hit(l) | HitKind::Occlusion(l) => Some(l),
            HitKind::Miss => None,
        }
    }
}

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
/// and fetches colours from `reference`.
pub fn warp_view(tracer: &dyn ScreenTracer, reference: &Reference, target: &Pinhole) -> WarpedView {
    let (w, h) = (target.width, target.height);
    let n = w as usize * h as usize;
    let mut image = vec![Vec3::ZERO; n];
    let mut kinds = vec![HitKind::Miss; n];
    let mut work = vec![0u32; n];
    let start = Instant::now();
    let stats = image
        .par_chunks_mut(w as usize)
        .zip(kinds.par_chunks_mut(w as usize))
        .zip(work.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, ((img, kind), wk))| {
            let mut total = TraceStats::default();
            for x in 0..w as usize {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let Some(cr) = target.generate_ray(film, Vec2::splat(0.5), 1) else {
                    img[x] = reference.background;
                    continue;
                };
                let mut s = TraceStats::default();
                let r = tracer.trace(&cr.ray, &mut s);
                let tests = s.box_tests + s.plane_tests;
                wk[x] = (if tests > 0 { tests } else { s.steps }).min(u32::MAX as u64) as u32;
                total += s;
                (img[x], kind[x]) = resolve(reference, r);
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

/// The colour and kind of one trace result.
#[inline]
fn resolve(reference: &Reference, r: TraceResult) -> (Rgb, HitKind) {
    let fetch = |layer: u32, p: glam::UVec2| {
        reference
            .colors
            .get(layer as usize)
            .filter(|c| p.x < c.width() && p.y < c.height())
            .map(|c| *c.get(p.x, p.y))
            .unwrap_or(reference.background)
    };
    match r {
        TraceResult::Hit { layer, pixel, .. } => (fetch(layer, pixel), HitKind::Hit(layer as u8)),
        TraceResult::Miss => (reference.background, HitKind::Miss),
        TraceResult::OcclusionVolume { layer, pixel, .. } => {
            (fetch(layer, pixel), HitKind::Occlusion(layer as u8))
        }
    }
}
