//! parallax-screen: screen-space ray tracing against captured depth layers.
//!
//! Foundation of Widmer et al. 2015, "An Adaptive Acceleration Structure for Screen-space Ray
//! Tracing" (issue 4):
//!
//! - [`tracer`]: the one interface every image-space structure implements ([`ScreenTracer`],
//!   DESIGN.md "the central seam"), its result and its work counters;
//! - [`space`]: the NDC-like unit cube of the reference view (§3.2) in which construction and
//!   tracing happen — a projective map, so planes stay planes and rays stay lines;
//! - [`planes`]: the per-pixel planes of a captured layer in that cube, with the discontinuity
//!   flag `O` (§3.2, "Bottom level generation");
//! - [`brute`]: [`BruteForcePlanes`], every pixel plane tested against every ray — the slow twin
//!   the quad-tree must agree with;
//! - baselines the quad-tree is measured against (Widmer et al. 2015, Tables 2-3), all behind
//!   [`ScreenTracer`]: [`dda`] (McGuire & Mara 2014), [`minmax`] (Tevs et al. 2008), [`hiz`]
//!   (Uludag 2014);
//! - [`dirt`]: DIRT's tracer over per-view primitive lists (Vardis et al. 2017, §4.2), an exact
//!   world-space tracer behind [`parallax_core::WorldTracer`].
//! - [`ldc`]: the two-level layered depth cube tracer (Bürger et al. 2007, §1.3-1.4) behind the
//!   world-space interface [`parallax_core::WorldTracer`].
//! - [`cubemap`]: six faces of captured layers around a point, one screen-space structure per
//!   face, as a world-space tracer ([`parallax_core::WorldTracer`]) with face transitions
//!   (Widmer et al. 2015, §5.4).
//!
//! **Invariant:** nothing here reads the scene; tracers see only what a capture holds.

pub mod brute;
pub mod cubemap;
pub mod dda;
mod depth_layers;
pub mod dirt;
pub mod hiz;
pub mod ldc;
pub mod minmax;
pub mod planes;
pub mod quadtree;
pub mod space;
mod space_pair;
pub mod tracer;

pub use brute::{BruteForcePlanes, BruteResult};
pub use cubemap::{CubeMapTracer, CubeTrace};
pub use dda::{DdaOptions, DdaTracer};
pub use dirt::{DirtCounters, DirtTracer};
pub use hiz::{HiZOptions, HiZTracer};
pub use ldc::{LdcTraceOptions, LdcTracer};
pub use minmax::{MinMaxOptions, MinMaxTracer};
pub use planes::{LayerPlanes, NormalSource};
pub use quadtree::{LayerMode, QuadTree, QuadTreeOptions, QuadTreeTracer};
pub use space::{CubeNear, CubeSegment, UnitCube};
pub use tracer::{ScreenTracer, TraceResult, TraceStats};

/// Errors of building screen-space structures.
#[derive(Debug, thiserror::Error)]
pub enum ScreenError {
    #[error("invalid unit cube: {0}")]
    InvalidSpace(String),
    #[error("capture does not match: {0}")]
    Mismatch(String),
    #[error(transparent)]
    Raster(#[from] parallax_raster::RasterError),
    #[error(transparent)]
    Core(#[from] parallax_core::CoreError),
}
