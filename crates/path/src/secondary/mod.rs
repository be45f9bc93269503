//! The secondary-ray renderer of the layered depth cube paper (Bürger, Krüger & Westermann
//! 2007, §2 "Rendering"): primary visibility by rasterization, then Whitted-style secondary
//! rays — mirror reflections, refractions and shadows — traced through any world-space tracer
//! ([`parallax_core::WorldTracer`]: the BVH, the layered depth cube, ...), and the comparison
//! of tracers on identical rays.
//!
//! **Passes (§2).** (1) The structures are built (the LDC capture, the BVH); (2) the primary
//! hits are rasterized into a G-buffer ([`parallax_raster::capture_gbuffer`], the same for
//! every tracer); (3) secondary rays are traced level by level ([`render()`]): at every surface
//! point a shadow ray to each light, at a mirror a reflection ray, at glass a reflection and a
//! refraction ray (Snell's law, exact dielectric Fresnel weights, the material's IOR), up to
//! `bounces` levels; a ray that misses every surface sees the environment (the paper's
//! environment-map lookup at the box exit). Hits are shaded with `parallax_render`'s BRDF and
//! lights from [`SurfacePoint::from_world_hit`](parallax_render::reference::surface::SurfacePoint::from_world_hit)
//! (sampled hits with their sample's normal and albedo).
//!
//! **Whitted shading** (deterministic, no random numbers): emission seen from the front;
//! at standard (metallic-roughness) surfaces the direct light of every point, spot and
//! directional light times its shadow ray's visibility, plus an unshadowed ambient term
//! `environment * albedo * (1 - metallic)` (Whitted 1980's ambient); scenes without analytic
//! lights light with their emissive triangles taken as point lights at their centroids
//! (intensity `L A cos`, [`lights`]). Specular surfaces reached at the last level add nothing.
//! This is a simplification of full light transport (no glossy or diffuse interreflection),
//! chosen so that every difference between two tracers' images comes from their hits alone.
//!
//! **Identical rays.** Every level's rays are recorded per effect ([`render::Batch`]); the
//! comparison ([`replay`]) re-traces the BVH renderer's batches through every other tracer:
//! hit agreement per bounce and per effect (same primitive, or position within a tolerance),
//! Mrays/s per tracer per effect on the same rays, and PSNR / SSIM of each tracer's own image
//! against the BVH's.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `effects` | [`Effects`] | all | which secondary rays are traced (`reflect`, `refract`, `shadow`); a disabled shadow leaves lights unshadowed |
//! | `bounces` | u32 | 4 | specular levels after the primary hit (0 = shadows of primary hits only), at most [`MAX_BOUNCES`] |
//!
//! **Invariants:** the image does not depend on the thread count (no randomness; rays are
//! traced in parallel chunks but answers and contributions are gathered in pixel order); every
//! tracer sees the same primary hits; the renderer never asks which structure answers.

pub mod bench;
pub mod classify;
pub mod compare;
pub mod lights;
pub mod options;
pub mod rays;
pub mod render;
pub mod replay;
pub mod roi;

pub use compare::{Comparison, compare};
pub use options::{Effect, Effects, MAX_BOUNCES, SecondaryError, SecondaryOptions};
pub use render::{Batch, SecondaryImage, render};
pub use replay::Agreement;
