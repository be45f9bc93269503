//! The surface model of the reference renderer: glTF metallic-roughness (Lambert + GGX
//! microfacet specular, Walter et al. 2007 with Heitz 2014's height-correlated Smith G),
//! plus perfect mirrors and smooth dielectrics.

use glam::Vec3;
use parallax_core::sampling::warp::{ggx_d, smith_g2};

/// Shading inputs at a surface point.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub albedo: Vec3,
    pub roughness: f32,
    pub metallic: f32,
}

/// Schlick's Fresnel approximation.
#[inline]
pub fn fresnel_schlick(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3::ONE - f0) * m5
}

/// Exact Fresnel reflectance of a smooth dielectric for unpolarised light; `cos_i` > 0 on the
/// side the light comes from, `eta` = n_transmitted / n_incident.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// BRDF value times the cosine at the light, for unit vectors `n` (shading normal), `wo`
/// (towards the viewer) and `wi` (towards the light). Zero below the surface.
pub fn eval_cos(s: &Surface, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    let cos_o = n.dot(wo);
    let cos_i = n.dot(wi);
    if cos_o <= 0.0 || cos_i <= 0.0 {
        return Vec3::ZERO;
    }
    let h = (wo + wi).normalize_or_zero();
    let cos_h = n.dot(h).max(0.0);
    let alpha = (s.roughness * s.roughness).max(1e-3);
    let f0 = Vec3::splat(0.04).lerp(s.albedo, s.metallic);
    let f = fresnel_schlick(f0, wo.dot(h).max(0.0));
    let spec = f * (ggx_d(cos_h, alpha) * smith_g2(cos_o, cos_i, alpha) / (4.0 * cos_o * cos_i));
    let diffuse = (Vec3::ONE - f) * (1.0 - s.metallic) * s.albedo * std::f32::consts::FRAC_1_PI;
    (diffuse + spec) * cos_i
}

/// Mirror direction of `wo` about `n`.
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    2.0 * wo.dot(n) * n - wo
}

/// Refracted direction of `wo` (pointing away from the surface on the incident side) through a
/// surface with normal `n` on the incident side and relative index `eta` = n_t / n_i; `None` at
/// total internal reflection.
pub fn refract(wo: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(n);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + n * (cos_i / eta - cos_t)).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_and_tir() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-4);
        assert_eq!(fresnel_dielectric(0.1, 1.0 / 1.5), 1.0);
    }

    #[test]
    fn refraction_obeys_snell() {
        let n = Vec3::Z;
        let wo = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
        let t = refract(wo, n, 1.5).unwrap();
        let sin_t = t.x.abs();
        assert!((0.5 - 1.5 * sin_t).abs() < 1e-5);
        assert!(t.z < 0.0);
    }

    #[test]
    fn lambert_white_furnace() {
        // A rough white dielectric reflects at most all light: integrate eval_cos over the
        // hemisphere with a midpoint rule.
        let s = Surface {
            albedo: Vec3::ONE,
            roughness: 1.0,
            metallic: 0.0,
        };
        let wo = Vec3::new(0.3, 0.0, 0.95).normalize();
        let n = 200;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let cos_t = (i as f32 + 0.5) / n as f32;
                let phi = (j as f32 + 0.5) / n as f32 * std::f32::consts::TAU;
                let sin_t = (1.0 - cos_t * cos_t).sqrt();
                let wi = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                sum += eval_cos(&s, Vec3::Z, wo, wi).x;
            }
        }
        let albedo = sum * std::f32::consts::TAU / (n * n) as f32;
        assert!(albedo > 0.8 && albedo <= 1.01, "{albedo}");
    }
}
