//! The adaptive quad-tree of Widmer et al. 2015, "An Adaptive Acceleration Structure for
//! Screen-space Ray Tracing" (§3-§4), as a [`crate::ScreenTracer`].
//!
//! - [`node`]: the 64-bit node of §3.4 (plane / AABB, tag in the sign bit);
//! - [`build`]: [`QuadTree`], one layer — per-pixel planes as leaves (§3.2) and bottom-up
//!   adaptive pruning with the three conditions and the least-squares proxy plane (§3.3);
//!   `leaf_lanes`: a leaf's plane map and node in SSE2 lanes (same bits, x86_64);
//! - [`merge`]: one pruning step (proxy plane or conservative AABB); `merge_lanes`: the same
//!   step with the four children in `Vec4` lanes (same bits); `merge_rows`: a level's row
//!   with four parents in SSE2 lanes (same bits, the build's fast path over whole levels on
//!   x86_64), `merge_rows8`: eight parents in AVX2 lanes (with F16C; same bits, run-time
//!   detection);
//!   `leaves`: the leaves a row at a time, `leaf_avx2` four pixels in AVX2 lanes (with F16C);
//!   `eff_lanes`: a row of effective levels sixteen nodes per step (SSE2, same bytes);
//!   `fixpoint`: the cascade's pruning fixed point computed incrementally (same results as the
//!   definition in `prune`, which [`QuadTreeTracer::build_reference`] runs);
//! - [`traverse`]: the stackless traversal of §4 (exact plane hits, child by entry
//!   quadrant, successor by exit edge, restart `findMSB((Qx^Qx*)|(Qy^Qy*))` levels up —
//!   Frisken & Perry 2002 — crack dilation, occlusion-volume extrusion, hard step bound);
//!   `setup`: its per-ray set-up ([`traverse::RaySetup`]);
//! - `batch`: [`QuadTreeTracer::trace_batch`], many rays in phases (clip, set-up and start,
//!   walk) with the results of one ray at a time — the per-ray set-up's latency chains of
//!   the batch's rays overlap (depth of field's lens rays, §5.2);
//! - [`cascade`]: [`QuadTreeTracer`], all layers of one reference view, with the occlusion
//!   handling of §4.1 in the two [`LayerMode`]s, and the derivation that makes cascading
//!   exact.
//!
//! **Coordinates.** Construction and tracing happen in the unit cube of [`crate::UnitCube`]
//! (§3.2). The traversal works in *grid* units (`X = x W`, `Y = y H`, pixel `(i, j)` is the
//! square `[i, i+1] x [j, j+1]`) for the node rectangles and in cube units for plane tests.
//! The ray is the straight cube segment `P(s) = p0 + s (p1 - p0)`, `s ∈ [0, 1]`, of
//! [`crate::UnitCube::clip_ray`]; results map back with [`crate::CubeSegment::world_t`].
//!
//! **Levels.** Level 0 holds one node per pixel; level `l` nodes cover `2^l x 2^l` pixels.
//! The number of levels is `min(max_levels, ceil(log2 max(W, H)) + 1)` (§3.2: "our
//! implementation caps it to 9 levels"); the top level then has several nodes. Every level is
//! one flat row-major array; the image is padded to a multiple of `2^(levels-1)` with empty
//! nodes, so non-power-of-two sizes need no special case.

//! **API.** [`QuadTreeTracer::build`] (all layers of a view; `build_ms`, `bytes`,
//! `unsafe_pixels`, `trace_layers` = result + number of layers traversed) implements
//! [`crate::ScreenTracer`]; [`QuadTree::build`] builds one layer (`bytes`, `node_count`,
//! `plane_node_count`, `effective_planes` = its brute-force twin).
//!
//! **Deviations from / additions to the paper** (its supplement is not public):
//! - the plane word stores `z_c` (the plane's `z` at the node centre) instead of an
//!   `-(P·N)` offset, and two flag bits in its lowest mantissa bits ([`node`]);
//! - the two f16 of a plane node are the plane's `z` slopes across the node's footprint
//!   instead of `N.x`, `N.y`: reconstructing `N.z` made grazing planes vertical in the cube
//!   ([`node`]);
//! - default normals are the G-buffer's ([`QuadTreeOptions::normals`]);
//! - the distance-adaptive thresholds of §6 are our definition ([`QuadTreeOptions::adaptive`]);
//! - crack dilation extends flagged planes *backwards along the ray* by
//!   [`QuadTreeOptions::crack_dilation`] pixels (an extra option field);
//! - inpainting reports the point [`INPAINT_DILATION_PX`] pixels before the occlusion entry;
//! - cascading is made exact by trigger depths for "unsafe" pixels and by never merging over
//!   them ([`cascade`], with the proof);
//! - the traversal starts at the level matching the segment's screen extent instead of the
//!   root (same result, [`traverse`]);
//! - every level is stored in full (pruned subtrees stay in the arrays but are never
//!   visited), so [`QuadTree::bytes`] is the padded pyramid (8 bytes x ~4/3 x padded
//!   pixels), while [`QuadTree::node_count`] counts the reachable nodes; a side array of one
//!   byte per pixel (the level of the pixel's effective plane node, for the traversal's
//!   start) is not counted there;
//! - construction runs on the CPU, in parallel over rows per level (rayon).
//!
//! **Invariants.** With lossless settings ([`QuadTreeOptions::lossless`]) a trace answers
//! exactly what [`crate::BruteForcePlanes`] over the decoded per-pixel planes answers (same
//! kind, layer, pixel; `t` within 1e-4), through every layer of the cascade, up to crossings
//! within 1e-3 px of a footprint edge (`tests/quadtree_*.rs`); AABB ranges are conservative, so
//! no node holding a crossed plane is skipped; every traversal ends within its step bound.
//!
//! **Parameters** ([`QuadTreeOptions`]):
//!
//! | name | type | default | meaning |
//! |---|---|---|---|
//! | `gamma_norm` | f32 | `cos(3°)` | §3.3 condition 2: merge iff every child normal is within `acos(gamma_norm)` of the proxy normal; 1 never merges |
//! | `gamma_dist` | f32 | `1e-5` | §3.3 condition 3: largest corner distance (cube `z`) between child and proxy planes; 0 never merges |
//! | `adaptive` | bool | false | §6: both thresholds grow with depth, up to [`ADAPTIVE_SCALE`] x at the far plane |
//! | `max_levels` | u32 | 9 | levels including the pixel level (§3.2 caps at 9) |
//! | `normals` | [`NormalSource`] | G-buffer | where the per-pixel plane normals come from (and flag `O`) |
//! | `mode` | [`LayerMode`] | cascade | occlusion volumes: exact cascade or single-layer inpainting (§4.1) |
//! | `crack_dilation` | f32 | 0.5 | pixels of ray travel before a flagged plane's footprint over which it is also intersected |
//!
//! Measurements, and what was tried and dropped: `docs/notes/quadtree.md`.

mod batch;
pub mod build;
pub mod cascade;
#[cfg(target_arch = "x86_64")]
mod eff_lanes;
#[cfg(target_arch = "x86_64")]
mod eff_planes_avx512;
mod fixpoint;
#[cfg(target_arch = "x86_64")]
mod leaf_avx2;
#[cfg(target_arch = "x86_64")]
mod leaf_avx512;
#[cfg(target_arch = "x86_64")]
mod leaf_lanes;
mod leaves;
mod mark_listed;
pub mod merge;
#[cfg(target_arch = "x86_64")]
mod merge_kids;
mod merge_lanes;
#[cfg(target_arch = "x86_64")]
mod merge_rows;
#[cfg(target_arch = "x86_64")]
mod merge_rows16;
#[cfg(target_arch = "x86_64")]
mod merge_rows8;
#[cfg(target_arch = "x86_64")]
mod merge_wide;
#[cfg(target_arch = "x86_64")]
mod merged_cert;
pub mod node;
mod prune;
mod setup;
#[cfg(test)]
mod test_rng;
pub mod traverse;
pub mod tree;
#[cfg(target_arch = "x86_64")]
mod trigger_avx2;
#[cfg(target_arch = "x86_64")]
mod trigger_avx512;
#[cfg(target_arch = "x86_64")]
mod trigger_lanes;

/// Whether this CPU runs the AVX-512 kernels of the build (`leaf_avx512`, `merge_rows16`,
/// `trigger_avx512`, `eff_planes_avx512`; their features: AVX-512 F, BW, DQ, VL and F16C,
/// within x86-64-v4).
#[cfg(target_arch = "x86_64")]
fn avx512_available() -> bool {
    parallax_core::cpu::x86_64_v4()
}

pub use cascade::QuadTreeTracer;
pub use node::Node;
pub use tree::QuadTree;

use crate::NormalSource;

/// How a [`QuadTreeTracer`] treats occlusion volumes (§4.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerMode {
    /// Multi-layer: only rays that enter layer `k`'s occlusion volume (before hitting layer
    /// `k`) are traced through layer `k + 1`. With lossless settings the result equals
    /// [`crate::BruteForcePlanes`] over all layers (see [`cascade`] for the proof).
    Cascade,
    /// Single-layer inpainting (§4.1): on the last layer the traversal stops at the first
    /// entry into the (slightly dilated) occlusion volume and returns
    /// [`crate::TraceResult::OcclusionVolume`] with the pixel the ray was over just before
    /// (the background side of the silhouette), so the application can take its colour.
    /// Earlier layers (if several are given) cascade as in [`LayerMode::Cascade`].
    Inpaint,
}

/// Construction and traversal settings (§3.3, §4, §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadTreeOptions {
    /// Cosine of the maximum angle between the proxy normal and a child normal for merging
    /// (§3.3 condition 2; merge iff `cos > gamma_norm`). Default `cos(3°)` (§6). `1.0` never
    /// merges.
    pub gamma_norm: f32,
    /// Maximum corner distance (cube `z` units, along the view direction `v = (0, 0, 1)` of
    /// the least-squares fit) between the children's planes and the proxy plane at the 16
    /// child footprint corners (§3.3 condition 3; merge iff `max < gamma_dist`). Default
    /// `1e-5` (§6). `0.0` never merges.
    pub gamma_dist: f32,
    /// Distance-adaptive thresholds (§6, Fig. 14/15): both tolerances grow linearly with
    /// the node's linear depth fraction `u = (d - near) / (far - near)` of the proxy's
    /// centre depth: the angle `acos(gamma_norm)` by up to `ADAPTIVE_SCALE` times (capped at
    /// 25°, the end of Fig. 15's range) and `gamma_dist` by up to `ADAPTIVE_SCALE` times
    /// (capped at `1e-1`). Lossless settings stay lossless. Default `false`.
    pub adaptive: bool,
    /// Maximum number of levels including the pixel level (§3.2 caps at 9). Default 9.
    pub max_levels: u32,
    /// Per-pixel normals. Default [`NormalSource::GBuffer`]: Widmer reconstructs normals from
    /// depth but notes (§3.2, §6 "Limitations") that G-buffer normals are more precise and
    /// avoid the cracks between unaligned planes; exact normals also make coplanar pixels
    /// merge. With `Depth { .. }` or `GBufferFlagged { .. }` the flag `O` drives
    /// [`Self::crack_dilation`]; plain `GBuffer` flags none (measured worse, see `planes.rs`).
    pub normals: NormalSource,
    /// Occlusion handling across layers. Default [`LayerMode::Cascade`] (exact).
    pub mode: LayerMode,
    /// Crack dilation (§3.2 / §4) in pixels: a plane flagged `O` is also intersected over the
    /// last `crack_dilation` pixels of ray travel *before* it enters the plane's footprint,
    /// which masks the cracks between unaligned neighbouring planes. Only flagged planes are
    /// affected ([`NormalSource::GBuffer`] flags none). Default 0.5. Not part of the paper's
    /// parameter list; set 0 for results identical to brute force with depth normals.
    pub crack_dilation: f32,
}

/// §6: the adaptive thresholds grow up to this factor at the far plane.
pub const ADAPTIVE_SCALE: f32 = 10.0;

/// Inpaint mode: the occlusion volume is dilated by this many pixels of ray travel (§4.1,
/// "a slightly dilated occlusion volume").
pub const INPAINT_DILATION_PX: f32 = 1.0;

impl Default for QuadTreeOptions {
    fn default() -> Self {
        Self {
            gamma_norm: 3f32.to_radians().cos(),
            gamma_dist: 1e-5,
            adaptive: false,
            max_levels: 9,
            normals: NormalSource::GBuffer,
            mode: LayerMode::Cascade,
            crack_dilation: 0.5,
        }
    }
}

impl QuadTreeOptions {
    /// Settings under which pruning never merges (`gamma_norm = 1`, `gamma_dist = 0`): the
    /// tree's leaves are exactly the (quantised) per-pixel planes.
    pub fn lossless() -> Self {
        Self {
            gamma_norm: 1.0,
            gamma_dist: 0.0,
            ..Self::default()
        }
    }
}
