//! `parallax bench warp`: the stereo-warping comparison of Widmer et al. 2015, Table 2, on any
//! scene and view. A cyclopean reference with `N` layers is captured and shaded once per `N`
//! (`T_ref` = capture + shade + the method's structure build), every method warps it to both
//! eyes (`T_eye` = mean per eye, `T_total = T_ref + 2 T_eye`), and both eyes are scored
//! against the BVH reference render of the eye cameras ([`parallax_render::score`](mod@parallax_render::score)).
//!
//! The mesh warp uses layer 0 only, so it runs once, with `N = 1`. Methods not available in
//! this build give a row carrying the error instead of numbers.
//!
//! **Trace-only throughput.** `mrays_per_s` = eye rays / `T_eye` counts the whole warp loop
//! (ray generation, the tracer, depth-aware colour resampling, the layer-0 guard), whose
//! shared part costs every method the same. Each tracer row also runs [`super::trace`]'s
//! trace-only pass over the same eye rays (`trace_mrays_per_s`, wall clock, same threads as
//! the warp; `trace_cpu_mrays_per_s`, per CPU-second of the tracing threads, robust on a
//! loaded machine) and times ray generation alone, so `T_eye` splits into ray generation,
//! tracing and the rest of the loop (`ms_raygen`, `ms_trace`, `ms_view - ms_raygen -
//! ms_trace`). Every time is the best of `repeats` rounds per eye, averaged over both eyes.
//!
//! **Interleaved rounds** ([`measure_interleaved`]). All methods of one layer count are built
//! first; then each of the `repeats` rounds runs every method once (the whole warp of both
//! eyes, then ray generation, then the trace-only pass of both eyes), round-robin, and every
//! time column keeps per method the best of the rounds: the standard way to compare on a
//! shared machine (a disturbance then hits every method alike; `docs/notes/synth.md`). The
//! eye rays are generated once per eye and traced by every tracer (identical rays). With
//! `--quiet` off, the CLI prints the quad-tree's ratios to the other methods.
//!
//! **Cube near plane** ([`MethodOptions::cube_near`], recorded per row): where every ray
//! starts. **DDA max steps** can be swept in one run ([`run`]'s `dda_steps`, one `dda` row
//! per value); [`dda_minimal_steps`] picks the smallest artifact-free value as Widmer et al.
//! 2015 (§5.1) did.

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::{Image, Ray, Rgb};
use parallax_scene::camera::Pinhole;
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{CubeNear, ScreenTracer};
use serde::Serialize;

use super::trace::{PassTimes, eye_rays, trace_pass};
use super::{mesh_layers, method_entries};
use crate::SynthError;
use crate::layers::check_layers;
use crate::layers::{Reference, ReferenceTimes, capture_reference};
use crate::method::{Method, MethodOptions, Synthesizer, cube_near_name};
use crate::stereo::{StereoViews, stereo_eyes};
use crate::warp::WarpedView;
use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_render::score::Shading;
use parallax_render::score::{Score, ground_truth, score};

/// The view and settings of a stereo benchmark.
#[derive(Clone, Debug)]
pub struct StereoSetup {
    pub desc: CameraDesc,
    pub width: u32,
    pub height: u32,
    pub ipd: f32,
    pub shading: Shading,
    pub seed: u64,
    /// Score against the BVH eye views (costs two reference renders).
    pub score: bool,
    /// Timed runs of each eye's warp and trace-only pass (the best is kept), >= 1.
    pub repeats: u32,
}

/// One row of Table 2.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WarpRow {
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// The unit cube's near-plane setting (`fitted` or `camera <m> m`) and the resulting
    /// near / far view depths of the cube (metres).
    pub cube_near: String,
    pub near_m: f32,
    pub far_m: f32,
    /// The DDA's max steps (DDA rows only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dda_max_steps: Option<u32>,
    /// Timed runs per eye (best kept).
    pub repeats: u32,
    /// `T_ref`: capture + shade + build.
    pub ms_ref: f64,
    pub ms_capture: f64,
    pub ms_shade: f64,
    pub ms_build: f64,
    /// `T_eye`: mean per eye.
    pub ms_view: f64,
    /// `T_ref + 2 T_eye`.
    pub ms_total: f64,
    /// CPU time of the process per eye during the warp (all threads).
    pub ms_view_cpu: f64,
    /// Eye rays per second of the whole warp loop, `rays / T_eye` (0 for the mesh warp).
    pub mrays_per_s: f64,
    /// Trace-only pass per eye (module docs): wall ms, CPU ms of the tracing threads, CPU
    /// ms of the process.
    pub ms_trace: f64,
    pub ms_trace_cpu: f64,
    pub ms_trace_process_cpu: f64,
    /// Generating the eye rays alone, per eye: wall ms and CPU ms of the process.
    pub ms_raygen: f64,
    pub ms_raygen_process_cpu: f64,
    /// Eye rays per wall second of the trace-only pass.
    pub trace_mrays_per_s: f64,
    /// Eye rays per CPU second of the tracing threads (one core's throughput).
    pub trace_cpu_mrays_per_s: f64,
    /// Hierarchy nodes (or steps) per ray.
    pub nodes_per_ray: f64,
    /// Box + plane tests per ray.
    pub tests_per_ray: f64,
    /// % of rays answered from layer 1 or deeper.
    pub pct_layer2: f64,
    pub pct_miss: f64,
    pub pct_occlusion: f64,
    /// % of rays whose traversal ran out of its step bound (a DDA `max_steps` too small for
    /// the view: those rays end as misses or occlusion volumes).
    pub pct_truncated: f64,
    /// Mean over both eyes (NaN when not scored).
    pub psnr: f64,
    pub ssim: f64,
    /// Why the method produced no numbers.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The BVH ground truth of both eyes.
pub fn eye_truths(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
) -> Result<[Image<Rgb>; 2], SynthError> {
    let eyes = stereo_eyes(&setup.desc, setup.width, setup.height, setup.ipd)?;
    Ok(eyes.map(|e| ground_truth(scene, bvh, &e, setup.shading, setup.seed)))
}

/// Mean score of both eyes.
pub fn score_pair(views: &StereoViews, truths: &[Image<Rgb>; 2]) -> Result<Score, SynthError> {
    let a = score(&views.views[0].image, &truths[0])?;
    let b = score(&views.views[1].image, &truths[1])?;
    Ok(Score {
        psnr: (a.psnr + b.psnr) * 0.5,
        ssim: (a.ssim + b.ssim) * 0.5,
    })
}

/// The reference of `setup` with `layers` layers.
pub fn reference(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
    layers: usize,
) -> Result<Reference, SynthError> {
    let cam = Pinhole::new(&setup.desc, setup.width, setup.height)?;
    capture_reference(scene, bvh, &cam, layers, setup.shading, setup.seed)
}

/// Fits `reference`'s cube with `opts.cube_near`, builds `method` over it, warps it to both
/// eyes (best of `setup.repeats` per eye) and, for tracers, times the trace-only pass and ray
/// generation over the same eye rays; fills a row (an error row when the method fails).
/// [`measure_interleaved`] with one method.
pub fn measure(
    scene_name: &str,
    reference: &Reference,
    setup: &StereoSetup,
    method: Method,
    opts: &MethodOptions,
    truths: Option<&[Image<Rgb>; 2]>,
) -> (WarpRow, Option<StereoViews>) {
    measure_interleaved(
        scene_name,
        reference,
        setup,
        &[(method, *opts)],
        truths,
        &|_| {},
    )
    .pop()
    .expect("one row per method")
}

/// One method of [`measure_interleaved`].
struct Entrant {
    row: WarpRow,
    /// Index of its fitted reference.
    r: usize,
    synth: Option<Synthesizer>,
    build_ms: f64,
    /// The first view of each eye (warps are deterministic), `ms` lowered to the best round.
    views: [Option<WarpedView>; 2],
    /// Best process CPU ms of each eye's warp.
    view_cpu: [f64; 2],
    /// Best trace-only pass of each eye, and the rays it traced.
    trace: [PassTimes; 2],
    traced: [u64; 2],
}

impl Entrant {
    fn tracer(&self) -> Option<&dyn ScreenTracer> {
        match &self.synth {
            Some(Synthesizer::Tracer(t, _)) => Some(t.as_ref()),
            _ => None,
        }
    }

    /// Makes this an error row and stops measuring it.
    fn fail(&mut self, e: impl ToString) {
        self.row.error = Some(e.to_string());
        self.synth = None;
        self.views = [None, None];
    }
}

/// Measures every `(method, options)` of `entries` over `reference` (module docs, "Interleaved
/// rounds"): every method is built first (its reference's cube fitted with its
/// `cube_near`), then each of `setup.repeats` rounds runs every method once: the whole warp
/// of both eyes for every method, ray generation of both eyes once (the rays of the first
/// round are shared by every tracer), then the trace-only pass of both eyes for every
/// tracer. Every time column keeps per method the best (minimum) of the rounds, so a
/// disturbance of the machine during one round hits every method alike instead of skewing
/// one method's block. Rows in the order of `entries`, with the stereo views of the
/// methods that produced numbers; images, kinds, work and stats are those of
/// [`measure`]-ing each method alone.
pub fn measure_interleaved(
    scene_name: &str,
    reference: &Reference,
    setup: &StereoSetup,
    entries: &[(Method, MethodOptions)],
    truths: Option<&[Image<Rgb>; 2]>,
    progress: &dyn Fn(&str),
) -> Vec<(WarpRow, Option<StereoViews>)> {
    let repeats = setup.repeats.max(1);
    let n_layers = reference.layers.len();
    let eyes = stereo_eyes(
        &setup.desc,
        reference.width(),
        reference.height(),
        setup.ipd,
    );
    // One fitted reference per cube near plane (a run shares one).
    let mut refs: Vec<(CubeNear, Result<Reference, String>)> = Vec::new();
    let mut ents: Vec<Entrant> = Vec::with_capacity(entries.len());
    for (method, opts) in entries {
        progress(&format!("build {method}, {n_layers} layer(s)"));
        let mut e = Entrant {
            row: WarpRow {
                method: method.name().into(),
                layers: n_layers,
                scene: scene_name.into(),
                width: setup.width,
                height: setup.height,
                cube_near: cube_near_name(opts.cube_near),
                dda_max_steps: (*method == Method::Dda).then_some(opts.dda_max_steps),
                repeats,
                psnr: f64::NAN,
                ssim: f64::NAN,
                ms_trace: f64::NAN,
                ms_trace_cpu: f64::NAN,
                ms_trace_process_cpu: f64::NAN,
                ms_raygen: f64::NAN,
                ms_raygen_process_cpu: f64::NAN,
                trace_mrays_per_s: f64::NAN,
                trace_cpu_mrays_per_s: f64::NAN,
                ..WarpRow::default()
            },
            r: 0,
            synth: None,
            build_ms: 0.0,
            views: [None, None],
            view_cpu: [f64::INFINITY; 2],
            trace: [PassTimes::worst(); 2],
            traced: [0; 2],
        };
        let k = match refs.iter().position(|(near, _)| *near == opts.cube_near) {
            Some(k) => k,
            None => {
                let mut r = reference.clone();
                let fitted = r.fit_cube(opts.cube_near).map(|_| r);
                refs.push((opts.cube_near, fitted.map_err(|e| e.to_string())));
                refs.len() - 1
            }
        };
        e.r = k;
        let built = match (&refs[k].1, &eyes) {
            (Err(err), _) => Err(err.clone()),
            (_, Err(err)) => Err(err.to_string()),
            (Ok(r), Ok(_)) => {
                let t = Instant::now();
                let s = Synthesizer::build(*method, r, opts).map_err(|e| e.to_string());
                e.build_ms = t.elapsed().as_secs_f64() * 1e3;
                s
            }
        };
        match built {
            Ok(s) => e.synth = Some(s),
            Err(err) => e.row.error = Some(err),
        }
        ents.push(e);
    }
    let Ok(eyes) = eyes else {
        return ents.into_iter().map(|e| (e.row, None)).collect();
    };
    let mut gen_t = [PassTimes::worst(); 2];
    let mut rays: [Vec<Option<Ray>>; 2] = [Vec::new(), Vec::new()];
    for round in 0..repeats {
        let tag = |m: &str, what: &str| {
            format!(
                "round {}/{repeats}: {m} {what}, {n_layers} layer(s)",
                round + 1
            )
        };
        for e in &mut ents {
            let Some(synth) = &e.synth else { continue };
            progress(&tag(&e.row.method, "warp"));
            let Ok(r) = &refs[e.r].1 else { continue };
            let mut failed = None;
            for (k, eye) in eyes.iter().enumerate() {
                let c0 = process_cpu_ns();
                let v = match synth.view(r, eye) {
                    Ok(v) => v,
                    Err(err) => {
                        failed = Some(err);
                        break;
                    }
                };
                e.view_cpu[k] = e.view_cpu[k].min(ms_between(c0, process_cpu_ns()));
                match &mut e.views[k] {
                    Some(best) => best.ms = best.ms.min(v.ms),
                    slot => *slot = Some(v),
                }
            }
            if let Some(err) = failed {
                e.fail(err);
            }
        }
        if !ents.iter().any(|e| e.tracer().is_some()) {
            continue;
        }
        progress(&tag("eye", "rays"));
        for (k, eye) in eyes.iter().enumerate() {
            let (rs, g) = eye_rays(eye);
            gen_t[k] = gen_t[k].min(g);
            if round == 0 {
                rays[k] = rs;
            }
        }
        for e in &mut ents {
            let Some(tracer) = e.tracer() else { continue };
            progress(&tag(&e.row.method, "trace-only"));
            let out = [0, 1].map(|k| trace_pass(tracer, &rays[k], eyes[k].width));
            for (k, (stats, t)) in out.into_iter().enumerate() {
                e.trace[k] = e.trace[k].min(t);
                e.traced[k] = stats.rays;
            }
        }
    }
    drop(rays);
    ents.into_iter()
        .map(|e| {
            let r = refs[e.r].1.as_ref().ok();
            finish(e, r, &eyes, gen_t, truths)
        })
        .collect()
}

/// The row of a measured entrant (the arithmetic of the per-method measurement before the
/// rounds were interleaved, so the numbers compare across versions).
fn finish(
    mut e: Entrant,
    r: Option<&Reference>,
    eyes: &[Pinhole; 2],
    gen_t: [PassTimes; 2],
    truths: Option<&[Image<Rgb>; 2]>,
) -> (WarpRow, Option<StereoViews>) {
    let mut row = std::mem::take(&mut e.row);
    if let Some(r) = r {
        row.near_m = r.cube.near;
        row.far_m = r.cube.far;
    }
    let (Some(r), [Some(_), Some(_)]) = (r, &e.views) else {
        return (row, None);
    };
    let [Some(v0), Some(v1)] = std::mem::take(&mut e.views) else {
        unreachable!("checked above")
    };
    let sv = StereoViews {
        eyes: eyes.clone(),
        views: [v0, v1],
    };
    let t = ReferenceTimes {
        build_ms: e.build_ms,
        ..r.times
    };
    row.ms_capture = t.capture_ms;
    row.ms_shade = t.shade_ms;
    row.ms_build = t.build_ms;
    row.ms_ref = t.total_ms();
    row.ms_view = sv.ms_eye();
    row.ms_view_cpu = e.view_cpu[0] * 0.5 + e.view_cpu[1] * 0.5;
    row.ms_total = row.ms_ref + 2.0 * row.ms_view;
    let rays: u64 = sv.views.iter().map(|v| v.stats.rays).sum();
    let ms: f64 = sv.views.iter().map(|v| v.ms).sum();
    row.mrays_per_s = if rays > 0 {
        rays as f64 / (ms * 1e3)
    } else {
        0.0
    };
    if e.tracer().is_some() {
        let half = |f: fn(&PassTimes) -> f64, t: &[PassTimes; 2]| f(&t[0]) * 0.5 + f(&t[1]) * 0.5;
        row.ms_raygen = half(|t| t.wall_ms, &gen_t);
        row.ms_raygen_process_cpu = half(|t| t.process_cpu_ms, &gen_t);
        row.ms_trace = half(|t| t.wall_ms, &e.trace);
        row.ms_trace_cpu = half(|t| t.thread_cpu_ms, &e.trace);
        row.ms_trace_process_cpu = half(|t| t.process_cpu_ms, &e.trace);
        // Per eye: half the rays of both eyes.
        let per_eye = (e.traced[0] + e.traced[1]) as f64 * 0.5;
        row.trace_mrays_per_s = per_eye / (row.ms_trace * 1e3);
        row.trace_cpu_mrays_per_s = per_eye / (row.ms_trace_cpu * 1e3);
    }
    row.nodes_per_ray = sv.views.iter().map(|v| v.nodes_per_ray()).sum::<f64>() * 0.5;
    row.tests_per_ray = sv.views.iter().map(|v| v.tests_per_ray()).sum::<f64>() * 0.5;
    row.pct_layer2 = sv.views.iter().map(|v| v.frac_deep()).sum::<f64>() * 50.0;
    let fr: Vec<_> = sv.views.iter().map(|v| v.kind_fractions()).collect();
    row.pct_miss = (fr[0].1 + fr[1].1) * 50.0;
    row.pct_occlusion = (fr[0].2 + fr[1].2) * 50.0;
    row.pct_truncated = sv.views.iter().map(|v| v.pct_truncated()).sum::<f64>() * 0.5;
    if let Some(tr) = truths {
        match score_pair(&sv, tr) {
            Ok(s) => (row.psnr, row.ssim) = (s.psnr, s.ssim),
            Err(e) => row.error = Some(e.to_string()),
        }
    }
    (row, Some(sv))
}

/// PSNR tolerance of [`dda_minimal_steps`]: a max-steps setting is equivalent to the
/// converged DDA when its PSNR is at most this much lower (dB).
pub const DDA_EQUIV_PSNR_DB: f64 = 0.05;
/// Miss / occlusion-volume tolerance of [`dda_minimal_steps`]: at most this many more % of
/// the pixels may be misses, and as many more occlusion-volume answers, than with the
/// converged DDA (0.01% = 144 of 1600x900 pixels; capped rays end as one or the other).
pub const DDA_EQUIV_EXTRA_PCT: f64 = 0.01;

/// Widmer et al. 2015, §5.1: "we used a minimum value [of the DDA's max steps] at which the
/// DDA method produced results that are artifact-free and equivalent to ours". Over the
/// `(max_steps, psnr, pct_miss, pct_occlusion)` of a sweep, the converged reference is the
/// largest `max_steps`; returns the smallest `max_steps` from which on every setting is within
/// [`DDA_EQUIV_PSNR_DB`] of the reference's PSNR and has at most [`DDA_EQUIV_EXTRA_PCT`] %
/// more misses and occlusion-volume answers (`None` for an empty sweep).
pub fn dda_minimal_steps(sweep: &[(u32, f64, f64, f64)]) -> Option<u32> {
    let mut v = sweep.to_vec();
    v.sort_by_key(|s| s.0);
    let &(_, p_ref, m_ref, o_ref) = v.last()?;
    let ok = |&(_, p, m, o): &(u32, f64, f64, f64)| {
        (p_ref.is_nan() || p >= p_ref - DDA_EQUIV_PSNR_DB)
            && m <= m_ref + DDA_EQUIV_EXTRA_PCT
            && o <= o_ref + DDA_EQUIV_EXTRA_PCT
    };
    let mut best = v.last()?.0;
    for s in v.iter().rev() {
        if ok(s) {
            best = s.0;
        } else {
            break;
        }
    }
    Some(best)
}

/// Runs every `method` x `layers` (mesh once with one layer); the DDA once per value of
/// `dda_steps` (once with `opts.dda_max_steps` when empty). `progress(msg)` reports stages.
#[allow(clippy::too_many_arguments)]
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
    methods: &[Method],
    layers: &[usize],
    opts: &MethodOptions,
    dda_steps: &[u32],
    progress: &dyn Fn(&str),
) -> Result<Vec<WarpRow>, SynthError> {
    check_layers(layers)?;
    let truths = if setup.score {
        progress("BVH eye views");
        Some(eye_truths(scene, bvh, setup)?)
    } else {
        None
    };
    let mesh_layers = mesh_layers(layers);
    let mut rows = Vec::new();
    for &n in layers {
        progress(&format!("reference, {n} layer(s)"));
        let r = reference(scene, bvh, setup, n)?;
        let entries = method_entries(methods, n, mesh_layers, opts, dda_steps);
        let measured =
            measure_interleaved(&scene.name, &r, setup, &entries, truths.as_ref(), progress);
        rows.extend(measured.into_iter().map(|(row, _)| row));
    }
    Ok(rows)
}
