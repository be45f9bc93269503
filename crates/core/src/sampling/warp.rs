//! Warps from the unit square to disks, hemispheres, spheres, triangles and BRDF lobes.
//!
//! All directions are in a local frame with `z` as the normal ("z up"); use
//! [`crate::math::Frame`] to move them to world space. Every sampler has a pdf with respect
//! to solid angle (directions) or area (disk, triangle) next to it. Inputs `u` are in
//! `[0, 1)^2`.

use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

use glam::{Vec2, Vec3};

use crate::math::Frame;

/// Concentric map of the square onto the unit disk (Shirley & Chiu 1997, "A low distortion
/// map between disk and square"; the form of pbrt-v3 §13.6.2). Area-preserving up to a
/// constant: the pdf on the disk is `1/π`.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    let (s, c) = theta.sin_cos();
    Vec2::new(r * c, r * s)
}

/// Inverse of [`concentric_disk`]: a point of the unit disk back to the square.
///
/// With `φ = atan2(y, x)` shifted into `[-π/4, 7π/4)`, the four wedges of the forward map
/// invert as: `φ < π/4`: `(r, 4φ/π · r)`; `φ < 3π/4`: `((2 - 4φ/π) r, r)`; `φ < 5π/4`:
/// `(-r, -4(φ-π)/π · r)`; else `(-(2 - 4(φ-π)/π) r, -r)` in `[-1, 1]^2`.
pub fn concentric_disk_inverse(p: Vec2) -> Vec2 {
    let r = p.length();
    let mut phi = p.y.atan2(p.x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    let t = phi * (4.0 * FRAC_1_PI); // phi in units of π/4, in [-1, 7)
    let o = if t < 1.0 {
        Vec2::new(r, r * t)
    } else if t < 3.0 {
        Vec2::new(r * (2.0 - t), r)
    } else if t < 5.0 {
        Vec2::new(-r, -r * (t - 4.0))
    } else {
        Vec2::new(-r * (6.0 - t), -r)
    };
    ((o + Vec2::ONE) * 0.5).clamp(Vec2::ZERO, Vec2::ONE)
}

/// Cosine-weighted hemisphere direction (Malley's method: project the concentric disk up).
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Pdf of [`cosine_hemisphere`]: `cos θ / π` (0 below the horizon).
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// A cosine-weighted direction around the world-space unit normal `n`.
#[inline]
pub fn cosine_hemisphere_around(n: Vec3, u: Vec2) -> Vec3 {
    Frame::from_normal(n).to_world(cosine_hemisphere(u))
}

/// Uniform direction on the unit sphere (pbrt-v4 §A.5.2).
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Pdf of [`uniform_sphere`]: `1 / 4π`.
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// Uniform direction on the upper (`z >= 0`) hemisphere.
#[inline]
pub fn uniform_hemisphere(u: Vec2) -> Vec3 {
    let z = u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Pdf of [`uniform_hemisphere`]: `1 / 2π`.
pub const UNIFORM_HEMISPHERE_PDF: f32 = 0.5 * FRAC_1_PI;

/// Uniform point on a triangle as barycentrics `(b0, b1, b2)` (Osada et al. 2002, "Shape
/// distributions", eq. 1): `b0 = 1 - √u0`, `b1 = u1 √u0`. The area pdf is `1 / area`.
#[inline]
pub fn uniform_triangle(u: Vec2) -> Vec3 {
    let su = u.x.sqrt();
    let b0 = 1.0 - su;
    let b1 = u.y * su;
    Vec3::new(b0, b1, (1.0 - b0 - b1).max(0.0))
}

/// Blinn-Phong exponent equivalent to a GGX/Beckmann roughness `alpha` (Walter et al. 2007,
/// "Microfacet models for refraction through rough surfaces", §5.2: `n = 2/α² - 2`), clamped
/// to `[0, 1e6]`.
#[inline]
pub fn phong_exponent_from_roughness(alpha: f32) -> f32 {
    let a = alpha.max(1e-3);
    (2.0 / (a * a) - 2.0).clamp(0.0, 1.0e6)
}

/// A direction from the normalised `cos^n θ` lobe around `z` (Phong lobe sampling, Lafortune
/// & Willems 1994): `cos θ = u0^(1/(n+1))`.
#[inline]
pub fn phong_lobe(u: Vec2, exponent: f32) -> Vec3 {
    let z = u.x.powf(1.0 / (exponent + 1.0));
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = (2.0 * PI * u.y).sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Pdf of [`phong_lobe`] (solid angle): `(n + 1) / 2π · cos^n θ`.
#[inline]
pub fn phong_lobe_pdf(cos_theta: f32, exponent: f32) -> f32 {
    if cos_theta <= 0.0 {
        return 0.0;
    }
    (exponent + 1.0) * 0.5 * FRAC_1_PI * cos_theta.powf(exponent)
}

/// The normalised Blinn-Phong NDF `D(h) = (n + 2) / 2π · cos^n θ_h` (`∫ D cos θ_h dω = 1`).
#[inline]
pub fn blinn_phong_d(cos_theta_h: f32, exponent: f32) -> f32 {
    if cos_theta_h <= 0.0 {
        return 0.0;
    }
    (exponent + 2.0) * 0.5 * FRAC_1_PI * cos_theta_h.powf(exponent)
}

/// The GGX / Trowbridge-Reitz microfacet distribution (Walter et al. 2007; anisotropic form
/// and Smith masking from Heitz 2014, "Understanding the masking-shadowing function in
/// microfacet-based BRDFs"). Roughness values are clamped to at least [`Ggx::MIN_ALPHA`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub alpha_x: f32,
    pub alpha_y: f32,
}

impl Ggx {
    /// Smallest roughness used (avoids the singular perfect-mirror limit).
    pub const MIN_ALPHA: f32 = 1e-4;

    /// An isotropic distribution with roughness `alpha` (= perceptual roughness squared).
    pub fn isotropic(alpha: f32) -> Self {
        Self::anisotropic(alpha, alpha)
    }

    pub fn anisotropic(alpha_x: f32, alpha_y: f32) -> Self {
        Self {
            alpha_x: alpha_x.max(Self::MIN_ALPHA),
            alpha_y: alpha_y.max(Self::MIN_ALPHA),
        }
    }

    /// The NDF `D(h) = 1 / (π αx αy ((hx/αx)² + (hy/αy)² + hz²)²)` (Heitz 2014 eq. 85), zero
    /// for `hz <= 0`; normalised so that `∫ D(h) hz dω = 1`.
    #[inline]
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let t = (h.x / self.alpha_x).powi(2) + (h.y / self.alpha_y).powi(2) + h.z * h.z;
        1.0 / (PI * self.alpha_x * self.alpha_y * t * t)
    }

    /// Smith `Λ(w) = (√(1 + α²tan²θ) - 1) / 2` with `α²tan²θ = (αx² wx² + αy² wy²) / wz²`
    /// (Heitz 2014 eq. 86); infinite at grazing directions.
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f32::INFINITY;
        }
        let a2_tan2 = ((self.alpha_x * w.x).powi(2) + (self.alpha_y * w.y).powi(2)) / z2;
        0.5 * ((1.0 + a2_tan2).sqrt() - 1.0)
    }

    /// Smith masking `G1(w) = 1 / (1 + Λ(w))`.
    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing `G2 = 1 / (1 + Λ(wo) + Λ(wi))` (Heitz 2014 eq. 99).
    #[inline]
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Samples a microfacet normal from the distribution of visible normals
    /// `D_wo(h) = G1(wo) max(0, wo·h) D(h) / wo.z` (Heitz 2018, "Sampling the GGX distribution
    /// of visible normals", listing 1). `wo` must point into the upper hemisphere.
    pub fn sample_visible(&self, wo: Vec3, u: Vec2) -> Vec3 {
        // Section 3.2: the view direction in the hemisphere configuration (α = 1).
        let vh = Vec3::new(self.alpha_x * wo.x, self.alpha_y * wo.y, wo.z).normalize();
        // Section 4.1: orthonormal basis around vh (with a fallback at normal incidence).
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 {
            Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
        } else {
            Vec3::X
        };
        let t2 = vh.cross(t1);
        // Section 4.2: parameterisation of the projected area.
        let r = u.x.sqrt();
        let (sp, cp) = (2.0 * PI * u.y).sin_cos();
        let p1 = r * cp;
        let s = 0.5 * (1.0 + vh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * sp;
        // Section 4.3: reprojection onto the hemisphere.
        let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
        // Section 3.4: back to the ellipsoid configuration.
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(0.0)).normalize()
    }

    /// Pdf (solid angle of `h`) of [`Ggx::sample_visible`]: `G1(wo) max(0, wo·h) D(h) / wo.z`.
    #[inline]
    pub fn pdf_visible(&self, wo: Vec3, h: Vec3) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.g1(wo) * wo.dot(h).max(0.0) * self.d(h) / wo.z
    }

    /// Pdf (solid angle of `wi`) of reflecting `wo` about a visible normal:
    /// `pdf_visible(wo, h) / (4 wo·h)` with `h = normalize(wo + wi)` (the reflection
    /// Jacobian, Walter et al. 2007 eq. 14).
    #[inline]
    pub fn pdf_reflect(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = wo + wi;
        if h.length_squared() == 0.0 {
            return 0.0;
        }
        let h = h.normalize();
        let cos = wo.dot(h);
        if cos <= 0.0 {
            return 0.0;
        }
        self.pdf_visible(wo, h) / (4.0 * cos)
    }
}

/// Isotropic GGX NDF from `cos θ_h` (Walter et al. 2007 eq. 33):
/// `α² / (π (cos²θ_h (α² - 1) + 1)²)`, zero for `cos θ_h <= 0`. Same as [`Ggx::d`].
#[inline]
pub fn ggx_d(cos_theta_h: f32, alpha: f32) -> f32 {
    if cos_theta_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha.max(Ggx::MIN_ALPHA).powi(2);
    let t = cos_theta_h * cos_theta_h * (a2 - 1.0) + 1.0;
    a2 / (PI * t * t)
}

/// Isotropic Smith `Λ` from `cos θ`: `(√(1 + α² tan²θ) - 1) / 2`.
#[inline]
fn smith_lambda(cos_theta: f32, alpha: f32) -> f32 {
    let c2 = cos_theta * cos_theta;
    if c2 == 0.0 {
        return f32::INFINITY;
    }
    let a2_tan2 = alpha.max(Ggx::MIN_ALPHA).powi(2) * (1.0 - c2).max(0.0) / c2;
    0.5 * ((1.0 + a2_tan2).sqrt() - 1.0)
}

/// Isotropic GGX Smith masking `G1` from `cos θ`. Same as [`Ggx::g1`].
#[inline]
pub fn smith_g1(cos_theta: f32, alpha: f32) -> f32 {
    1.0 / (1.0 + smith_lambda(cos_theta, alpha))
}

/// Isotropic height-correlated GGX `G2` from `cos θ_o`, `cos θ_i` (Heitz 2014 eq. 99).
/// Same as [`Ggx::g2`].
#[inline]
pub fn smith_g2(cos_o: f32, cos_i: f32, alpha: f32) -> f32 {
    1.0 / (1.0 + smith_lambda(cos_o, alpha) + smith_lambda(cos_i, alpha))
}

/// Mirror `wo` about the unit normal `h`.
#[inline]
pub fn reflect(wo: Vec3, h: Vec3) -> Vec3 {
    2.0 * wo.dot(h) * h - wo
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_disk_round_trips_and_stays_inside() {
        let n = 64;
        for j in 0..n {
            for i in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let d = concentric_disk(u);
                assert!(d.length() <= 1.0 + 1e-6);
                let back = concentric_disk_inverse(d);
                assert!(
                    (back - u).abs().max_element() < 1e-5,
                    "{u} -> {d} -> {back}"
                );
            }
        }
        // Corners of the square go to the rim.
        assert!((concentric_disk(Vec2::new(1.0, 0.5)) - Vec2::X).length() < 1e-6);
        assert_eq!(concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
    }

    #[test]
    fn directions_are_unit_and_in_their_domain() {
        let mut rng = crate::sampling::Rng::new(5, 6);
        let ggx = Ggx::anisotropic(0.2, 0.6);
        let wo = Vec3::new(0.5, -0.3, 0.4).normalize();
        for _ in 0..1000 {
            let u = rng.next_vec2();
            for (w, upper) in [
                (cosine_hemisphere(u), true),
                (uniform_hemisphere(u), true),
                (uniform_sphere(u), false),
                (phong_lobe(u, 20.0), true),
                (ggx.sample_visible(wo, u), true),
            ] {
                assert!((w.length() - 1.0).abs() < 1e-4, "{w}");
                assert!(!upper || w.z >= 0.0);
            }
            let b = uniform_triangle(u);
            assert!(b.min_element() >= 0.0 && (b.element_sum() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn height_correlated_g2_lies_between_product_and_min() {
        let ggx = Ggx::isotropic(0.4);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let wi = Vec3::new(-0.3, 0.5, 0.3).normalize();
        let (g_o, g_i, g2) = (ggx.g1(wo), ggx.g1(wi), ggx.g2(wo, wi));
        assert!(g2 >= g_o * g_i - 1e-6 && g2 <= g_o.min(g_i) + 1e-6);
        assert!(
            g2 < g_o.min(g_i) - 1e-3,
            "G2 should be strictly below min(G1)"
        );
        assert_eq!(ggx.g1(Vec3::Z), 1.0);
    }

    #[test]
    fn cosine_helpers_equal_the_vector_forms() {
        for alpha in [0.05, 0.3, 0.9] {
            let ggx = Ggx::isotropic(alpha);
            for (h, wi) in [
                (
                    Vec3::new(0.3, 0.1, 0.9).normalize(),
                    Vec3::new(-0.5, 0.2, 0.4).normalize(),
                ),
                (Vec3::Z, Vec3::new(0.9, 0.0, 0.1).normalize()),
            ] {
                let rel = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1.0);
                assert!(rel(ggx_d(h.z, alpha), ggx.d(h)));
                assert!(rel(smith_g1(wi.z, alpha), ggx.g1(wi)));
                assert!(rel(smith_g2(h.z, wi.z, alpha), ggx.g2(h, wi)));
            }
        }
    }

    #[test]
    fn phong_exponent_matches_roughness_width() {
        // Walter et al.: alpha = 1 maps to exponent 0 (uniform-ish), small alpha to sharp.
        assert_eq!(phong_exponent_from_roughness(1.0), 0.0);
        assert!((phong_exponent_from_roughness(0.1) - 198.0).abs() < 1e-2);
    }
}
