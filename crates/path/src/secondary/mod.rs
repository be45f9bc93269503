//! The secondary-ray renderer of the layered depth cube paper (Bürger, Krüger & Westermann
//! 2007, §2 "Rendering"): primary visibility by rasterization, then Whitted-style secondary
//! rays — mirror reflections, refractions and shadows — traced through any world-space tracer
//! ([`parallax_core::WorldTracer`]: the BVH, the layered depth cube, ...), and the comparison
//! of tracers on identical rays.
//!
//! **Passes (§2).** (1) The structures are built (the LDC capture, the BVH); (2) the primary
//! hits are rasterized into a G-buffer ([`parallax_raster::capture_gbuffer`], the same for
//! every tracer); (3) secondary rays are traced level by level ([`render`]): at every surface
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
pub mod compare;
pub mod lights;
pub mod rays;
pub mod render;
pub mod replay;

use serde::Serialize;

pub use compare::{Comparison, compare};
pub use render::{Batch, SecondaryImage, render};
pub use replay::Agreement;

/// Largest `bounces`.
pub const MAX_BOUNCES: u32 = 16;

/// A kind of secondary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Effect {
    /// Mirror reflections (also the reflected part at glass, and total internal reflection).
    Reflect,
    /// Refraction through glass.
    Refract,
    /// Shadow rays to lights.
    Shadow,
}

impl Effect {
    pub const ALL: [Effect; 3] = [Effect::Reflect, Effect::Refract, Effect::Shadow];

    pub fn name(self) -> &'static str {
        match self {
            Effect::Reflect => "reflect",
            Effect::Refract => "refract",
            Effect::Shadow => "shadow",
        }
    }
}

/// Which effects are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Effects {
    pub reflect: bool,
    pub refract: bool,
    pub shadow: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Self {
            reflect: true,
            refract: true,
            shadow: true,
        }
    }
}

impl Effects {
    /// A comma list of `reflect`, `refract`, `shadow` (or `all`).
    pub fn parse(list: &str) -> Result<Self, SecondaryError> {
        let mut e = Self {
            reflect: false,
            refract: false,
            shadow: false,
        };
        for w in list.split(',').map(str::trim).filter(|w| !w.is_empty()) {
            match w {
                "reflect" => e.reflect = true,
                "refract" => e.refract = true,
                "shadow" => e.shadow = true,
                "all" => e = Self::default(),
                _ => {
                    return Err(SecondaryError::InvalidOptions(format!(
                        "unknown effect {w:?} (expected reflect, refract, shadow or all)"
                    )));
                }
            }
        }
        Ok(e)
    }

    pub fn has(&self, effect: Effect) -> bool {
        match effect {
            Effect::Reflect => self.reflect,
            Effect::Refract => self.refract,
            Effect::Shadow => self.shadow,
        }
    }
}

/// Renderer options (module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SecondaryOptions {
    pub effects: Effects,
    pub bounces: u32,
}

impl Default for SecondaryOptions {
    fn default() -> Self {
        Self {
            effects: Effects::default(),
            bounces: 4,
        }
    }
}

impl SecondaryOptions {
    pub fn validate(&self) -> Result<(), SecondaryError> {
        if self.bounces > MAX_BOUNCES {
            return Err(SecondaryError::InvalidOptions(format!(
                "bounces must be at most {MAX_BOUNCES}, got {}",
                self.bounces
            )));
        }
        Ok(())
    }
}

/// Errors of the secondary-ray renderer.
#[derive(Debug, thiserror::Error)]
pub enum SecondaryError {
    #[error("invalid secondary-ray options: {0}")]
    InvalidOptions(String),
    #[error("the secondary-ray renderer needs a pinhole camera (primary hits are rasterized)")]
    NotPinhole,
    #[error(transparent)]
    Raster(#[from] parallax_raster::RasterError),
    #[error(transparent)]
    Tracer(#[from] crate::PathError),
    #[error(transparent)]
    Core(#[from] parallax_core::CoreError),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effects_parse() {
        let e = Effects::parse("reflect, shadow").unwrap();
        assert!(e.reflect && e.shadow && !e.refract);
        assert_eq!(Effects::parse("all").unwrap(), Effects::default());
        assert!(Effects::parse("glow").is_err());
        let bad = SecondaryOptions {
            bounces: MAX_BOUNCES + 1,
            ..SecondaryOptions::default()
        };
        assert!(bad.validate().is_err());
    }
}
