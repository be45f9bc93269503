//! The triangle rasterizer: what every capture of parallax is made with.
//!
//! Pipeline (one call of [`rasterize`]):
//! 1. **setup** (parallel over triangle chunks, [`setup`]): world -> clip `(x, y, d, w)` by the
//!    [`View`], homogeneous clipping against near/far and — only when a vertex leaves it — an
//!    x/y guard band ([`clip`]; Blinn & Newell 1978), snapping to 8-bit sub-pixel fixed point,
//!    orientation (nothing is culled by winding: back faces are layers too, and cube faces are
//!    mirrored), and the 2D-homogeneous barycentric solve (Olano & Greer 1997);
//! 2. **bin** ([`bin`]): triangles listed per 32x32 tile, in triangle order;
//! 3. **raster** (parallel over tiles, each tile owning its pixels, [`tile`]): Pineda 1988 edge
//!    functions in i64 with the top-left fill rule, perspective-correct barycentrics and view
//!    depth at the exact pixel centre, and `N` layers per pixel kept by a k-buffer (one pass)
//!    or by depth peeling with a minimum separation (Everitt 2001; Mara et al. 2013).
//!
//! The result ([`Fragments`]) holds per pixel and layer the depth, the primitive id and the
//! barycentrics; [`crate::capture`] resolves them into G-buffers. Output does not depend on the
//! thread count: fragments are ordered by `(depth, primitive id)`.
//!
//! **Invariants:** a pixel centre on an edge shared by two triangles is covered by exactly one of
//! them; a triangle covers a pixel at most once; the layers of a pixel are sorted by
//! `(depth, primitive id)`.

pub mod bin;
pub mod clip;
pub mod setup;
pub mod tile;
pub mod view;

use std::time::Instant;

use parallax_scene::TriangleMesh;
use rayon::prelude::*;
use serde::Serialize;

/// The largest layer count (that of [`parallax_core::LayeredGBuffer`]).
pub const MAX_LAYERS: usize = 64;

pub use bin::{Bins, TILE};
pub use setup::{RasterTri, SUB_BITS};
pub use tile::Fragment;
pub use view::{Projection, View};

use setup::{Setup, SetupOutcome};
use tile::Rect;

pub use crate::error::RasterError;

/// How the `N` layers are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum LayerMethod {
    /// One pass, insertion into a per-pixel k-buffer (exact for `min_separation = 0`).
    #[default]
    KBuffer,
    /// `N` passes per tile (exact for any `min_separation`).
    Peel,
}

/// Rasterizer options.
///
/// | option | type | default | meaning |
/// |---|---|---|---|
/// | `layers` | usize | 1 | depth layers per pixel, 1..=64 |
/// | `min_separation` | f32 (m) | 0 | minimum view-depth gap between consecutive layers (deep G-buffer Δ); > 0 forces [`LayerMethod::Peel`] |
/// | `method` | [`LayerMethod`] | `KBuffer` | how layers are found |
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RasterOptions {
    pub layers: usize,
    pub min_separation: f32,
    pub method: LayerMethod,
}

impl Default for RasterOptions {
    fn default() -> Self {
        Self {
            layers: 1,
            min_separation: 0.0,
            method: LayerMethod::KBuffer,
        }
    }
}

impl RasterOptions {
    /// `layers` layers, no separation.
    pub fn layers(layers: usize) -> Self {
        Self {
            layers,
            ..Self::default()
        }
    }

    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), RasterError> {
        if self.layers == 0 || self.layers > MAX_LAYERS {
            return Err(RasterError::InvalidOptions(format!(
                "layers must be in 1..=64, got {}",
                self.layers
            )));
        }
        if !(self.min_separation.is_finite() && self.min_separation >= 0.0) {
            return Err(RasterError::InvalidOptions(format!(
                "min_separation must be finite and >= 0, got {}",
                self.min_separation
            )));
        }
        Ok(())
    }
}

/// Work and time of one rasterization.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RasterStats {
    pub triangles: usize,
    /// Triangles dropped by the filter.
    pub filtered: usize,
    /// Triangles outside a clip plane, off screen or degenerate.
    pub culled: usize,
    /// Triangles clipped (near/far/guard band) before rasterization.
    pub clipped: usize,
    /// Raster triangles after clipping (fans).
    pub raster_triangles: usize,
    /// Tile-list entries.
    pub bin_refs: usize,
    /// Fragments kept (non-empty layer entries).
    pub fragments: usize,
    /// Bytes of the scratch arrays (raster triangles, bins, fragment store).
    pub scratch_bytes: usize,
    pub setup_ms: f64,
    pub bin_ms: f64,
    pub raster_ms: f64,
}

/// Per-pixel layers of fragments, tile-major: tile `t` owns a contiguous block of
/// `TILE * TILE * layers` fragments (pixel-major, layers nearest first).
#[derive(Clone, Debug)]
pub struct Fragments {
    pub width: u32,
    pub height: u32,
    pub layers: usize,
    tiles_x: u32,
    pub data: Vec<Fragment>,
}

impl Fragments {
    /// Layer `k` of pixel `(x, y)`.
    #[inline]
    pub fn get(&self, x: u32, y: u32, k: usize) -> Fragment {
        self.data[self.index(x, y) + k]
    }

    /// All layers of pixel `(x, y)`, nearest first.
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> &[Fragment] {
        let i = self.index(x, y);
        &self.data[i..i + self.layers]
    }

    #[inline]
    fn index(&self, x: u32, y: u32) -> usize {
        let t = (y / TILE) as usize * self.tiles_x as usize + (x / TILE) as usize;
        let local = (y % TILE) as usize * TILE as usize + (x % TILE) as usize;
        (t * (TILE * TILE) as usize + local) * self.layers
    }

    /// Bytes of the fragment store.
    pub fn bytes(&self) -> usize {
        self.data.len() * size_of::<Fragment>()
    }
}

/// A per-triangle predicate: rasterize triangle `prim` only if it returns true.
pub type TriangleFilter<'a> = &'a (dyn Fn(u32) -> bool + Sync);

pub(crate) fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Sets up every triangle of `mesh` that passes `filter`, in triangle order.
pub(crate) fn setup_all(
    mesh: &TriangleMesh,
    view: &View,
    filter: Option<TriangleFilter>,
    stats: &mut RasterStats,
) -> Vec<RasterTri> {
    const CHUNK: usize = 4096;
    let setup = Setup::new(view);
    let parts: Vec<(Vec<RasterTri>, [usize; 3])> = mesh
        .indices
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(ci, chunk)| {
            let mut out = Vec::with_capacity(chunk.len());
            let mut counts = [0usize; 3]; // filtered, culled, clipped
            for (k, idx) in chunk.iter().enumerate() {
                let prim = (ci * CHUNK + k) as u32;
                if filter.is_some_and(|f| !f(prim)) {
                    counts[0] += 1;
                    continue;
                }
                let c = idx.map(|i| view.clip(mesh.positions[i as usize]));
                match setup.triangle(prim, c, &mut out) {
                    SetupOutcome::Culled => counts[1] += 1,
                    SetupOutcome::Clipped => counts[2] += 1,
                    SetupOutcome::Unclipped => {}
                }
            }
            (out, counts)
        })
        .collect();
    let total = parts.iter().map(|p| p.0.len()).sum();
    let mut tris = Vec::with_capacity(total);
    for (p, c) in parts {
        tris.extend_from_slice(&p);
        stats.filtered += c[0];
        stats.culled += c[1];
        stats.clipped += c[2];
    }
    tris
}

/// Errors if a triangle index of `mesh` is out of range.
pub(crate) fn check_mesh(mesh: &TriangleMesh) -> Result<(), RasterError> {
    let nv = mesh.positions.len();
    if mesh
        .indices
        .par_iter()
        .any(|t| t.iter().any(|&i| i as usize >= nv))
    {
        return Err(RasterError::InvalidMesh(format!(
            "a triangle index is out of range ({nv} vertices)"
        )));
    }
    Ok(())
}

/// Rasterizes `mesh` into `opts.layers` fragment layers per pixel of `view`, optionally only
/// the triangles `filter` accepts. Errors on invalid options or a mesh whose indices are out of
/// range; degenerate, behind-the-eye or huge triangles are clipped or dropped, never a panic.
pub fn rasterize(
    mesh: &TriangleMesh,
    view: &View,
    opts: &RasterOptions,
    filter: Option<TriangleFilter>,
) -> Result<(Fragments, RasterStats), RasterError> {
    opts.validate()?;
    parallax_core::image::check_size(view.width, view.height).map_err(RasterError::Size)?;
    check_mesh(mesh)?;
    let layers = opts.layers;
    let tiles_x = view.width.div_ceil(TILE);
    let tiles_y = view.height.div_ceil(TILE);
    let per_tile = (TILE * TILE) as usize * layers;
    let total = tiles_x as u64 * tiles_y as u64 * per_tile as u64;
    if total > parallax_core::image::MAX_IMAGE_PIXELS {
        return Err(RasterError::InvalidOptions(format!(
            "{layers} layers of {}x{} exceed the size limit",
            view.width, view.height
        )));
    }
    let mut stats = RasterStats {
        triangles: mesh.indices.len(),
        ..RasterStats::default()
    };

    let t = Instant::now();
    let tris = setup_all(mesh, view, filter, &mut stats);
    stats.raster_triangles = tris.len();
    stats.setup_ms = ms(t);

    let t = Instant::now();
    let bins = Bins::new(&tris, view.width, view.height);
    stats.bin_refs = bins.items.len();
    stats.bin_ms = ms(t);

    let t = Instant::now();
    let mut data = vec![Fragment::EMPTY; total as usize];
    let far = view.far as f64;
    let method = if opts.min_separation > 0.0 {
        LayerMethod::Peel
    } else {
        opts.method
    };
    let fragments: usize = data
        .par_chunks_mut(per_tile)
        .enumerate()
        .map(|(ti, slots)| {
            let (tx, ty) = (ti as u32 % tiles_x, ti as u32 / tiles_x);
            let rect = Rect {
                x0: tx * TILE,
                y0: ty * TILE,
                x1: ((tx + 1) * TILE).min(view.width),
                y1: ((ty + 1) * TILE).min(view.height),
            };
            let items = bins.tile(ti);
            let pitch = TILE as usize;
            match method {
                LayerMethod::KBuffer => {
                    tile::for_each_fragment(&tris, items, rect, far, |x, y, f| {
                        let base = (y as usize * pitch + x as usize) * layers;
                        tile::kbuffer_insert(&mut slots[base..base + layers], f);
                    });
                }
                LayerMethod::Peel => {
                    let delta = opts.min_separation;
                    tile::peel(&tris, items, rect, far, pitch, layers, delta, slots);
                }
            }
            slots.iter().filter(|f| !f.is_empty()).count()
        })
        .sum();
    stats.fragments = fragments;
    stats.raster_ms = ms(t);
    let frags = Fragments {
        width: view.width,
        height: view.height,
        layers,
        tiles_x,
        data,
    };
    stats.scratch_bytes = tris.len() * size_of::<RasterTri>() + bins.bytes() + frags.bytes();
    Ok((frags, stats))
}
