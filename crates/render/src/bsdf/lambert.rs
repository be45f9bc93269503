//! Two-sided Lambertian reflection: `f = albedo / π`, sampled by the cosine-weighted hemisphere
//! (Malley's method, [`parallax_core::sampling::warp::cosine_hemisphere`]), so the weight is
//! exactly `albedo`.

use std::f32::consts::FRAC_1_PI;

use glam::{Vec2, Vec3};
use parallax_core::sampling::warp;

use super::sample::BsdfSample;

/// `albedo / π · cos θ_i` in the upper hemisphere, zero elsewhere.
#[inline]
pub fn eval(albedo: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    albedo * (FRAC_1_PI * wi.z)
}

/// `cos θ_i / π` in the upper hemisphere.
#[inline]
pub fn pdf(wo: Vec3, wi: Vec3) -> f32 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return 0.0;
    }
    warp::cosine_hemisphere_pdf(wi.z)
}

/// A cosine-distributed direction; weight `albedo`.
#[inline]
pub fn sample(albedo: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    if wo.z <= 0.0 {
        return None;
    }
    let wi = warp::cosine_hemisphere(u);
    let pdf = warp::cosine_hemisphere_pdf(wi.z);
    (pdf > 0.0).then_some(BsdfSample {
        wi,
        weight: albedo,
        pdf,
        delta: false,
        eta: 1.0,
    })
}
