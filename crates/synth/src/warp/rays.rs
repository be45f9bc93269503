//! The warp's answer for one ray of any origin and direction ([`RayWarp`]): trace, the
//! layer-0 guard, colour resampling and the occlusion-volume fill of [`super`] (module docs),
//! without the target pinhole. [`super::warp_view_with`] runs its per-pixel loop through it;
//! the other per-pixel reprojections of Widmer et al. 2015 (§5.2 depth of field: lens rays;
//! §5.3 light fields: off-axis views and lenslet rays) call it with their own rays, so every
//! application colours a trace result the same way.
//!
//! **Invariant:** for a pinhole's pixel-centre ray, [`RayWarp::trace`] followed by
//! [`RayWarp::colour`] is exactly the warp's pass 1 and pass 2 for that pixel (same
//! operations, same order), so [`super::warp_view_with`]'s output did not change when its
//! loop moved here.

use parallax_core::{Ray, Rgb};
use parallax_screen::{DdaOptions, DdaTracer, ScreenTracer, TraceResult, TraceStats};

use super::fill::background_fill;
use super::guard::{guard_deep, nearer_neighbour_guard, silhouette_guard};
use super::hit::HitKind;
use super::options::{OcclusionFill, WarpOptions};
use super::resolve::Resolver;
use crate::layers::Reference;

/// Per-warp state of the per-ray answer: the layer-0 guard's DDA, the colour lookup and
/// the switches of [`WarpOptions`] resolved against the reference's layer count.
pub struct RayWarp<'a> {
    reference: &'a Reference,
    side_guard: bool,
    silhouette: bool,
    nearer: bool,
    fill_bg: bool,
    guard: Option<DdaTracer>,
    resolver: Resolver<'a>,
}

impl<'a> RayWarp<'a> {
    /// The per-ray answer over `reference` with `opts` (the guard's parts act only with 2+
    /// layers, [`super`] module docs).
    pub fn new(reference: &'a Reference, opts: &WarpOptions) -> Self {
        let deep = reference.layers.len() > 1;
        let guard = (opts.dda_recheck && deep)
            .then(|| {
                // Never truncated: a segment clipped to the reference image crosses at most
                // `max(W, H) + 1` pixel columns / rows along its major axis (stride 1), so
                // this bound lets every re-check march to its end. The stereo default (260,
                // tuned for atrium) gave up on 0.8% of the classroom's rays at 1600x900.
                let d = DdaOptions::default();
                let o = DdaOptions {
                    layers: 1,
                    max_steps: reference.width().max(reference.height()) + 2,
                    ..d
                };
                DdaTracer::new(&reference.cube, &reference.layers[..1], &o).ok()
            })
            .flatten();
        Self {
            reference,
            side_guard: opts.side_entry_guard && deep,
            silhouette: opts.silhouette_check && deep,
            nearer: opts.nearer_neighbour_check && deep,
            // The background fill of Fig. 6e, for every layer count.
            fill_bg: opts.fill == OcclusionFill::NearestBackground,
            guard,
            resolver: Resolver::new(reference, opts.resample),
        }
    }

    /// The reference the answers come from.
    pub fn reference(&self) -> &'a Reference {
        self.reference
    }

    /// Traces `ray` with `tracer` (built over the reference's layers) and applies the
    /// layer-0 guard (the warp's pass 1), adding the work to `stats`.
    #[inline(always)]
    pub fn trace(
        &self,
        tracer: &dyn ScreenTracer,
        ray: &Ray,
        stats: &mut TraceStats,
    ) -> TraceResult {
        let r = tracer.trace(ray, stats);
        self.guarded(ray, r, stats)
    }

    /// The layer-0 guard of [`Self::trace`] applied to `r`, the tracer's answer for `ray`
    /// (for rays traced in batches), adding the guard's work to `stats`.
    #[inline(always)]
    pub fn guarded(&self, ray: &Ray, mut r: TraceResult, stats: &mut TraceStats) -> TraceResult {
        let reference = self.reference;
        if self.side_guard || self.guard.is_some() {
            r = guard_deep(
                reference,
                self.side_guard,
                self.guard.as_ref(),
                ray,
                r,
                stats,
            );
        }
        if self.silhouette {
            r = silhouette_guard(reference, ray, r);
        }
        if self.nearer {
            r = nearer_neighbour_guard(reference, ray, r);
        }
        r
    }

    /// The colour and kind of `ray`'s answer `r` (the warp's pass 2): resampled hit colour,
    /// environment for a miss, the filled colour of an occlusion volume.
    #[inline(always)]
    pub fn colour(&self, ray: &Ray, r: TraceResult) -> (Rgb, HitKind) {
        self.colour_with(|| *ray, r)
    }

    /// [`Self::colour`] with the ray made only when the fill needs it (the warp regenerates
    /// its pixel ray there instead of keeping it).
    #[inline(always)]
    pub fn colour_with(&self, ray: impl FnOnce() -> Ray, r: TraceResult) -> (Rgb, HitKind) {
        let (mut c, kind) = self.resolver.resolve(r);
        if let (Some(env), HitKind::Miss) = (&self.reference.environment, kind) {
            return (env.lookup(ray().dir), kind);
        }
        if let (true, HitKind::Occlusion(l)) = (self.fill_bg, kind)
            && let TraceResult::OcclusionVolume { pixel, .. } = r
        {
            let ray = ray();
            if let Some(f) = background_fill(self.reference, 0, pixel, &ray)
                .or_else(|| background_fill(self.reference, l as u32, pixel, &ray))
            {
                c = f;
            }
        }
        (c, kind)
    }

    /// [`Self::trace`] then [`Self::colour`].
    #[inline(always)]
    pub fn answer(
        &self,
        tracer: &dyn ScreenTracer,
        ray: &Ray,
        stats: &mut TraceStats,
    ) -> (Rgb, HitKind, TraceResult) {
        let r = self.trace(tracer, ray, stats);
        let (c, k) = self.colour(ray, r);
        (c, k, r)
    }
}
