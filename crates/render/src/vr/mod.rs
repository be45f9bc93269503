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
//! - [`cast()`]: block cull, tile cull and sample testing (§5.3-5.5), `intersect.rs` for the
//!   last; the culling itself lives in `parallax_bvh::beam`, the beam in
//!   `parallax_core::math::Beam`.

pub mod cast;
pub mod hierarchy;
pub mod intersect;
pub mod packet;
pub mod patterns;
pub mod samples;
pub mod visibility;

pub use cast::{CastStats, cast, cast_with};
pub use hierarchy::{Block, Hierarchy, HierarchyError, Tile};
pub use patterns::PatternError;
pub use samples::{Sample, SampleSet};
pub use visibility::{VisibilityBuffer, trace_per_ray};
