//! What every lobe returns when sampled ([`BsdfSample`]), and the luminance used for lobe
//! selection and Russian roulette.

use glam::Vec3;

/// A sampled direction and its Monte Carlo weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Local direction towards the light.
    pub wi: Vec3,
    /// `f |cos θ_i| / pdf` for smooth lobes; lobe value / lobe probability for delta lobes.
    pub weight: Vec3,
    /// Solid-angle density (smooth lobes) or discrete lobe probability (delta lobes).
    pub pdf: f32,
    /// True when a delta lobe (mirror, refraction, straight transmission) was sampled.
    pub delta: bool,
    /// Relative index of refraction crossed: `n_t / n_i` for refraction, 1 otherwise.
    pub eta: f32,
}

/// Luminance of linear Rec. 709 RGB.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}
