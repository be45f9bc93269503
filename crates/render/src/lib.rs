//! parallax-render: the techniques, and the reference they are scored against.
//!
//! So far: the reference renderer ([`reference`](mod@reference)) — an exact BVH ray tracer that produces, for
//! any camera model, a G-buffer from primary rays and a shaded image (direct light with shadow
//! rays, GGX specular, mirror and glass) — the ray-throughput benchmark ([`bench`](mod@bench)) and the
//! run statistics every command reports ([`stats`]).
//!
//! **Invariant:** every image-space technique added here is scored against
//! [`reference::render()`] on identical cameras.

pub mod bench;
pub mod brdf;
pub mod lights;
pub mod reference;
pub mod stats;
pub mod synth;
pub mod tiles;
pub mod vr;

pub use stats::{RunStats, StageTimer};
