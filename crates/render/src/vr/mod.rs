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

pub mod samples;
pub mod visibility;

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
