//! `parallax bench upsample`: the 15 -> 60 Hz comparison of Widmer et al. 2015, Table 3. Per
//! method and layer count the camera path is run with a reference every 4th frame
//! ([`crate::upsample`]); reported: mean `T_ref`, mean and standard deviation of
//! `T_syn` over the synthesised frames, the amortised frame time `T_amt` (all frame times /
//! frames), tracing Mrays/s, and the mean PSNR / SSIM of the synthesised frames against the
//! BVH render of their cameras (optional: one reference render per synthesised frame).
//!
//! The methods of one layer count run **interleaved** ([`measure_interleaved`]): each
//! reference is captured once, and each synthesised frame is warped by every method in turn,
//! so a disturbance of the shared machine hits every method alike (before, each method ran
//! the whole path in its own block). `T_ref` of a method = the shared capture + shading + its
//! own structure build.

use parallax_bvh::Bvh;
use parallax_core::{Image, Rgb};
use parallax_scene::Scene;
use parallax_scene::path::CameraPath;
use serde::Serialize;

use super::{mesh_layers, method_entries};
use crate::SynthError;
use crate::layers::check_layers;
use crate::method::{Method, MethodOptions, cube_near_name};
use crate::upsample::{FrameTimes, UpsampleOptions, upsample_interleaved};
use parallax_render::score::Shading;
use parallax_render::score::{ground_truth, score};

/// One row of Table 3.
#[derive(Clone, Debug, Default, Serialize)]
pub struct UpsampleRow {
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    /// The unit cube's near-plane setting (`fitted` or `camera <m> m`) and the first
    /// reference's cube near / far view depths (metres).
    pub cube_near: String,
    pub near_m: f32,
    pub far_m: f32,
    /// The DDA's max steps (DDA rows only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dda_max_steps: Option<u32>,
    /// Mean `T_ref` of the reference frames.
    pub ms_ref: f64,
    /// Mean `T_syn` of the synthesised frames and its standard deviation.
    pub ms_view: f64,
    pub ms_view_std: f64,
    /// Amortised frame time.
    pub ms_amortized: f64,
    pub mrays_per_s: f64,
    pub nodes_per_ray: f64,
    pub pct_layer2: f64,
    /// % of synthesised pixels that are misses / occlusion-volume answers (mean over frames).
    pub pct_miss: f64,
    pub pct_occlusion: f64,
    /// % of synthesised rays whose traversal ran out of its step bound (mean over frames).
    pub pct_truncated: f64,
    /// Means over the synthesised frames (NaN when not scored).
    pub psnr: f64,
    pub ssim: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// Settings of the run.
#[derive(Clone, Copy, Debug)]
pub struct UpsampleSetup {
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub shading: Shading,
    pub seed: u64,
    pub score: bool,
}

/// One method and layer count over the path ([`measure_interleaved`] with one method).
#[allow(clippy::too_many_arguments)]
pub fn measure(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    setup: &UpsampleSetup,
    method: Method,
    layers: usize,
    opts: &MethodOptions,
    progress: &dyn Fn(&str),
) -> UpsampleRow {
    measure_interleaved(
        scene,
        bvh,
        path,
        setup,
        &[(method, *opts)],
        layers,
        progress,
    )
    .pop()
    .expect("one row per method")
}

/// Sums over the synthesised frames of one method.
#[derive(Default)]
struct Acc {
    psnr: f64,
    ssim: f64,
    scored: u32,
    rays: u64,
    nodes: f64,
    deep: f64,
    trace_ms: f64,
    syn: u32,
    miss: f64,
    occ: f64,
    truncated: f64,
    near: Option<(f32, f32)>,
}

/// Every `(method, options)` of `entries` with `layers` layers over the path, interleaved
/// ([`upsample_interleaved`]: one capture per reference frame, every synthesised frame run by
/// every method in turn, so a disturbance of the machine hits all methods alike; the BVH
/// ground truth of a frame is rendered once for all methods). Rows in the order of
/// `entries`, each equal but for the times to [`measure`]-ing the method alone.
pub fn measure_interleaved(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    setup: &UpsampleSetup,
    entries: &[(Method, MethodOptions)],
    layers: usize,
    progress: &dyn Fn(&str),
) -> Vec<UpsampleRow> {
    let uo = UpsampleOptions {
        frames: setup.frames,
        fps: 60.0,
        period: 4,
        layers,
        method: entries.first().map_or(Method::QuadTree, |e| e.0),
        method_opts: entries.first().map_or_else(MethodOptions::default, |e| e.1),
        shading: setup.shading,
        seed: setup.seed,
    };
    let mut accs: Vec<Acc> = entries.iter().map(|_| Acc::default()).collect();
    let mut truth: Option<(u32, Image<Rgb>)> = None;
    let results = upsample_interleaved(
        scene,
        bvh,
        path,
        setup.width,
        setup.height,
        &uo,
        entries,
        &mut |k, f| {
            progress(&format!(
                "{}, {layers} layer(s): frame {}",
                entries[k].0, f.index
            ));
            let a = &mut accs[k];
            a.near
                .get_or_insert((f.reference.cube.near, f.reference.cube.far));
            if let Some(v) = &f.view {
                let (_, m, o) = v.kind_fractions();
                a.miss += m;
                a.occ += o;
                a.truncated += v.pct_truncated();
                a.rays += v.stats.rays;
                a.nodes += v.nodes_per_ray();
                a.deep += v.frac_deep();
                a.trace_ms += v.ms;
                a.syn += 1;
                if setup.score {
                    if truth.as_ref().is_none_or(|(i, _)| *i != f.index) {
                        let t = ground_truth(scene, bvh, &f.camera, setup.shading, setup.seed);
                        truth = Some((f.index, t));
                    }
                    let (_, t) = truth.as_ref().expect("just rendered");
                    let s = score(&v.image, t)?;
                    a.psnr += s.psnr;
                    a.ssim += s.ssim;
                    a.scored += 1;
                }
            }
            Ok(())
        },
    );
    entries
        .iter()
        .zip(results)
        .zip(accs)
        .map(|(((method, opts), result), a)| {
            let mut row = UpsampleRow {
                method: method.name().into(),
                layers,
                scene: scene.name.clone(),
                width: setup.width,
                height: setup.height,
                frames: setup.frames,
                cube_near: cube_near_name(opts.cube_near),
                dda_max_steps: (*method == Method::Dda).then_some(opts.dda_max_steps),
                psnr: f64::NAN,
                ssim: f64::NAN,
                ..UpsampleRow::default()
            };
            match result {
                Ok(times) => finish(&mut row, &times, &a),
                Err(e) => row.error = Some(e.to_string()),
            }
            row
        })
        .collect()
}

/// Fills the numbers of a row from its frame times and sums.
fn finish(row: &mut UpsampleRow, times: &[FrameTimes], a: &Acc) {
    let refs: Vec<f64> = times
        .iter()
        .filter(|t| t.is_reference)
        .map(|t| t.ms_ref)
        .collect();
    let syns: Vec<f64> = times
        .iter()
        .filter(|t| !t.is_reference)
        .map(|t| t.ms_syn)
        .collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    row.ms_ref = mean(&refs);
    row.ms_view = mean(&syns);
    row.ms_view_std = (syns.iter().map(|x| (x - row.ms_view).powi(2)).sum::<f64>()
        / syns.len().max(1) as f64)
        .sqrt();
    row.ms_amortized = (refs.iter().sum::<f64>() + syns.iter().sum::<f64>()) / times.len() as f64;
    row.mrays_per_s = if a.rays > 0 {
        a.rays as f64 / (a.trace_ms * 1e3)
    } else {
        0.0
    };
    let syn = a.syn.max(1) as f64;
    row.nodes_per_ray = a.nodes / syn;
    row.pct_layer2 = a.deep * 100.0 / syn;
    row.pct_miss = a.miss * 100.0 / syn;
    row.pct_occlusion = a.occ * 100.0 / syn;
    row.pct_truncated = a.truncated / syn;
    (row.near_m, row.far_m) = a.near.unwrap_or((f32::NAN, f32::NAN));
    if a.scored > 0 {
        row.psnr = a.psnr / a.scored as f64;
        row.ssim = a.ssim / a.scored as f64;
    }
}

/// Every method x layer count; the DDA once per value of `dda_steps` (once with
/// `opts.dda_max_steps` when empty). The methods of one layer count run interleaved
/// ([`measure_interleaved`]).
#[allow(clippy::too_many_arguments)]
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    setup: &UpsampleSetup,
    methods: &[Method],
    layers: &[usize],
    opts: &MethodOptions,
    dda_steps: &[u32],
    progress: &dyn Fn(&str),
) -> Result<Vec<UpsampleRow>, SynthError> {
    check_layers(layers)?;
    if setup.frames == 0 {
        return Err(SynthError::Invalid("frames must be >= 1".into()));
    }
    let mesh_layers = mesh_layers(layers);
    let mut rows = Vec::new();
    for &n in layers {
        let entries = method_entries(methods, n, mesh_layers, opts, dda_steps);
        rows.extend(measure_interleaved(
            scene, bvh, path, setup, &entries, n, progress,
        ));
    }
    Ok(rows)
}
