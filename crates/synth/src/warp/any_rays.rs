//! The warp for any rays (not only a pinhole's): lenslet rays of a near-eye display, lens
//! rays of depth of field; each ray answered by [`RayWarp`] as in [`super::warp_view_with`].

use parallax_core::{Ray, Rgb};
use parallax_screen::{ScreenTracer, TraceStats};
use rayon::prelude::*;

use super::WarpedView;
use super::hit::HitKind;
use super::options::WarpOptions;
use super::rays::RayWarp;
use crate::layers::Reference;

/// Warps `reference` into a `width x height` image whose pixel `(x, y)` looks along
/// `ray(x, y)` (any origin and direction; `None`: the environment colour, counted as a miss):
/// the warp of [`super::warp_view_with`] for rays that no pinhole generates (lenslet rays of
/// a near-eye display, lens rays). Rows run in parallel (rayon), each with its own stats.
pub fn warp_rays(
    tracer: &dyn ScreenTracer,
    reference: &Reference,
    width: u32,
    height: u32,
    ray: impl Fn(u32, u32) -> Option<Ray> + Sync,
    opts: &WarpOptions,
) -> Result<WarpedView, crate::SynthError> {
    parallax_core::image::check_size(width, height)?;
    let per_ray = RayWarp::new(reference, opts);
    let n = width as usize * height as usize;
    let mut image = vec![Rgb::ZERO; n];
    let mut kinds = vec![HitKind::Miss; n];
    let mut work = vec![0u32; n];
    let start = std::time::Instant::now();
    let w = width as usize;
    let stats = image
        .par_chunks_mut(w)
        .zip(kinds.par_chunks_mut(w))
        .zip(work.par_chunks_mut(w))
        .enumerate()
        .map(|(y, ((img, kind), wk))| {
            let mut total = TraceStats::default();
            for (x, ((img, kind), wk)) in img.iter_mut().zip(kind).zip(wk).enumerate() {
                let Some(r) = ray(x as u32, y as u32) else {
                    *img = reference.background;
                    continue;
                };
                let mut s = TraceStats::default();
                (*img, *kind, _) = per_ray.answer(tracer, &r, &mut s);
                let tests = s.box_tests + s.plane_tests;
                *wk = (if tests > 0 { tests } else { s.steps }).min(u32::MAX as u64) as u32;
                total += s;
            }
            total
        })
        .reduce(TraceStats::default, |a, b| a + b);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(WarpedView {
        image: parallax_core::Image::from_vec(width, height, image)?,
        kinds,
        work,
        stats,
        ms,
    })
}
