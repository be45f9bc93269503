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
//! **Geometry.** The box is the mesh bounds (intersected with the region of interest `roi`
//! when one is given) padded by `padding` times its longest side on every side. LDI `a`
//! (0 = X, 1 = Y, 2 = Z) looks along `+a`; its image axes are `u = (a + 1) % 3` (columns,
//! growing right) and `v = (a + 2) % 3` (rows, growing down), so the centre of pixel `(x, y)`
//! is the ray `o + t e_a` with `o_u = min_u + (x + 1/2) s`, `o_v = min_v + (y + 1/2) s`,
//! `o_a = min_a`, and a sample's depth is its `t` (distance from the box's `min_a` face).
//! Pixels are square, of side `s = longest side / resolution`: `resolution` is the number of
//! pixels along the padded box's longest side; the other sides get `ceil(side / s)` pixels,
//! and the box grows to whole pixels (its `max` faces move out by less than a pixel), so the
//! LDI images cover its faces exactly. Geometry outside the box is clipped (the image edges,
//! and the far plane of LDI `a` at the box's `max_a` face).
//!
//! **Region of interest.** An interior whose bounds are dominated by a huge ground quad (the
//! classroom's 222 m plane) spreads the pixels over the whole quad; `roi` fits the cube to the
//! part of the scene the secondary rays need. Surfaces outside it are not captured: rays that
//! would hit them leave the cube and see the environment.
//!
//! **Sample normals** are the shading normals oriented like the triangle's winding (its
//! geometric normal), not towards the LDI's viewer: a tracer turns them to face its ray, and
//! the winding tells a refracting ray whether it enters or leaves a solid. Each sample also
//! keeps its triangle's geometric normal ([`Ldi::geometric_normal`]): the plane it lies in.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `block` | u32 | 16 | coarse grid block edge `n` in pixels (§1.3; the paper does not give its `n`) |
//! | `padding` | f32 | 1e-3 | box padding, fraction of the longest side |
//! | `max_samples` | u64 | 2^28 | per-LDI bound on samples: the build fails instead of allocating more |
//! | `max_layers` | u32 | 1024 | bound on the depth complexity (layers) of any LDI pixel: the build fails beyond it |
//! | `roi` | `Option<[Vec3; 2]>` | none | region of interest `[min, max]`: the cube covers its intersection with the scene bounds |
//!
//! **Build stages** ([`LdcStats`]): `assign_ms` (dominant axes of all triangles), `peel_ms`
//! (the three all-layers captures: the counterpart of the paper's depth peeling, §1.2),
//! `orient_ms` (sample normals to the winding, geometric normals), `grid_ms` (the three coarse grids, §1.3).
//!
//! **Memory:** three [`AllLayersCapture`]s (flat CSR arrays, [`AllLayersCapture::bytes`]) and
//! three [`CoarseGrid`]s; [`LayeredDepthCube::bytes`] is their sum.

mod build;
pub mod coarse;

use glam::{DMat4, DVec4, Vec3};
use parallax_core::math::Aabb;
use parallax_scene::TriangleMesh;
use serde::Serialize;

pub use coarse::CoarseGrid;

use crate::capture::{AllLayersCapture, AllLayersStats, all_layers};
use crate::raster::{Projection, RasterError, View};

/// Largest allowed resolution (pixels along the longest box side).
pub const MAX_RESOLUTION: u32 = 1 << 14;

/// Default coarse block edge in pixels (measured in `docs/notes/ldc.md`).
pub const DEFAULT_BLOCK: u32 = 16;

/// Default bound on the layers (depth complexity) of an LDI pixel.
pub const DEFAULT_MAX_LAYERS: u32 = 1024;

/// Build options (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LdcOptions {
    pub block: u32,
    pub padding: f32,
    pub max_samples: u64,
    pub max_layers: u32,
    /// Region of interest `[min, max]` (world units), `None` for the whole scene.
    pub roi: Option<[Vec3; 2]>,
}

impl Default for LdcOptions {
    fn default() -> Self {
        Self {
            block: DEFAULT_BLOCK,
            padding: 1e-3,
            max_samples: all_layers::DEFAULT_MAX_SAMPLES,
            max_layers: DEFAULT_MAX_LAYERS,
            roi: None,
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

/// Sizes and per-stage times of an LDC build (stages: see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LdcStats {
    pub resolution: u32,
    pub block: u32,
    pub box_min: Vec3,
    pub box_max: Vec3,
    /// True when the box was fitted to a region of interest.
    pub roi: bool,
    /// Pixel side in metres.
    pub pixel_size: f32,
    pub triangles: usize,
    pub samples: usize,
    /// Largest number of samples of one pixel over the three LDIs (the layers the cube needs).
    pub max_depth_complexity: u32,
    pub bytes: usize,
    /// Dominant-axis assignment of all triangles.
    pub assign_ms: f64,
    /// The three all-layers captures (depth peeling's counterpart).
    pub peel_ms: f64,
    /// Sample normals turned to the triangles' winding.
    pub orient_ms: f64,
    /// The three coarse grids.
    pub grid_ms: f64,
    pub ldis: [LdiStats; 3],
    pub total_ms: f64,
}

/// One axis of the cube: its all-layers LDI and coarse grid.
#[derive(Clone, Debug)]
pub struct Ldi {
    /// 0 = X, 1 = Y, 2 = Z; the LDI looks along `+axis`.
    pub axis: usize,
    pub capture: AllLayersCapture,
    /// Per sample the unit geometric normal of its triangle (winding orientation): the plane
    /// the sample lies in, for tracers that intersect samples as planar splats.
    pub geometric_normal: Vec<Vec3>,
    pub coarse: CoarseGrid,
}

impl Ldi {
    /// Bytes of the samples, their geometric normals and the coarse grid.
    pub fn bytes(&self) -> usize {
        self.capture.bytes() + self.geometric_normal.len() * size_of::<Vec3>() + self.coarse.bytes()
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

/// The orthographic view of LDI `axis` of `bounds` with square pixels of side `s`; depths run
/// from the box's `min_axis` face (near plane 0) to its `max_axis` face (far plane).
pub fn ldi_view(bounds: &Aabb, s: f32, axis: usize) -> Result<View, RasterError> {
    let (u, v) = image_axes(axis);
    let ext = bounds.extent();
    // A side of whole pixels (up to rounding) keeps its count.
    let cells = |e: f32| (((e / s) * (1.0 - 1e-6)).ceil() as u32).max(1);
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
        far: ext[axis],
    })
}

impl LayeredDepthCube {
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
