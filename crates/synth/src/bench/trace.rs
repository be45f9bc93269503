//! Trace-only timing of a view-synthesis tracer: the eye rays of the warp
//! ([`crate::warp`]: one ray per target pixel centre, row-major) generated once, then
//! traced with nothing else (no colour lookup, no layer-0 guard, no per-pixel outputs), rayon
//! over rows like the warp. `T_eye` of the warp = ray generation + tracing + the rest of the
//! shared per-pixel loop (colour resampling, the guard, stats and image writes); this pass
//! measures the first two so the rest can be read off, and it scores tracers on their own
//! work (the shared loop costs every method the same and dilutes their ratios).

use std::time::Instant;

use parallax_core::Ray;
use parallax_scene::camera::Pinhole;
use parallax_screen::{ScreenTracer, TraceStats};
use rayon::prelude::*;

use crate::warp::PixelRays;
use parallax_core::cpu_time::{ms_between, process_cpu_ns, thread_cpu_ns};

/// Times of one pass (milliseconds).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    /// Wall clock.
    pub wall_ms: f64,
    /// Sum over the rows of the CPU time of the thread that ran them (NaN without the clock).
    pub thread_cpu_ms: f64,
    /// CPU time of the whole process during the pass (includes idle rayon workers spinning).
    pub process_cpu_ms: f64,
}

impl PassTimes {
    /// Element-wise minimum (best of repeats).
    pub fn min(self, o: Self) -> Self {
        let m = |a: f64, b: f64| if a.is_nan() { b } else { a.min(b) };
        Self {
            wall_ms: m(self.wall_ms, o.wall_ms),
            thread_cpu_ms: m(self.thread_cpu_ms, o.thread_cpu_ms),
            process_cpu_ms: m(self.process_cpu_ms, o.process_cpu_ms),
        }
    }

    /// Infinite times, the identity of [`Self::min`].
    pub fn worst() -> Self {
        Self {
            wall_ms: f64::INFINITY,
            thread_cpu_ms: f64::INFINITY,
            process_cpu_ms: f64::INFINITY,
        }
    }
}

/// Runs `row(y)` for every row on rayon's threads and times it.
fn timed_rows<T: Send>(
    height: u32,
    row: impl Fn(usize) -> T + Sync + Send,
    init: impl Fn() -> T + Sync + Send,
    sum: impl Fn(T, T) -> T + Sync + Send,
) -> (T, PassTimes) {
    let p0 = process_cpu_ns();
    let start = Instant::now();
    let (out, cpu) = (0..height as usize)
        .into_par_iter()
        .map(|y| {
            let c0 = thread_cpu_ns();
            let v = row(y);
            (v, ms_between(c0, thread_cpu_ns()))
        })
        .reduce(|| (init(), 0.0), |a, b| (sum(a.0, b.0), a.1 + b.1));
    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
    let times = PassTimes {
        wall_ms,
        thread_cpu_ms: cpu,
        process_cpu_ms: ms_between(p0, process_cpu_ns()),
    };
    (out, times)
}

/// The warp's eye rays of `target` (row-major, [`PixelRays`], bit-identical to the warp's;
/// never `None` for a pinhole), and the time to generate them.
pub fn eye_rays(target: &Pinhole) -> (Vec<Option<Ray>>, PassTimes) {
    let pixel_rays = PixelRays::new(target);
    let gen_row = |y: usize| -> Vec<Option<Ray>> {
        let row = pixel_rays.row(y as u32);
        (0..target.width).map(|x| Some(row.ray(x))).collect()
    };
    // Timed without keeping the rows (the warp writes into preallocated images).
    let (_, times) = timed_rows(
        target.height,
        |y| std::hint::black_box(gen_row(y)).len(),
        || 0,
        |a, b| a + b,
    );
    let rays = (0..target.height as usize)
        .into_par_iter()
        .flat_map_iter(gen_row)
        .collect();
    (rays, times)
}

/// Traces `rays` (rows of `width`) with `tracer` and nothing else.
pub fn trace_pass(
    tracer: &dyn ScreenTracer,
    rays: &[Option<Ray>],
    width: u32,
) -> (TraceStats, PassTimes) {
    let w = width as usize;
    let height = rays.len().div_ceil(w.max(1)) as u32;
    timed_rows(
        height,
        |y| {
            let mut s = TraceStats::default();
            let end = ((y + 1) * w).min(rays.len());
            for r in rays[y * w..end].iter().flatten() {
                std::hint::black_box(tracer.trace(r, &mut s));
            }
            s
        },
        TraceStats::default,
        |a, b| a + b,
    )
}
