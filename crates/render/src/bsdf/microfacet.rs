//! glTF 2.0 metallic-roughness (glTF spec, Appendix B "BRDF implementation"): a Lambertian
//! base under a GGX microfacet specular layer (Walter et al. 2007), masking-shadowing by the
//! height-correlated Smith `G2` (Heitz 2014, eq. 99), Fresnel by Schlick:
//!
//! ```text
//! s = (1 - |wo·h|)^5,  F_dielectric = 0.04 + 0.96 s,  F = f0 + (1 - f0) s,  f0 = lerp(0.04, base, metallic)
//! f = (1 - metallic) (1 - F_dielectric) base / π  +  F D(h) G2(wo, wi) / (4 cos θ_o cos θ_i)
//! ```
//!
//! Sampling is a two-lobe mixture: with probability `p_spec` a GGX visible normal (Heitz 2018,
//! [`parallax_core::sampling::warp::Ggx::sample_visible`]) reflected about, else a cosine
//! direction; `p_spec` is the specular share of the lobes' albedo estimated at `h = n`. The pdf
//! is the mixture's, so the weight `eval / pdf` is bounded wherever either lobe dominates.
//!
//! | parameter | type | range | meaning |
//! |---|---|---|---|
//! | `base` | Vec3 | [0, 1] | base colour (texture included) |
//! | `metallic` | f32 | [0, 1] | glTF metalness |
//! | `roughness` | f32 | [0, 1] | perceptual roughness; GGX `alpha = max(roughness², MIN_ALPHA)` |

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use parallax_core::sampling::warp::{self, Ggx};

use super::sample::{BsdfSample, luminance};

/// Smallest GGX alpha used: perceptual roughness below `sqrt(MIN_ALPHA)` ≈ 0.032 renders as
/// that roughness (sharper lobes make the pdf spike beyond what f32 MIS handles gracefully).
pub const MIN_ALPHA: f32 = 1e-3;

/// Smallest specular lobe probability: keeps the specular lobe sampled on dark bases.
const MIN_SPEC_PROB: f32 = 0.05;

/// The glTF metallic-roughness BRDF at one surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughness {
    pub base: Vec3,
    pub metallic: f32,
    pub ggx: Ggx,
}

#[inline]
fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

impl MetallicRoughness {
    pub fn new(base: Vec3, metallic: f32, roughness: f32) -> Self {
        let r = roughness.clamp(0.0, 1.0);
        Self {
            base: base.clamp(Vec3::ZERO, Vec3::ONE),
            metallic: metallic.clamp(0.0, 1.0),
            ggx: Ggx::isotropic((r * r).max(MIN_ALPHA)),
        }
    }

    #[inline]
    fn f0(&self) -> Vec3 {
        Vec3::splat(0.04).lerp(self.base, self.metallic)
    }

    /// Probability of sampling the specular lobe for viewing direction `wo`.
    #[inline]
    pub fn spec_prob(&self, wo: Vec3) -> f32 {
        let s = schlick_weight(wo.z);
        let f0 = self.f0();
        let spec = luminance(f0 + (Vec3::ONE - f0) * s);
        let diffuse = (1.0 - self.metallic) * (1.0 - (0.04 + 0.96 * s)) * luminance(self.base);
        let total = spec + diffuse;
        if total <= 0.0 {
            return 1.0;
        }
        (spec / total).clamp(MIN_SPEC_PROB, 1.0)
    }

    /// `f(wo, wi) cos θ_i`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let s = schlick_weight(wo.dot(h));
        let f0 = self.f0();
        let f = f0 + (Vec3::ONE - f0) * s;
        let diffuse = self.base * ((1.0 - self.metallic) * (1.0 - (0.04 + 0.96 * s)) * FRAC_1_PI);
        let spec = f * (self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z));
        (diffuse + spec) * wi.z
    }

    /// The mixture pdf of `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p = self.spec_prob(wo);
        p * self.ggx.pdf_reflect(wo, wi) + (1.0 - p) * warp::cosine_hemisphere_pdf(wi.z)
    }

    /// Picks a lobe with `u_lobe`, samples it with `u`.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.spec_prob(wo) {
            let h = self.ggx.sample_visible(wo, u);
            warp::reflect(wo, h)
        } else {
            warp::cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        let f = self.eval(wo, wi);
        if !(pdf > 0.0) || !f.is_finite() {
            return None;
        }
        let weight = f / pdf;
        weight.is_finite().then_some(BsdfSample {
            wi,
            weight,
            pdf,
            delta: false,
            eta: 1.0,
        })
    }
}
