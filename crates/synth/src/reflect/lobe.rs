//! The reflection lobes of the reflection renderer (Widmer et al. 2015, §5.4: "for each
//! intersection point we sample a new direction for the reflection vector by sampling the
//! normalized Blinn-Phong BRDF at this position"; Fig. 13).
//!
//! | material | lobe |
//! |---|---|
//! | `Mirror` | perfect mirror, weight = base colour |
//! | `Standard`, `metallic >= 0.5`, `roughness <= ` [`MAX_GLOSSY_ROUGHNESS`] | normalised Blinn-Phong of exponent `n = 2/α² - 2`, `α = roughness²` (Walter et al. 2007), weight colour = base colour |
//! | anything else | diffuse: the path stops and takes the surface's colour |
//!
//! **Sampling** (importance sampling of the normalised Blinn-Phong BRDF
//! `f = (n + 8) / 8π · cos^n θ_h`): the half vector from `pdf(h) = (n + 1) / 2π · cos^n θ_h`
//! around the normal, `wi = reflect(wo, h)`, `pdf(wi) = pdf(h) / (4 wo·h)`, so the sample's
//! weight `f cos θ_i / pdf(wi) = (n + 8) / (n + 1) · cos θ_i · (wo·h)` (times the colour); a
//! direction below the surface has weight 0. The lobe's energy falls off away from normal
//! incidence (`cos θ_i cos θ_o` at the mirror direction: this normalisation has no microfacet
//! `1 / (4 cos θ_i cos θ_o)`). No Fresnel term (a metal's base colour is its
//! reflectance; the paper's lobe has none either).

use glam::{Vec2, Vec3};
use parallax_core::math::Frame;
use parallax_core::sampling::warp::{phong_exponent_from_roughness, phong_lobe};
use parallax_render::brdf;
use parallax_scene::{Material, MaterialKind};

/// Roughest standard metal that is traced as a glossy reflector (exponent ~30).
pub const MAX_GLOSSY_ROUGHNESS: f32 = 0.5;

/// How a surface reflects (module table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    Mirror { colour: Vec3 },
    Glossy { colour: Vec3, exponent: f32 },
}

impl Lobe {
    /// The lobe of `material` with (textured) albedo `albedo`; `None` for a diffuse surface.
    pub fn of(material: &Material, albedo: Vec3) -> Option<Self> {
        match material.kind {
            MaterialKind::Mirror => Some(Lobe::Mirror { colour: albedo }),
            MaterialKind::Standard
                if material.metallic >= 0.5 && material.roughness <= MAX_GLOSSY_ROUGHNESS =>
            {
                let alpha = material.roughness * material.roughness;
                Some(Lobe::Glossy {
                    colour: albedo,
                    exponent: phong_exponent_from_roughness(alpha),
                })
            }
            _ => None,
        }
    }

    /// True for the mirror (every sample is the same direction).
    pub fn is_delta(&self) -> bool {
        matches!(self, Lobe::Mirror { .. })
    }

    /// A reflected direction for outgoing `wo` (unit, towards the viewer) at unit normal `n`
    /// (facing `wo`) from the uniform sample `u`, and its weight (module docs); weight zero
    /// when the direction falls below the surface.
    pub fn sample(&self, wo: Vec3, n: Vec3, u: Vec2) -> (Vec3, Vec3) {
        match *self {
            Lobe::Mirror { colour } => (brdf::reflect(wo, n), colour),
            Lobe::Glossy { colour, exponent } => {
                let h = Frame::from_normal(n).to_world(phong_lobe(u, exponent));
                let wo_h = wo.dot(h);
                let wi = (2.0 * wo_h * h - wo).normalize();
                let cos_i = wi.dot(n);
                if cos_i <= 0.0 || wo_h <= 0.0 {
                    return (wi, Vec3::ZERO);
                }
                let w = (exponent + 8.0) / (exponent + 1.0) * cos_i * wo_h;
                (wi, colour * w)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    #[test]
    fn mirror_reflects_and_glossy_lobes_concentrate_around_the_mirror_direction() {
        let n = Vec3::Y;
        let wo = Vec3::new(0.6, 0.8, 0.0);
        let m = Lobe::Mirror {
            colour: Vec3::splat(0.9),
        };
        let (d, w) = m.sample(wo, n, Vec2::new(0.3, 0.7));
        assert!((d - Vec3::new(-0.6, 0.8, 0.0)).length() < 1e-6);
        assert_eq!(w, Vec3::splat(0.9));
        let mat = Material {
            kind: MaterialKind::Standard,
            metallic: 1.0,
            roughness: 0.25,
            ..Material::default()
        };
        let g = Lobe::of(&mat, Vec3::ONE).unwrap();
        let mut rng = Rng::new(1, 2);
        let (mut cos_sum, mut w_sum) = (0.0, 0.0);
        for _ in 0..1000 {
            let (d, w) = g.sample(wo, n, rng.next_vec2());
            cos_sum += d.dot(Vec3::new(-0.6, 0.8, 0.0));
            w_sum += w.x;
        }
        // Exponent ~510: directions within a few degrees of the mirror direction, weights
        // close to (n + 8) / (n + 1) cos(theta_i) (wo . h) = 1.014 * 0.8 * 0.8 = 0.649 there
        // (this BRDF darkens away from normal incidence; it has no microfacet 1/(4 cos cos)).
        assert!(cos_sum / 1000.0 > 0.99, "{}", cos_sum / 1000.0);
        assert!((w_sum / 1000.0 - 0.649).abs() < 0.02, "{}", w_sum / 1000.0);
        assert!(Lobe::of(&Material::diffuse("d", Vec3::ONE), Vec3::ONE).is_none());
    }
}
