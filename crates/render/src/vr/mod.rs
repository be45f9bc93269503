//! HVVR (Hunt et al. 2018, "Hierarchical Visibility for Virtual Reality"): primary visibility by
//! ray casting that shares traversal across thousands of coherent rays (issue 5).
//!
//! The seam between the stages:
//! - [`samples`]: a [`SampleSet`] — any sample pattern a headset needs (grid, per-channel lens
//!   distortion, foveated, wide FoV, depth of field); every sample owns `spp` subsample rays
//!   generated just in time from its film position and footprint (§5.1, §5.5);
//! - [`visibility`]: the [`VisibilityBuffer`] every visibility method fills — the closest
//!   triangle of every subsample ray. The beam caster and the per-ray BVH baseline fill the
//!   same buffer, so they are compared sample by sample, and shading/resolve consumes either.
//!
//! The beam caster:
//! - [`patterns`]: the sample patterns of §2 as [`SampleSet`] constructors;
//! - [`hierarchy`]: tiles (<= 128 samples) and blocks (<= 64 tiles) with bounding beams (§5);
//! - [`cast()`]: block cull, tile cull and sample testing (§5.3-5.5): [`packet`] (four rays
//!   per SIMD op, the default) and [`intersect`] (one ray at a time, the fallback for packets
//!   whose rays need different watertight permutations); the culling itself lives in
//!   `parallax_bvh::beam`, the beam in `parallax_core::math::Beam`.
//!
//! **Exactness.** Every kernel performs, per subsample ray, the f32 operations of the BVH's own
//! watertight leaf test with the same tie-break, on rays bit-identical to
//! [`SampleSet::subsample_ray`], and the culling is conservative, so the caster's buffer equals
//! [`trace_per_ray`]'s subsample for subsample (tests/vr_cast.rs: agreement 1.0 and equal `t`
//! on atrium and cornell for grid, per-channel distortion, foveated, 210 x 130 fisheye,
//! thin-lens DoF and stereo, spp 1 and 4).
//!
//! **Measured** (`cargo run --release -p parallax-render --example vr_speed`, atrium 49k
//! triangles, stereo 1080 x 1200 per eye = 2160 x 1200, 4-lane kernel, 2 threads on a 2-core VM
//! shared with other jobs (load 1.5-9), so absolute rates swing 3x between runs; speed-up =
//! beam caster / per-ray `trace_per_ray` on the same rays in the same process; four full runs):
//! spp 1: 1.6-2.8x, spp 8: 2.4-3.6x, spp 16: 2.2-3.1x (3.3x and 6.1x in two spp-16-only runs at
//! lower load), spp 32: 2.6-4.8x; best beam rate 26 Mrays/s (spp 16). The aim of 5x at
//! spp 16 is **not** reliably reached. Where the time
//! goes: the sample test is ~95% of the caster's CPU time (block cull < 1%, tile cull 2-5%);
//! per packet of four rays ~6.3 leaf-box slab tests and ~5.2 triangle tests, plus the ray
//! generation and shear set-up (~18% of the packet kernel's perf samples at 1080 x 600). The
//! per-ray BVH is already cheap on coherent primary rays (the BVH docs measure ~18 nodes per
//! primary ray on Sponza). Not yet tried: the AVX2 8-lane kernel
//! as compiled is slower than the 4-lane one (see [`cast_with`]); HVVR's per-tile triangle
//! set-up (tile-corner all-in / all-out classification, precomputed edge equations shared by
//! the tile's rays) — our per-ray watertight test recomputes the shear projection of every
//! vertex for every ray, which is what exactness against the BVH costs.

pub mod cast;
pub mod hierarchy;
pub mod intersect;
pub mod packet;
pub mod patterns;
pub mod samples;
pub mod tile_setup;
pub mod visibility;

pub use cast::{CastOptions, CastStats, cast, cast_opts, cast_with};
pub use hierarchy::{Block, Hierarchy, HierarchyError, Tile};
pub use patterns::PatternError;
pub use samples::{Sample, SampleSet};
pub use tile_setup::SampleTest;
pub use visibility::{VisibilityBuffer, trace_per_ray};

// HVVR around the visibility stage (issue 5 parts 4-6): presets, shading, resolve,
// reconstruction, the frame and its benchmark.
pub mod bench;
pub mod frame;
pub mod presets;
pub mod reconstruct;
pub mod resolve;
pub mod shade;
