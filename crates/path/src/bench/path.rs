//! `parallax bench path`: the path tracer's speed and error per tracer.
//!
//! For each tracer (built once, outside the timing): a fixed-spp render, timed in `repeats`
//! interleaved rounds (round-robin over the tracers, best round kept), then renders with time
//! budgets of 1/4, 1/2, 1 and 2 times the first tracer's best time. Every image is scored by
//! RMSE (linear RGB) against a reference of `reference_spp` samples rendered with the first
//! tracer and another seed; the reference's own noise adds `var_ref` to every `RMSE²` alike.
//! `efficiency = 1 / (RMSE² · seconds)` is the figure of merit of unbiased Monte Carlo
//! estimators (constant while the error is noise, higher is better).
//!
//! Rates: `paths_per_s` and `mrays_per_s` are per wall-clock second of the render; per bounce,
//! `trace_mrays_per_s` is closest-hit rays over the trace pass's thread time times the thread
//! count (the rate with every thread tracing), likewise `shadow_mrays_per_s`.
//!
//! | parameter | type | default (CLI) | meaning |
//! |---|---|---|---|
//! | `opts` | [`PathOptions`] | `--spp 16`, depth 16 | the timed renders' options |
//! | `reference_spp` | u32 | 256 | samples of the reference |
//! | `repeats` | u32 | 3 | interleaved timing rounds |
//! | `tracers` | `Vec<TracerKind>` | all | structures compared |

use std::time::Instant;

use parallax_core::metrics::rmse_rgb;
use parallax_core::{Image, Rgb};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use serde::Serialize;

use crate::error::{PathError, Result};
use crate::options::PathOptions;
use crate::render::{PathOutput, PathTracer};
use crate::stats::PathStats;
use crate::tracers::{BuiltTracer, TracerKind, TracerOptions, build_tracer};

/// What the bench runs (see the module table).
#[derive(Clone, Debug)]
pub struct PathBenchSetup {
    pub opts: PathOptions,
    pub reference_spp: u32,
    pub repeats: u32,
    pub tracers: Vec<TracerKind>,
}

/// One bounce of a fixed-spp render.
#[derive(Clone, Debug, Serialize)]
pub struct BounceRow {
    pub bounce: usize,
    pub rays: u64,
    pub hit_rate: f64,
    pub trace_mrays_per_s: f64,
    pub shadow_rays: u64,
    pub shadow_mrays_per_s: f64,
    pub ms_trace: f64,
    pub ms_fetch: f64,
    pub ms_shade: f64,
    pub ms_shadow: f64,
}

/// One render with a time budget.
#[derive(Clone, Debug, Serialize)]
pub struct BudgetRow {
    pub budget_s: f64,
    pub seconds: f64,
    pub spp: u32,
    pub rmse: f64,
    pub efficiency: f64,
}

/// One tracer.
#[derive(Clone, Debug, Serialize)]
pub struct PathRow {
    pub method: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub materials: String,
    pub threads: usize,
    pub repeats: u32,
    pub ms_build: f64,
    /// Best fixed-spp render, milliseconds.
    pub ms_render: f64,
    pub paths_per_s: f64,
    pub mrays_per_s: f64,
    pub rays_per_path: f64,
    pub rmse: f64,
    pub efficiency: f64,
    pub reference_spp: u32,
    pub bounces: Vec<BounceRow>,
    pub budgets: Vec<BudgetRow>,
}

fn bounce_rows(s: &PathStats, threads: usize) -> Vec<BounceRow> {
    let rate = |rays: u64, ns: u64| {
        if ns == 0 {
            0.0
        } else {
            rays as f64 * threads as f64 / ns as f64 * 1e3
        }
    };
    s.bounces
        .iter()
        .enumerate()
        .filter(|(_, b)| b.rays > 0)
        .map(|(i, b)| BounceRow {
            bounce: i,
            rays: b.rays,
            hit_rate: b.hits as f64 / b.rays as f64,
            trace_mrays_per_s: rate(b.rays, b.trace_ns),
            shadow_rays: b.shadow_rays,
            shadow_mrays_per_s: rate(b.shadow_rays, b.shadow_ns),
            ms_trace: b.trace_ns as f64 * 1e-6,
            ms_fetch: b.fetch_ns as f64 * 1e-6,
            ms_shade: b.shade_ns as f64 * 1e-6,
            ms_shadow: b.shadow_ns as f64 * 1e-6,
        })
        .collect()
}

fn score(img: &Image<Rgb>, reference: &Image<Rgb>) -> Result<f64> {
    Ok(rmse_rgb(img, reference)?)
}

/// Runs the bench on `scene` (lights already applied) through `camera`.
pub fn run(
    scene: &Scene,
    camera: &Camera,
    setup: &PathBenchSetup,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<PathRow>> {
    setup.opts.validate()?;
    if setup.tracers.is_empty() {
        return Err(PathError::Option(
            "bench path needs at least one tracer".into(),
        ));
    }
    if setup.repeats == 0 {
        return Err(PathError::Option("--repeats must be at least 1".into()));
    }
    let threads = rayon::current_num_threads();
    let built: Vec<(TracerKind, BuiltTracer)> = setup
        .tracers
        .iter()
        .map(|&k| {
            Ok((
                k,
                build_tracer(k, scene, camera, &TracerOptions::default())?,
            ))
        })
        .collect::<Result<_>>()?;
    // Reference: the first tracer, many samples, another seed.
    progress("reference");
    let reference = PathTracer::new(
        scene,
        camera,
        built[0].1.tracer.as_ref(),
        PathOptions {
            spp: setup.reference_spp,
            seed: setup.opts.seed ^ 0x5eed_5eed,
            time_budget: None,
            ..setup.opts.clone()
        },
    )?
    .render(&|_| {})
    .image;
    let fixed = PathOptions {
        time_budget: None,
        ..setup.opts.clone()
    };
    // Interleaved rounds of the fixed-spp render.
    let mut best: Vec<Option<PathOutput>> = built.iter().map(|_| None).collect();
    for round in 0..setup.repeats {
        for (i, (k, b)) in built.iter().enumerate() {
            progress(&format!("{} round {}", k.name(), round + 1));
            let pt = PathTracer::new(scene, camera, b.tracer.as_ref(), fixed.clone())?;
            let t = Instant::now();
            let mut out = pt.render(&|_| {});
            out.seconds = t.elapsed().as_secs_f64();
            if best[i].as_ref().is_none_or(|b| out.seconds < b.seconds) {
                best[i] = Some(out);
            }
        }
    }
    let base_s = best[0].as_ref().expect("one round ran").seconds;
    let mut rows = Vec::new();
    for ((k, b), out) in built.iter().zip(best) {
        let out = out.expect("one round ran");
        let rmse = score(&out.image, &reference)?;
        let mut budgets = Vec::new();
        for f in [0.25, 0.5, 1.0, 2.0] {
            progress(&format!("{} budget {f}x", k.name()));
            let budget = base_s * f;
            let o = PathTracer::new(
                scene,
                camera,
                b.tracer.as_ref(),
                PathOptions {
                    spp: crate::options::MAX_SPP,
                    time_budget: Some(budget),
                    ..setup.opts.clone()
                },
            )?
            .render(&|_| {});
            let e = score(&o.image, &reference)?;
            budgets.push(BudgetRow {
                budget_s: budget,
                seconds: o.seconds,
                spp: o.spp,
                rmse: e,
                efficiency: 1.0 / (e * e * o.seconds),
            });
        }
        let paths = out.stats.paths as f64;
        rows.push(PathRow {
            method: k.name().into(),
            scene: scene.name.clone(),
            width: camera.width(),
            height: camera.height(),
            spp: out.spp,
            max_depth: fixed.max_depth,
            materials: fixed.materials.name().into(),
            threads,
            repeats: setup.repeats,
            ms_build: b.build_ms,
            ms_render: out.seconds * 1e3,
            paths_per_s: paths / out.seconds,
            mrays_per_s: out.stats.rays() as f64 / out.seconds * 1e-6,
            rays_per_path: out.stats.rays() as f64 / paths.max(1.0),
            rmse,
            efficiency: 1.0 / (rmse * rmse * out.seconds),
            reference_spp: setup.reference_spp,
            bounces: bounce_rows(&out.stats, threads),
            budgets,
        });
    }
    Ok(rows)
}
