//! Captures: what the image-space tracers trace. A capture is a stack of `N` G-buffer layers
//! of one view, rasterized by [`crate::raster`] and resolved into the same channels as the BVH
//! reference renderer (view depth, world position, shading normal, albedo, material and
//! primitive ids, barycentrics), plus its size in bytes and per-stage timings.
//!
//! | capture | views | built by |
//! |---|---|---|
//! | [`LayerCapture`] | one pinhole / stereo eye / orthographic view | [`capture_layers`] |
//! | [`CubeCapture`] | six 90° faces around a point (seamless) | [`CubeCapture::capture`] |
//! | [`AllLayersCapture`] | one view, every surface per pixel (CSR) | [`capture_all_layers`] |
//!
//! Layer 0 is the G-buffer (primary visibility); layer `k` the `k`-th surface along the
//! pixel-centre ray (depth peeling, Everitt 2001), optionally at least `Δ` behind layer
//! `k - 1` (deep G-buffers, Mara et al. 2013). Layers are flat planar arrays
//! ([`LayeredGBuffer`]); nothing is allocated per pixel.
//!
//! **Invariant:** a resolved sample equals what the BVH reference G-buffer computes from the
//! same primitive and barycentrics (same normal flip towards the viewer, same texture lookup).

pub mod all_layers;
pub mod cube;
mod resolve;

use std::time::Instant;

use parallax_core::image::{GBuffer, LayeredGBuffer};
use parallax_scene::Scene;
use serde::Serialize;

pub use all_layers::{AllLayersCapture, AllLayersStats, capture_all_layers};
pub use cube::CubeCapture;
pub use resolve::resolve_fragment;

use crate::raster::{RasterError, RasterOptions, RasterStats, TriangleFilter, View, rasterize};

/// Sizes, work and per-stage times of a capture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CaptureStats {
    pub width: u32,
    pub height: u32,
    pub layers: usize,
    /// Bytes of the captured layers (the result; scratch is in `raster.scratch_bytes`).
    pub bytes: usize,
    pub raster: RasterStats,
    pub resolve_ms: f64,
    /// Setup + bin + raster + resolve, wall clock.
    pub total_ms: f64,
}

/// `N` G-buffer layers of one view.
#[derive(Clone, Debug)]
pub struct LayerCapture {
    pub view: View,
    pub layers: LayeredGBuffer,
    pub stats: CaptureStats,
}

impl LayerCapture {
    /// Layer 0: the G-buffer of primary visibility.
    pub fn gbuffer(&self) -> &GBuffer {
        self.layers.layer(0)
    }

    /// Bytes held by the layers.
    pub fn bytes(&self) -> usize {
        self.layers.bytes()
    }
}

/// Rasterizes `scene` into `opts.layers` G-buffer layers of `view`.
pub fn capture_layers(
    scene: &Scene,
    view: &View,
    opts: &RasterOptions,
) -> Result<LayerCapture, RasterError> {
    capture_layers_filtered(scene, view, opts, None)
}

/// [`capture_layers`] of one layer: the rasterized G-buffer.
pub fn capture_gbuffer(scene: &Scene, view: &View) -> Result<LayerCapture, RasterError> {
    capture_layers(scene, view, &RasterOptions::default())
}

/// [`capture_layers`] of only the triangles `filter` accepts (e.g. one object, or the
/// triangles facing an LDI axis).
pub fn capture_layers_filtered(
    scene: &Scene,
    view: &View,
    opts: &RasterOptions,
    filter: Option<TriangleFilter>,
) -> Result<LayerCapture, RasterError> {
    let start = Instant::now();
    opts.validate()?;
    let mut layers =
        LayeredGBuffer::new(view.width, view.height, opts.layers).map_err(RasterError::Size)?;
    let (frags, raster) = rasterize(&scene.mesh, view, opts, filter)?;
    let t = Instant::now();
    for (k, g) in layers.layers.iter_mut().enumerate() {
        resolve::resolve_layer(scene, view, &frags, k, g);
    }
    let resolve_ms = t.elapsed().as_secs_f64() * 1e3;
    let stats = CaptureStats {
        width: view.width,
        height: view.height,
        layers: opts.layers,
        bytes: layers.bytes(),
        raster,
        resolve_ms,
        total_ms: start.elapsed().as_secs_f64() * 1e3,
    };
    Ok(LayerCapture {
        view: view.clone(),
        layers,
        stats,
    })
}
