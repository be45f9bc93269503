//! parallax-core: the bottom layer of parallax.
//!
//! Maths on [glam] (rays, boxes, planes, frusta, the watertight ray-triangle test), sampling
//! (seeded per-pixel random streams, low-discrepancy points, warps to disks, hemispheres and
//! BRDF lobes), images ([`Image`], layered G-buffers, PNG/EXR IO) and image metrics
//! (RMSE, PSNR, SSIM), SIMD lanes with one NaN rule ([`simd`]), and the world-space tracer interface ([`WorldTracer`]) that every
//! structure answering world-space rays implements.
//!
//! **Invariant:** nothing in this crate knows about scenes, cameras or acceleration structures.

pub mod cpu;
pub mod cpu_time;
pub mod error;
pub mod huge_pages;
pub mod image;
pub mod math;
pub mod metrics;
pub mod sampling;
pub mod simd;
pub mod spread;
pub mod world;

pub use error::{CoreError, Result};
pub use glam;
pub use image::{ExrImage, GBuffer, GSample, Image, LayeredGBuffer, NO_ID, Rgb};
pub use image::{read_exr, write_exr};
pub use math::{Aabb, Frustum, Plane, Ray, TriangleHit};
pub use metrics::{psnr, psnr_rgb, rmse, rmse_rgb, ssim, ssim_rgb};
pub use sampling::Rng;
pub use world::{HitSurface, SampledSurface, WorldHit, WorldStats, WorldTracer};
