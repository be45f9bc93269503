//! Delta lobes: the tinted mirror, the smooth dielectric interface (exact Fresnel, Snell
//! refraction, pbrt-v4 §9.3 / Mitsuba 3 `dielectric`) and the thin dielectric slab (Mitsuba 3
//! `thindielectric`: reflectance `R' = R + T² R / (1 - R²)` summing the slab's internal
//! reflections, transmission `1 - R'` straight through). Lobes are chosen by their energy, so
//! the dielectric weights are 1 for reflection and `1 / eta²` for refraction (radiance).

use glam::Vec3;

use super::sample::BsdfSample;
use crate::brdf::fresnel_dielectric;

/// Mirror reflection in the local frame.
#[inline]
pub fn reflect_local(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// Refraction of `wo` (upper hemisphere) into the lower one through an interface of relative
/// index `eta` = n_t / n_i; `None` at total internal reflection.
#[inline]
pub fn refract_local(wo: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.z;
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(Vec3::new(-wo.x / eta, -wo.y / eta, -cos_t).normalize())
}

/// The tinted perfect mirror.
pub fn sample_mirror(tint: Vec3, wo: Vec3) -> Option<BsdfSample> {
    (wo.z > 0.0).then_some(BsdfSample {
        wi: reflect_local(wo),
        weight: tint,
        pdf: 1.0,
        delta: true,
        eta: 1.0,
    })
}

/// The smooth dielectric: reflection with probability `F`, refraction otherwise.
pub fn sample_dielectric(eta: f32, wo: Vec3, u: f32) -> Option<BsdfSample> {
    if wo.z <= 0.0 || !(eta > 0.0) {
        return None;
    }
    let f = fresnel_dielectric(wo.z.min(1.0), eta);
    if u < f {
        return Some(BsdfSample {
            wi: reflect_local(wo),
            weight: Vec3::ONE,
            pdf: f,
            delta: true,
            eta: 1.0,
        });
    }
    // f < 1 here, so the refraction exists (fresnel_dielectric returns 1 at TIR).
    let wi = refract_local(wo, eta)?;
    Some(BsdfSample {
        wi,
        weight: Vec3::splat(1.0 / (eta * eta)),
        pdf: 1.0 - f,
        delta: true,
        eta,
    })
}

/// Reflectance of a thin slab of index `ior` seen at `cos_o`, internal reflections summed.
pub fn thin_dielectric_reflectance(ior: f32, cos_o: f32) -> f32 {
    let r = fresnel_dielectric(cos_o.clamp(0.0, 1.0), ior);
    if r < 1.0 {
        let t = 1.0 - r;
        r + t * t * r / (1.0 - r * r)
    } else {
        1.0
    }
}

/// The thin dielectric: reflection with probability `R'`, straight transmission otherwise.
pub fn sample_thin_dielectric(ior: f32, wo: Vec3, u: f32) -> Option<BsdfSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let r = thin_dielectric_reflectance(ior, wo.z);
    let (wi, pdf) = if u < r {
        (reflect_local(wo), r)
    } else {
        (-wo, 1.0 - r)
    };
    Some(BsdfSample {
        wi,
        weight: Vec3::ONE,
        pdf,
        delta: true,
        eta: 1.0,
    })
}
