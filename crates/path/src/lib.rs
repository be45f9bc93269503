//! parallax-path: light transport written once over the world-space tracer interface
//! ([`parallax_core::WorldTracer`]): the reference path tracer (the BVH behind the interface),
//! DIRT's deferred image-based path tracer (Vardis et al. 2017: the same estimator with DIRT's
//! per-pixel primitive lists behind it), and the secondary-ray renderer of the layered depth
//! cube paper (reflections, refractions and shadows from a rasterized primary view).
//!
//! The path tracer:
//! - [`estimator`]: unidirectional path tracing with next-event estimation and MIS (power
//!   heuristic) for emissive triangles, the constant environment and point / spot /
//!   directional lights; Russian roulette as Mitsuba 3's `path` integrator;
//! - [`wavefront`]: DIRT's deferred traversal (trace, fetch, shade, occlusion passes per
//!   bounce over a tile of pixels);
//! - [`render`]: a sample count or a time budget; [`schedule`]: one sample of one tile per
//!   work unit, handed to the workers without barriers; [`film`]: mean,
//!   variance and count per pixel; [`record`]: every ray and its hit, for comparisons;
//! - [`lighting`]: light overrides and the default sky; [`light_sampler`]: light choice and
//!   densities; [`mis`]; [`tracers`]: the `--tracer` factory; [`bvh_tracer`]: the BVH as
//!   the path tracer calls it (packets for a pinhole's camera rays);
//! - [`mod@bench`]: `parallax bench path`; [`export`]: the scene as a Mitsuba 3 cross-check reads it.
//!
//! **Invariant:** nothing here knows which structure answers its rays; every structure is
//! compared on identical rays.

pub mod bench;
pub mod bvh_tracer;
pub mod error;
pub mod estimator;
pub mod export;
pub mod film;
pub mod light_sampler;
pub mod lighting;
pub mod mis;
pub mod options;
pub mod record;
pub mod render;
pub mod reproject;
pub mod schedule;
pub mod secondary;
pub mod stats;
pub mod tracers;
pub mod wavefront;

pub use error::{PathError, Result};
pub use lighting::{LightOverrides, LightingNote, apply_lighting};
pub use options::PathOptions;
pub use render::{PathOutput, PathTracer};
pub use tracers::{BuiltTracer, TracerKind, TracerOptions, build_tracer};
