//! Stereo and temporal sample reprojection for path-traced stereo, measured in effective samples
//! per pixel (Mäkitalo, Kivi, Koskela, Jääskeläinen 2019, "Reducing Computational Complexity of
//! Real-Time Stereoscopic Ray Tracing with Spatiotemporal Sample Reprojection").
//!
//! Real-time path tracing affords about one sample per pixel and stereo doubles the cost; the
//! paper reuses samples across the eyes and across frames by backward reprojection and measures
//! the gain as the spp of plain path tracing that gives the same error.
//!
//! - [`sampler`]: the paper's sample (§4.1: primary ray, secondary ray, light connections at
//!   both vertices) with each sample's primary hit as its G-buffer texel ([`buffers`]);
//! - [`footprint`]: backward reprojection of a pixel: projection, 2x2 bilinear (or wider tent)
//!   neighbours, world-position and shading-normal tests, renormalised weights;
//! - [`history`]: temporal accumulation (blend 0.2, or BMFR's running mean);
//! - [`method`]: the stereo, temporal and stereo + temporal frames of one method;
//! - [`sequence`]: frames of a stereo sequence, seeds, default limits; [`dataset`]: the scenes,
//!   head paths and variants (glossy, moving light);
//! - [`metric`]: effective spp from the n-spp error curve (§3); [`mod@reference`]: references and
//!   curves from one progressive render per frame and eye, cached on disk by content
//!   ([`fingerprint`]);
//! - [`mod@evaluate`]: scores of a sequence per method and mode (Tables 1-2), which
//!   `parallax bench reproject` prints.
//!
//! **Why inside `parallax-path`:** the reprojection's sample *is* the path tracer's estimator
//! (its light sampler, MIS and BSDF sampling) and its references are path-traced renders; a
//! crate of its own would need those pieces moved down into `parallax-render` while the path
//! tracer is still changing. Nothing here changes the path tracer beyond its `final_nee` option.
//!
//! **Invariants:** every sample comes from a stream seeded by pixel, frame and eye, and every
//! pass writes only its own pixels and sums in a fixed order, so frames, masks and scores are
//! bit-identical at any thread count; the reprojection reads only G-buffers and values of the
//! two views involved, never the scene.

pub mod buffers;
pub mod dataset;
pub mod error;
pub mod evaluate;
pub mod fingerprint;
pub mod footprint;
pub mod history;
pub mod isa;
#[cfg(target_arch = "x86_64")]
mod lanes;
pub mod method;
pub mod metric;
mod projector;
pub mod reference;
pub mod sampler;
pub mod sequence;

pub use buffers::{EyeView, Texel};
pub use dataset::{Dataset, FrameWorld, Variant};
pub use error::{ReprojectError, Result};
pub use evaluate::{EvalOptions, Evaluation, FrameScore, Mode, Series, Stats, evaluate};
pub use footprint::{Footprint, Kernel, Outcome, Tests};
pub use history::{Blend, History};
pub use method::{Combine, Method, MethodFrame, MethodState, ModeFrame};
pub use metric::{EffectiveSpp, ErrorCurve};
pub use reference::{FrameReference, ReferenceCache, ReferenceSpec};
pub use sampler::{PaperSampler, TraceCost};
pub use sequence::{Frame, RunOptions};
