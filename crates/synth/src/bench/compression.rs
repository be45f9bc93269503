//! `parallax bench compression`: the quad-tree compression study of Widmer et al. 2015, §6,
//! Fig. 14 and 15, on stereo warping: frame time and PSNR while
//!
//! - `gamma_dist` goes from 1e-5 to 1e-1 (log steps) at `gamma_norm = cos 3°` (Fig. 14, red);
//! - `gamma_norm` goes from cos 3° to cos 25° at `gamma_dist = 1e-5` (Fig. 14, blue);
//! - both vary together from (cos 3°, 1e-5) to (cos 25°, 1e-1), depth-adaptive thresholds off
//!   and on (Fig. 15).
//!
//! The thresholds reach the structure through [`MethodOptions`] (`gamma_norm`, `gamma_dist`,
//! `adaptive`); methods that ignore them give the same numbers on every row.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use serde::Serialize;

use super::warp::{StereoSetup, eye_truths, measure, reference};
use crate::SynthError;
use crate::method::{Method, MethodOptions};

/// One point of Fig. 14 / 15.
#[derive(Clone, Debug, Default, Serialize)]
pub struct CompressionRow {
    /// "gamma_dist", "gamma_norm", "both" or "both_adaptive".
    pub sweep: String,
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub gamma_norm_deg: f32,
    pub gamma_norm: f32,
    pub gamma_dist: f32,
    pub adaptive: bool,
    /// The unit cube's near-plane setting (`fitted` or `camera <m> m`).
    pub cube_near: String,
    pub ms_build: f64,
    pub ms_view: f64,
    pub mrays_per_s: f64,
    pub nodes_per_ray: f64,
    pub psnr: f64,
    pub ssim: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The (sweep, angle in degrees, gamma_dist, adaptive) points.
pub fn points() -> Vec<(&'static str, f32, f32, bool)> {
    let dists = [1e-5f32, 1e-4, 1e-3, 1e-2, 1e-1];
    let angles = [3.0f32, 5.0, 10.0, 15.0, 20.0, 25.0];
    let mut p = Vec::new();
    for d in dists {
        p.push(("gamma_dist", 3.0, d, false));
    }
    for a in angles {
        p.push(("gamma_norm", a, 1e-5, false));
    }
    for adaptive in [false, true] {
        let name = if adaptive { "both_adaptive" } else { "both" };
        for i in 0..5 {
            let s = i as f32 / 4.0;
            p.push((name, 3.0 + 22.0 * s, 10f32.powf(-5.0 + 4.0 * s), adaptive));
        }
    }
    p
}

/// Runs every point with `method` and `layers` layers.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    setup: &StereoSetup,
    method: Method,
    layers: usize,
    base: &MethodOptions,
    progress: &dyn Fn(&str),
) -> Result<Vec<CompressionRow>, SynthError> {
    if layers == 0 || layers > 8 {
        return Err(SynthError::Invalid(format!(
            "layers must be in 1..=8, got {layers}"
        )));
    }
    let truths = if setup.score {
        progress("BVH eye views");
        Some(eye_truths(scene, bvh, setup)?)
    } else {
        None
    };
    progress("reference");
    let r = reference(scene, bvh, setup, layers)?;
    let mut rows = Vec::new();
    for (sweep, deg, dist, adaptive) in points() {
        progress(&format!(
            "{sweep}: {deg} deg, {dist:e}, adaptive {adaptive}"
        ));
        let opts = MethodOptions {
            gamma_norm: deg.to_radians().cos(),
            gamma_dist: dist,
            adaptive,
            ..*base
        };
        let (w, _) = measure(&scene.name, &r, setup, method, &opts, truths.as_ref());
        rows.push(CompressionRow {
            sweep: sweep.into(),
            method: w.method,
            layers,
            scene: w.scene,
            width: w.width,
            height: w.height,
            gamma_norm_deg: deg,
            gamma_norm: opts.gamma_norm,
            gamma_dist: dist,
            adaptive,
            cube_near: w.cube_near,
            ms_build: w.ms_build,
            ms_view: w.ms_view,
            mrays_per_s: w.mrays_per_s,
            nodes_per_ray: w.nodes_per_ray,
            psnr: w.psnr,
            ssim: w.ssim,
            error: w.error,
        });
    }
    Ok(rows)
}
