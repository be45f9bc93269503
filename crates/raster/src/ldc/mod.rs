//! Layered depth cubes (Lischinski & Rappoport 1998; built and traced on the GPU in Bürger,
//! Krüger & Westermann 2007, "Layered depth cubes for GPU ray tracing"): three orthographic
//! layered depth images along the axes of the scene's bounding box, with all layers (the full
//! depth complexity), each sample holding depth, normal, colour and primitive id (§1.2), plus a
//! coarse min/max depth grid per LDI (the two-level LDC, §1.3).
//!
//! **Assignment (§1.2, §2.1, Fig. 5).** Every triangle is rasterized only into the LDI of the
//! direction "most perpendicular" to it: the axis `argmax(|n.x|, |n.y|, |n.z|)` of its
//! geometric normal ([`dominant_axis`]). Ties go to the lower axis (X before Y before Z); a
//! degenerate triangle (zero or non-finite normal) goes to X — it has no area, so it yields no
//! samples and no ray hits it. So every triangle is in exactly one LDI, and its samples are
//! stored once; an LDI never sees a triangle within `acos(1/√3) ≈ 54.7°` of edge-on.
//!
//! **Geometry.** The box is the mesh bounds padded by `padding` times its longest side on every
//! side. LDI `a` (0 = X, 1 = Y, 2 = Z) looks along `+a`; its image axes are `u = (a + 1) % 3`
//! (columns, growing right) and `v = (a + 2) % 3` (rows, growing down), so the centre of pixel
//! `(x, y)` is the ray `o + t e_a` with `o_u = min_u + (x + 1/2) s`, `o_v = min_v + (y + 1/2) s`,
//! `o_a = min_a`, and a sample's depth is its `t` (distance from the box's `min_a` face).
//! Pixels are square, of side `s = longest side / resolution`: `resolution` is the number of
//! pixels along the box's longest side; the other sides get `ceil(side / s)` pixels (the image
//! plane covers the box face, overhanging by less than a pixel at the far edges).
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `block` | u32 | 8 | coarse grid block edge `n` in pixels (§1.3) |
//! | `padding` | f32 | 1e-3 | box padding, fraction of the longest side |
//! | `max_samples` | u64 | 2^28 | per-LDI bound on samples: the build fails instead of allocating more |
//!
//! **Memory:** three [`AllLayersCapture`]s (flat CSR arrays, [`AllLayersCapture::bytes`]) and
//! three [`CoarseGrid`]s; [`LayeredDepthCube::bytes`] is their sum.

pub mod coarse;

use std::time::Instant;

use glam::{DMat4, DVec4, Vec3};
use parallax_core::math::Aabb;
use parallax_scene::{Scene, TriangleMesh};
use rayon::prelude::*;
use serde::Serialize;

pub use coarse::CoarseGrid;

use crate::capture::{AllLayersCapture, AllLayersStats, all_layers, capture_all_layers};
use crate::raster::{Projection, RasterError, View, ms};

/// Largest allowed resolution (pixels along the longest box side).
pub const MAX_RESOLUTION: u32 = 1 << 14;

/// Build options (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LdcOptions {
    pub block: u32,
    pub padding: f32,
    pub max_samples: u64,
}

impl Default for LdcOptions {
    fn default() -> Self {
        Self {
            block: 8,
            padding: 1e-3,
            max_samples: all_layers::DEFAULT_MAX_SAMPLES,
        }
    }
}

/// The LDI axis of triangle `prim`: the largest `|component|` of its geometric normal, ties to
/// the lower axis, degenerate triangles to 0 (see the module docs).
#[inline]
pub fn dominant_axis(mesh: &TriangleMesh, prim: usize) -> usize {
    let [a, b, c] = mesh.triangle(prim);
    let n = (b - a).cross(c - a).abs();
    if n.y > n.x && n.y >= n.z {
        1
    } else if n.z > n.x && n.z > n.y {
        2
    } else {
        0
    }
}

/// Stats of one LDI.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LdiStats {
    pub axis: usize,
    /// Triangles assigned to this LDI.
    pub triangles: usize,
    pub capture: AllLayersStats,
    pub coarse_bytes: usize,
    pub coarse_ms: f64,
}

/// Sizes and per-stage times of an LDC build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LdcStats {
    pub resolution: u32,
    pub block: u32,
    pub box_min: Vec3,
    pub box_max: Vec3,
    /// Pixel side in metres.
    pub pixel_size: f32,
    pub triangles: usize,
    pub samples: usize,
    pub max_depth_complexity: u32,
    pub bytes: usize,
    /// Dominant-axis assignment of all triangles.
    pub assign_ms: f64,
    pub ldis: [LdiStats; 3],
    pub total_ms: f64,
}

/// One axis of the cube: its all-layers LDI and coarse grid.
#[derive(Clone, Debug)]
pub struct Ldi {
    /// 0 = X, 1 = Y, 2 = Z; the LDI looks along `+axis`.
    pub axis: usize,
    pub capture: AllLayersCapture,
    pub coarse: CoarseGrid,
}

impl Ldi {
    /// Bytes of the samples and the coarse grid.
    pub fn bytes(&self) -> usize {
        self.capture.bytes() + self.coarse.bytes()
    }
}

/// Three orthographic all-layers LDIs along the box axes (see the module docs).
#[derive(Clone, Debug)]
pub struct LayeredDepthCube {
    /// The padded box.
    pub bounds: Aabb,
    /// Pixel side (metres).
    pub pixel_size: f32,
    pub ldis: [Ldi; 3],
    pub stats: LdcStats,
}

/// The image axes `(u, v)` of LDI `axis`.
#[inline]
pub fn image_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// The orthographic view of LDI `axis` of `bounds` with square pixels of side `s`.
pub fn ldi_view(bounds: &Aabb, s: f32, axis: usize) -> Result<View, RasterError> {
    let (u, v) = image_axes(axis);
    let ext = bounds.extent();
    let cells = |e: f32| ((e / s).ceil() as u32).max(1);
    let (width, height) = (cells(ext[u]), cells(ext[v]));
    parallax_core::image::check_size(width, height).map_err(RasterError::Size)?;
    let (lo, s) = (bounds.min.as_dvec3(), s as f64);
    let (sw, sh) = (width as f64 * s, height as f64 * s);
    let e = |i: usize, k: f64| {
        let mut r = DVec4::ZERO;
        r[i] = k;
        r
    };
    // Rows of world -> clip: x = 2 (p_u - min_u) / (W s) - 1, y = 1 - 2 (p_v - min_v) / (H s),
    // d = p_a - min_a, w = 1 (see View's module docs for the screen map).
    let rows = [
        e(u, 2.0 / sw) + e(3, -2.0 * lo[u] / sw - 1.0),
        e(v, -2.0 / sh) + e(3, 1.0 + 2.0 * lo[v] / sh),
        e(axis, 1.0) + e(3, -lo[axis]),
        e(3, 1.0),
    ];
    let m = DMat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose();
    if !m.is_finite() {
        return Err(RasterError::InvalidView("non-finite LDC box".into()));
    }
    let mut forward = Vec3::ZERO;
    forward[axis] = 1.0;
    Ok(View {
        width,
        height,
        world_to_clip: m,
        projection: Projection::Orthographic { forward },
        near: 0.0,
        far: f32::INFINITY,
    })
}

impl LayeredDepthCube {
    /// Builds the LDC of `scene` with `resolution` pixels along the padded box's longest side.
    /// Errors on an empty or non-finite scene, a resolution outside `1..=2^14`, invalid options
    /// or an LDI exceeding `opts.max_samples`.
    pub fn build(scene: &Scene, resolution: u32, opts: &LdcOptions) -> Result<Self, RasterError> {
        let start = Instant::now();
        let mesh = &scene.mesh;
        if resolution == 0 || resolution > MAX_RESOLUTION {
            return Err(RasterError::InvalidOptions(format!(
                "resolution must be in 1..={MAX_RESOLUTION}, got {resolution}"
            )));
        }
        if opts.block == 0 || opts.block > MAX_RESOLUTION {
            return Err(RasterError::InvalidOptions(format!(
                "block must be in 1..={MAX_RESOLUTION}, got {}",
                opts.block
            )));
        }
        if !(opts.padding.is_finite() && opts.padding >= 0.0 && opts.padding <= 1.0) {
            return Err(RasterError::InvalidOptions(format!(
                "padding must be in [0, 1], got {}",
                opts.padding
            )));
        }
        crate::raster::check_mesh(mesh)?;
        let raw = mesh.bounds();
        let longest = raw.extent().max_element();
        if raw.is_empty() || !(raw.min.is_finite() && raw.max.is_finite()) {
            return Err(RasterError::InvalidMesh(
                "the scene has no finite bounding box".into(),
            ));
        }
        // Padding keeps surfaces off the image plane (depth > 0) and gives flat scenes depth.
        let pad = (opts.padding * longest).max(1e-6 * (1.0 + raw.max.abs().max_element()));
        let bounds = Aabb::new(raw.min - pad, raw.max + pad);
        let s = bounds.extent().max_element() / resolution as f32;

        let t = Instant::now();
        let axis_of: Vec<u8> = (0..mesh.indices.len())
            .into_par_iter()
            .map(|i| dominant_axis(mesh, i) as u8)
            .collect();
        let mut counts = [0usize; 3];
        for &a in &axis_of {
            counts[a as usize] += 1;
        }
        let assign_ms = ms(t);

        let build = |axis: usize| -> Result<Ldi, RasterError> {
            let view = ldi_view(&bounds, s, axis)?;
            let filter = |p: u32| axis_of[p as usize] as usize == axis;
            let capture = capture_all_layers(scene, &view, Some(&filter), opts.max_samples)?;
            let coarse = CoarseGrid::build(&capture, opts.block);
            Ok(Ldi {
                axis,
                capture,
                coarse,
            })
        };
        let mut ldis = Vec::with_capacity(3);
        let mut ldi_stats = [LdiStats::default(); 3];
        for (axis, st) in ldi_stats.iter_mut().enumerate() {
            let t = Instant::now();
            let ldi = build(axis)?;
            let coarse_ms = ms(t) - ldi.capture.stats.total_ms;
            *st = LdiStats {
                axis,
                triangles: counts[axis],
                capture: ldi.capture.stats,
                coarse_bytes: ldi.coarse.bytes(),
                coarse_ms: coarse_ms.max(0.0),
            };
            ldis.push(ldi);
        }
        let ldis: [Ldi; 3] = ldis.try_into().expect("three LDIs");
        let stats = LdcStats {
            resolution,
            block: opts.block,
            box_min: bounds.min,
            box_max: bounds.max,
            pixel_size: s,
            triangles: mesh.indices.len(),
            samples: ldis.iter().map(|l| l.capture.len()).sum(),
            max_depth_complexity: ldis
                .iter()
                .map(|l| l.capture.stats.max_depth_complexity)
                .max()
                .unwrap_or(0),
            bytes: ldis.iter().map(Ldi::bytes).sum(),
            assign_ms,
            ldis: ldi_stats,
            total_ms: ms(start),
        };
        Ok(Self {
            bounds,
            pixel_size: s,
            ldis,
            stats,
        })
    }

    /// Bytes of the three LDIs and their coarse grids.
    pub fn bytes(&self) -> usize {
        self.ldis.iter().map(Ldi::bytes).sum()
    }

    /// The world-space origin of the ray of pixel `(x, y)` of LDI `axis` (on the box's `min`
    /// face along `axis`; the ray runs along `+axis`).
    pub fn pixel_ray_origin(&self, axis: usize, x: u32, y: u32) -> Vec3 {
        let (u, v) = image_axes(axis);
        let mut o = self.bounds.min;
        o[u] += (x as f32 + 0.5) * self.pixel_size;
        o[v] += (y as f32 + 0.5) * self.pixel_size;
        o
    }
}
