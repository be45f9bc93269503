//! One view through several tracers: each renders its own image (its hits make its next
//! level's rays), each is scored against the reference's image, and the reference's batches
//! are replayed through all of them ([`super::replay`]) so that their agreement and speed are
//! measured on identical rays.

use parallax_core::image::GBuffer;
use parallax_core::{Image, Rgb};
use parallax_raster::ldc::LdcStats;
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;
use serde::Serialize;

use super::options::{SecondaryError, SecondaryOptions};
use super::render::render;
use super::replay::{Contender, EffectRow, RayBatch, replay_rows, score};
use crate::tracers::BuiltTracer;

/// One tracer's image and costs.
#[derive(Clone, Debug, Serialize)]
pub struct TracerReport {
    pub method: String,
    pub ms_build: f64,
    pub bytes: usize,
    /// The whole secondary pass with this tracer (shading included), wall ms.
    pub ms_render: f64,
    /// Rays of its own render.
    pub rays: usize,
    /// Against the reference image (`inf` for the reference itself).
    pub psnr: f64,
    pub ssim: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ldc: Option<LdcStats>,
}

/// The result of [`compare`].
pub struct Comparison {
    /// Each tracer's image, reference first.
    pub images: Vec<(String, Image<Rgb>)>,
    pub tracers: Vec<TracerReport>,
    /// The reference's rays through every tracer (reference first).
    pub rows: Vec<EffectRow>,
}

/// Renders the view with `reference` and every tracer of `others`, scores them and replays the
/// reference's batches through all (`repeats` interleaved rounds; agreement `tolerance` in
/// world units).
#[allow(clippy::too_many_arguments)]
pub fn compare(
    scene: &Scene,
    camera: &Pinhole,
    gbuffer: &GBuffer,
    reference: &BuiltTracer,
    others: &[BuiltTracer],
    opts: &SecondaryOptions,
    repeats: u32,
    tolerance: f32,
) -> Result<Comparison, SecondaryError> {
    let truth = render(scene, camera, gbuffer, reference.tracer.as_ref(), opts)?;
    let mut images = Vec::new();
    let mut reports = Vec::new();
    let report =
        |t: &BuiltTracer, r: &super::SecondaryImage, (psnr, ssim): (f64, f64)| TracerReport {
            method: t.tracer.name().to_string(),
            ms_build: t.build_ms,
            bytes: t.bytes,
            ms_render: r.ms,
            rays: r.rays(),
            psnr,
            ssim,
            ldc: t.ldc,
        };
    reports.push(report(reference, &truth, (f64::INFINITY, 1.0)));
    for t in others {
        let r = render(scene, camera, gbuffer, t.tracer.as_ref(), opts)?;
        reports.push(report(t, &r, score(&r.image, &truth.image)?));
        images.push((t.tracer.name().to_string(), r.image));
    }
    let contenders: Vec<Contender> = std::iter::once(reference)
        .chain(others)
        .map(|t| Contender {
            tracer: t.tracer.as_ref(),
            build_ms: t.build_ms,
            bounds: t.bounds,
        })
        .collect();
    let batches: Vec<RayBatch> = truth.batches.iter().map(RayBatch::from).collect();
    let rows = replay_rows(&batches, &contenders, repeats, tolerance);
    images.insert(0, (reference.tracer.name().to_string(), truth.image));
    Ok(Comparison {
        images,
        tracers: reports,
        rows,
    })
}
