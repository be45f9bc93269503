//! `parallax bench warp`: the stereo-warping comparison of Widmer et al. 2015, Table 2, on any
//! scene and view. A cyclopean reference with `N` layers is captured and shaded once per `N`
//! (`T_ref` = capture + shade + the method's structure build), every method warps it to both
//! eyes (`T_eye` = mean per eye, `T_total = T_ref + 2 T_eye`), and both eyes are scored
//! against the BVH reference render of the eye cameras ([`crate::synth::score`]).
//!
//! The mesh warp uses layer 0 only, so it runs once, with `N = 1`. Methods not available in
//! this build give a row carrying the error instead of numbers.

use parallax_bvh::Bvh;
use parallax_core::{Image, Rgb};
use parallax_scene::camera::Pinhole;
use parallax_scene::{CameraDesc, Scene};
use serde::Serialize;

use crate::synth::SynthError;
use crate::synth::layers::{Reference, Shading, capture_reference};
use crate::synth::method::{Method, MethodOptions};
use crate::synth::score::{Score, ground_truth, score};
use crate::synth::stereo::{StereoViews, stereo_eyes, warp_stereo};

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
}

/// One row of Table 2.
#[derive(Clone, Debug, Default, Serialize)]
pub struct WarpRow {
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// `T_ref`: capture + shade + build.
    pub ms_ref: f64,
    pub ms_capture: f64,
    pub ms_shade: f64,
    pub ms_build: f64,
    /// `T_eye`: mean per eye.
    pub ms_view: f64,
    /// `T_ref + 2 T_eye`.
    pub ms_total: f64,
    /// Eye rays per second of tracing (0 for the mesh warp).
    pub mrays_per_s: f64,
    /// Hierarchy nodes (or steps) per ray.
    pub nodes_per_ray: f64,
    /// Box + plane tests per ray.
    pub tests_per_ray: f64,
    /// % of rays answered from layer 1 or deeper.
    pub pct_layer2: f64,
    pub pct_miss: f64,
    pub pct_occlusion: f64,
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

/// Warps `reference` with `method` and fills a row (an error row when the method fails).
pub fn measure(
    scene_name: &str,
    reference: &Reference,
    setup: &StereoSetup,
    method: Method,
    opts: &MethodOptions,
    truths: Option<&[Image<Rgb>; 2]>,
) -> (WarpRow, Option<StereoViews>) {
    let mut row = WarpRow {
        method: method.name().into(),
        layers: reference.layers.len(),
        scene: scene_name.into(),
        width: setup.width,
        height: setup.height,
        psnr: f64::NAN,
        ssim: f64::NAN,
        ..WarpRow::default()
    };
    let mut r = reference.clone();
    let sv = match warp_stereo(&mut r, &setup.desc, setup.ipd, method, opts) {
        Ok(sv) => sv,
        Err(e) => {
            row.error = Some(e.to_string());
            return (row, None);
        }
    };
    let t = r.times;
    row.ms_capture = t.capture_ms;
    row.ms_shade = t.shade_ms;
    row.ms_build = t.build_ms;
    row.ms_ref = t.total_ms();
    row.ms_view = sv.ms_eye();
    row.ms_total = row.ms_ref + 2.0 * row.ms_view;
    let rays: u64 = sv.views.iter().map(|v| v.stats.rays).sum();
    let ms: f64 = sv.views.iter().map(|v| v.ms).sum();
    row.mrays_per_s = if rays > 0 {
        rays as f64 / (ms * 1e3)
    } else {
        0.0
    };
    row.nodes_per_ray = sv.views.iter().map(|v| v.nodes_per_ray()).sum::<f64>() * 0.5;
    row.tests_per_ray = sv.views.iter().map(|v| v.tests_per_ray()).sum::<f64>() * 0.5;
    row.pct_layer2 = sv.views.iter().map(|v| v.frac_deep()).sum::<f64>() * 50.0;
    let fr: Vec<_> = sv.views.iter().map(|v| v.kind_fractions()).collect();
    row.pct_miss = (fr[0].1 + fr[1].1) * 50.0;
    row.pct_occlusion = (fr[0].2 + fr[1].2) * 50.0;
    if let Some(tr) = truths {
        match score_pair(&sv, tr) {
            Ok(s) => (row.psnr, row.ssim) = (s.psnr, s.ssim),
            Err(e) => row.error = Some(e.to_string()),
        }
    }
    (row, Some(sv))
}

/// Runs every `method` x `layers` (mesh once with one layer). `progress(msg)` reports stages.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
    methods: &[Method],
    layers: &[usize],
    opts: &MethodOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<WarpRow>, SynthError> {
    if layers.is_empty() || layers.iter().any(|&l| l == 0 || l > 8) {
        return Err(SynthError::Invalid(format!(
            "layers must be in 1..=8, got {layers:?}"
        )));
    }
    let truths = if setup.score {
        progress("BVH eye views");
        Some(eye_truths(scene, bvh, setup)?)
    } else {
        None
    };
    let mesh_layers = if layers.contains(&1) { 1 } else { layers[0] };
    let mut rows = Vec::new();
    for &n in layers {
        progress(&format!("reference, {n} layer(s)"));
        let r = reference(scene, bvh, setup, n)?;
        for &m in methods {
            if m == Method::Mesh && n != mesh_layers {
                continue;
            }
            progress(&format!("{m}, {n} layer(s)"));
            rows.push(measure(&scene.name, &r, setup, m, opts, truths.as_ref()).0);
        }
    }
    Ok(rows)
}
