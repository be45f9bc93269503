//! parallax-raster: what the image-space tracers trace — captures made by a software
//! rasterizer.
//!
//! - [`raster`]: a tile-binned, multi-threaded triangle rasterizer (homogeneous clipping,
//!   fixed-point sub-pixel edge functions, top-left fill rule, perspective-correct attributes);
//! - [`capture`]: G-buffers, k depth layers (depth peeling), cube maps, orthographic views;
//! - [`dirt`]: DIRT's per-pixel (or per-tile) lists of pixel-clipped triangles with depth
//!   bounds and their min-max mip chain (Vardis et al. 2017, §4.1);
//! - [`ldc`]: layered depth cubes — three all-layers orthographic LDIs along the scene box axes
//!   with a coarse min/max grid (Bürger et al. 2007, §1.2-1.3).
//!
//! **Invariant:** `raster` reads the scene; the screen-space tracers built on top never do —
//! they see only what a capture holds.

pub mod capture;
pub mod dirt;
pub mod error;
pub mod ldc;
pub mod normals;
pub mod raster;

pub use capture::{
    AllLayersCapture, CaptureStats, CubeCapture, LayerCapture, capture_all_layers, capture_gbuffer,
    capture_layers, capture_layers_filtered,
};
pub use ldc::{LayeredDepthCube, LdcOptions};
pub use raster::{
    Fragment, Fragments, LayerMethod, Projection, RasterError, RasterOptions, RasterStats, View,
    rasterize,
};
