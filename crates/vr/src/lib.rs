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
//! - [`cast()`]: block cull, tile cull and sample testing (§5.3-5.5). The default sample test
//!   is HVVR's per-tile triangle set-up ([`cast::setup`], [`SampleTest::TileSetup`]): per tile,
//!   edge covectors and a `1/t` covector relative to the tiles' shared ray origin, tile-corner
//!   all-in / partial / all-out classification, then packets of four rays (SSE; eight on AVX2
//!   as an option) at a few multiply-adds per ray-triangle test. The exact kernels
//!   ([`SampleTest::Watertight`]: [`cast::packet`], four rays per SIMD op, and [`cast::intersect`], one ray
//!   at a time) run the BVH's own watertight test; they serve tiles without a shared origin
//!   (thin lens) and are selectable ([`CastOptions`], `--visibility beam-watertight`). The
//!   culling and the beam itself live in [`beam`].
//!
//! **Exactness.** The watertight kernels perform, per subsample ray, the f32 operations of the
//! BVH's own leaf test with the same tie-break, on rays bit-identical to
//! [`SampleSet::subsample_ray`], and the culling is conservative, so their buffer equals
//! [`trace_per_ray`]'s subsample for subsample (tests/cast.rs: agreement 1.0 and equal `t`
//! on atrium and cornell for grid, per-channel distortion, foveated, 210 x 130 fisheye,
//! thin-lens DoF and stereo, spp 1 and 4). The set-up kernel uses its float edge and depth
//! values as a filter with a conservative uncertainty band and decides inside the band with
//! the same watertight test (`cast/setup/mod.rs`, "exact band"), in two settings
//! ([`SetupExactness`] in [`CastOptions`]): the default `Edges` bands only the edge values —
//! exact coverage (no vertex hole, no hit-vs-miss difference), depth by HVVR's largest `1/t`
//! with `t = 1 / (g . d)`, so the only differences from per-ray traversal are depth ties
//! within float tolerance (0 on atrium, 47 of 213,385 subsamples on cornell's coplanar
//! overlapping faces) — at 0-15% over the kernel without a band; `Full` also bands the depth
//! and takes every winner's `t` from the watertight test: 0 differing subsamples and
//! bit-identical `t` for every scheme (`--visibility beam-exact`), up to ~25% slower than
//! `Edges` (`cast/setup/mod.rs`, "cost of exactness").
//!
//! **Measured** before the exact band (`vr_speed` example, atrium stereo 540 x 600 per eye, spp 16, 2 threads on the
//! 2-core VM at load 15 — ratios from one process, noisy): set-up kernel 3.4-4.7x the per-ray
//! rate, watertight kernel 2.3x in the same conditions (earlier idle-machine figures for the
//! watertight kernel at 2160 x 1200: 2.5-2.65x). See `cast/setup/mod.rs` for the full table and
//! what remains (the 8-lane AVX2 build is not yet vectorised well).

pub mod beam;
pub mod cast;
pub mod hierarchy;
pub mod patterns;
pub mod samples;
pub mod visibility;

pub use cast::setup::{SampleTest, SetupExactness};
pub use cast::{CastOptions, CastStats, cast, cast_opts, cast_with};
pub use hierarchy::{Block, Hierarchy, HierarchyError, Tile};
pub use patterns::PatternError;
pub use samples::{Sample, SampleSet};
pub use visibility::{VisibilityBuffer, trace_per_ray};

// HVVR around the visibility stage (issue 5 parts 4-6): presets, shading, resolve,
// reconstruction, the frame and its benchmark.
pub mod bench;
pub mod frame;
pub mod presets;
pub mod reconstruct;
pub mod resolve;
pub mod shade;
