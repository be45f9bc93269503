//! The two-level layered depth cube tracer (Bürger, Krüger & Westermann 2007, "Layered depth
//! cubes for GPU ray tracing", §1.3 "Two Level LDC" and §1.4 "Ray Traversal") behind the
//! world-space interface [`WorldTracer`]: secondary rays traced through the three LDIs that
//! [`parallax_raster::ldc`] captured, never through the triangles.
//!
//! **Traversal (§1.4).** The ray is clipped to the cube's box. Then, per LDI direction:
//! 1. the ray is projected into the LDI raster (pixel coordinates `u, v` and depth `z` from the
//!    box face, all affine in `t`);
//! 2. a DDA (Amanatides & Woo 1987) walks the coarse `n x n` blocks the projected ray crosses;
//!    for each it compares the ray's depth span over the block with the block's depth bounds
//!    over all layers, widened by `eps` and the splat margin;
//! 3. on overlap a fine DDA walks the block's pixels and tests the ray against every layer
//!    sample of each pixel (*sample test* below); a pixel whose depth range (or, with one or
//!    two samples, whose samples) the ray's span misses is passed without reading its samples;
//! 4. the first pixel with a hit ends the direction: its hit is the nearest sample hit of the
//!    pixel, ordered by the hit's parameter clamped to the pixel's interval, so pixels visited
//!    later never hold an earlier one.
//!
//! Directions run one after another, the most ray-aligned first (it crosses the fewest pixels);
//! a hit in one shortens the ray for the next ("we can change the end point of the ray to the
//! position of that intersection"). A miss in all three is a miss: the consumer looks up the
//! environment (the paper's box-exit lookup).
//!
//! **Coarse bounds.** The paper's coarse texel holds one `[min, max]` over all layers of its
//! block (`intervals = 1`, exactly [`parallax_raster::ldc::CoarseGrid`]). In a closed room a
//! block always holds a floor and a ceiling, so that interval spans the whole room and the
//! coarse level skips nothing; with `intervals = k` a block keeps up to `k` disjoint depth
//! intervals that cover its samples (split at the widest gaps, `layout.rs`). Both are exact
//! filters: the answers do not depend on `block` or `intervals`, only the work does.
//!
//! **Sample test.** With `test = Depth` a sample is the paper's: depth `d` constant over its
//! pixel, a hit when `|ray depth - d| < eps` somewhere over the pixel (the ray's `t` interval
//! inside the pixel's column), at the ray's point where its depth reaches `d` (clamped to the
//! pixel). The paper's scenes are about a unit across, so its `eps = 0.001` is about a pixel
//! of a 1024² LDI; on a 15 cm model it is 6 pixels thick, on a 35 m one 1/30 of a pixel, and
//! rays slip between the samples of a tilted surface once a pixel is wider than `2 eps`. With
//! `test = Plane` (default) a sample is a planar splat: the plane of its triangle (from the
//! triangle's geometric normal) over its pixel's square, and the paper's tolerance is a
//! distance in space — the ray hits the sample where it crosses that plane, if the crossing
//! lies inside the square or within `eps` of the sample's point ("the distance between a point
//! on the secondary ray and a fragment coded in the LDC was less than 0.001", §3). Splats of
//! neighbouring pixels tile a surface without gaps in depth, and a hit's position is the
//! crossing itself (measured in `docs/notes/ldc.md`). Where two neighbouring splats lie in
//! different planes (a crease of the mesh, a pixel whose centre falls on another triangle of
//! a finely tessellated surface) a ray can cross each plane over the other's square and slip
//! through both; the square grown by `overlap` pixels on every side closes that crack (the
//! grown splats overlap, and the first one the walk meets answers).
//!
//! **Self-intersection.** A secondary ray starts on (a hair above) the surface it leaves.
//! A sample is accepted only if the ray crosses its plane ahead of its start (`t > t_min`):
//! a ray leaving a surface recedes from the planes it lies on. Its neighbouring splats stick
//! out by up to a pixel where the surface bends or a triangle ends (a splat covers its whole
//! pixel), so hits nearer to the origin than `skip` pixels are ignored too. (The paper does not
//! say how it avoids self-hits; both rules are ours, the same in both sample tests.)
//!
//! **Invariants:**
//! - `screen` never reads the scene: only the captured LDIs (depth, normals, albedo,
//!   primitive);
//! - every loop is bounded: coarse DDA by `blocks_x + blocks_y + 2` steps, fine DDA by
//!   `2 n + 2` steps per block, one pass over the samples of a pixel; a ray cut by a bound
//!   counts in [`WorldStats::truncated`]; invalid rays (NaN, zero direction, NaN or empty
//!   `t` range) miss;
//! - hits are [`HitSurface::Sampled`] with the sample's shading normal (oriented like its
//!   triangle's winding), albedo and primitive id (the material is the primitive's:
//!   `material_id` is [`NO_ID`]); `ray.t_min < t < ray.t_max`, `position = ray.at(t)`;
//! - `occluded(ray)` is `closest_hit(ray).is_some()`.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `eps` | f32 | 0.001 | hit tolerance in world units (the paper's, §3) |
//! | `test` | [`SampleTest`] | `Plane` | planar splats, or the paper's constant-depth samples |
//! | `intervals` | u32 | 8 | depth intervals per coarse block (1 = the paper's `[min, max]`), at most [`MAX_INTERVALS`] |
//! | `skip` | f32 | 0.5 | hits nearer to the ray's origin than this many LDI pixels are ignored, in `[0, 16]` |
//! | `overlap` | f32 | 0.1 | a planar splat reaches this many pixels past its pixel's square on every side, in `[0, 1]` |
//!
//! **Memory:** the cube ([`LayeredDepthCube::bytes`]: offsets, depth, normals, albedo,
//! primitive id per sample, coarse grids) plus the tracer's block-major copy (`layout.rs`:
//! 12 bytes per pixel, 16 per sample — the splat `(depth, dz/du, dz/dv)` and the capture
//! index — and `8 intervals` per block; [`LdcTracer::tracer_bytes`]).

mod layout;

pub use layout::MAX_SLOPE;
mod traverse;

use parallax_core::{HitSurface, NO_ID, Ray, SampledSurface, WorldHit, WorldStats, WorldTracer};
use parallax_raster::ldc::{LayeredDepthCube, image_axes};
use rayon::prelude::*;
use serde::Serialize;

/// Default hit tolerance in world units (the paper's 0.001).
pub const DEFAULT_EPS: f32 = 1e-3;

/// Default number of depth intervals per coarse block.
pub const DEFAULT_INTERVALS: u32 = 8;

/// Default distance from a ray's origin, in LDI pixels, within which hits are ignored.
pub const DEFAULT_SKIP: f32 = 0.5;

/// Default growth of a planar splat past its pixel's square, in pixels on every side.
pub const DEFAULT_OVERLAP: f32 = 0.1;

/// Largest number of depth intervals per coarse block.
pub const MAX_INTERVALS: u32 = 64;

/// How a ray is tested against a layer sample (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum SampleTest {
    /// The paper's: the sample's depth, constant over its pixel.
    Depth,
    /// The sample's tangent plane over its pixel.
    #[default]
    Plane,
}

impl SampleTest {
    pub fn parse(s: &str) -> Result<Self, LdcTraceError> {
        match s {
            "depth" => Ok(Self::Depth),
            "plane" => Ok(Self::Plane),
            _ => Err(LdcTraceError(format!(
                "unknown LDC sample test {s:?} (expected depth or plane)"
            ))),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Depth => "depth",
            Self::Plane => "plane",
        }
    }
}

/// Tracer options (module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LdcTraceOptions {
    pub eps: f32,
    pub test: SampleTest,
    pub intervals: u32,
    pub skip: f32,
    pub overlap: f32,
}

impl Default for LdcTraceOptions {
    fn default() -> Self {
        Self {
            eps: DEFAULT_EPS,
            test: SampleTest::default(),
            intervals: DEFAULT_INTERVALS,
            skip: DEFAULT_SKIP,
            overlap: DEFAULT_OVERLAP,
        }
    }
}

/// Invalid tracer options.
#[derive(Debug, thiserror::Error)]
#[error("invalid LDC tracer options: {0}")]
pub struct LdcTraceError(pub String);

/// What the traversal reads of one LDI, in flat arrays.
#[derive(Clone, Debug)]
struct LdiTrace {
    axis: usize,
    /// Image axes (world components of columns and rows).
    u: usize,
    v: usize,
    width: u32,
    height: u32,
    block: u32,
    blocks_x: u32,
    blocks_y: u32,
    /// Pixels and splats in block-major order (slopes in world units per world unit).
    layout: layout::BlockLayout,
    /// Largest depth change of a splat from its pixel centre to where a ray may cross it
    /// (world units): `max((1/2 + overlap) s, eps) * max(|dz/du| + |dz/dv|)`; 0 for the depth test.
    margin: f32,
}

/// The LDC behind [`WorldTracer`] (module docs).
#[derive(Clone, Debug)]
pub struct LdcTracer {
    ldc: LayeredDepthCube,
    opts: LdcTraceOptions,
    ldis: [LdiTrace; 3],
    /// Tracer set-up time (splats and margins), ms.
    pub build_ms: f64,
}

impl LdcTracer {
    /// A tracer over `ldc`. Errors when `eps` is not a finite positive number.
    pub fn new(ldc: LayeredDepthCube, opts: LdcTraceOptions) -> Result<Self, LdcTraceError> {
        if !(opts.eps.is_finite() && opts.eps > 0.0) {
            return Err(LdcTraceError(format!(
                "eps must be a finite number > 0, got {}",
                opts.eps
            )));
        }
        if !(opts.skip.is_finite() && (0.0..=16.0).contains(&opts.skip)) {
            return Err(LdcTraceError(format!(
                "skip must be in [0, 16] pixels, got {}",
                opts.skip
            )));
        }
        if !(opts.overlap.is_finite() && (0.0..=1.0).contains(&opts.overlap)) {
            return Err(LdcTraceError(format!(
                "overlap must be in [0, 1] pixels, got {}",
                opts.overlap
            )));
        }
        if opts.intervals == 0 || opts.intervals > MAX_INTERVALS {
            return Err(LdcTraceError(format!(
                "intervals must be in 1..={MAX_INTERVALS}, got {}",
                opts.intervals
            )));
        }
        let start = std::time::Instant::now();
        let s = ldc.pixel_size;
        let ldis = [0, 1, 2].map(|axis| {
            let ldi = &ldc.ldis[axis];
            let cap = &ldi.capture;
            let layout = layout::BlockLayout::build(ldi, opts.intervals as usize);
            let spread = match opts.test {
                SampleTest::Depth => 0.0,
                SampleTest::Plane => layout
                    .splats
                    .par_iter()
                    .map(|p| p[1].abs() + p[2].abs())
                    .reduce(|| 0.0, f32::max),
            };
            let (u, v) = image_axes(axis);
            LdiTrace {
                axis,
                u,
                v,
                width: cap.width(),
                height: cap.height(),
                block: ldi.coarse.block,
                blocks_x: ldi.coarse.blocks_x,
                blocks_y: ldi.coarse.blocks_y,
                layout,
                margin: ((0.5 + opts.overlap) * s).max(opts.eps) * spread,
            }
        });
        Ok(Self {
            ldc,
            opts,
            ldis,
            build_ms: start.elapsed().as_secs_f64() * 1e3,
        })
    }

    /// The captured cube.
    pub fn cube(&self) -> &LayeredDepthCube {
        &self.ldc
    }

    pub fn options(&self) -> &LdcTraceOptions {
        &self.opts
    }

    /// Bytes of the cube and the tracer's block-major copy ([`Self::tracer_bytes`]).
    pub fn bytes(&self) -> usize {
        self.ldc.bytes() + self.tracer_bytes()
    }

    /// Bytes of the tracer's block-major pixels and splats alone.
    pub fn tracer_bytes(&self) -> usize {
        self.ldis.iter().map(|l| l.layout.bytes()).sum()
    }

    /// The hit of splat `splat` of LDI `axis` at parameter `t`.
    fn hit(&self, ray: &Ray, axis: usize, splat: usize, t: f32) -> WorldHit {
        let cap = &self.ldc.ldis[axis].capture;
        let index = self.ldis[axis].layout.sample[splat] as usize;
        WorldHit {
            t,
            position: ray.at(t),
            prim: cap.primitive_id[index],
            barycentrics: glam::Vec2::ZERO,
            surface: HitSurface::Sampled(SampledSurface {
                normal: cap.normal[index],
                albedo: cap.albedo[index],
                material_id: NO_ID,
            }),
        }
    }
}

impl WorldTracer for LdcTracer {
    fn name(&self) -> &str {
        "ldc"
    }

    fn is_exact(&self) -> bool {
        false
    }

    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit> {
        stats.rays += 1;
        let (axis, index, t) = self.trace(ray, false, stats)?;
        Some(self.hit(ray, axis, index, t))
    }

    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool {
        stats.rays += 1;
        self.trace(ray, true, stats).is_some()
    }
}
