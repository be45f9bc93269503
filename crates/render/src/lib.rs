//! parallax-render: what every technique of parallax shares, and the reference they are scored
//! against.
//!
//! - [`reference`](mod@reference): the reference renderer — an exact BVH ray tracer that
//!   produces, for any camera model, a G-buffer from primary rays and a shaded image (direct
//!   light with shadow rays, GGX specular, mirror and glass);
//! - [`brdf`], [`lights`], [`reference::surface`]: the shading every technique reuses;
//! - [`score`](mod@score): PSNR / SSIM of an image against the BVH ground truth of the same
//!   camera, through the display transform of the PNGs;
//! - [`tiles`]: screen tiles over rayon; [`stats`]: the run statistics every command reports;
//! - [`bench`](mod@bench): the ray-throughput benchmark (`parallax bench rays`).
//!
//! The techniques live in crates of their own above this one (`parallax-synth`, `parallax-vr`,
//! `parallax-path`) and never use each other.
//!
//! **Invariant:** every image-space technique is scored against [`reference::render()`] on
//! identical cameras.

pub mod bench;
pub mod brdf;
pub mod bsdf;
pub mod lights;
pub mod reference;
pub mod score;
pub mod stats;
pub mod tiles;

pub use stats::{RunStats, StageTimer};
