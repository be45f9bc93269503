//! Shading of the reference renderer: direct light with shadow rays, GGX, mirror and glass.
//!
//! Light transport covered (and only this — it is a reference for image-space *visibility*
//! techniques, not a global-illumination ground truth; the path tracer comes with DIRT):
//! - direct light from point, spot and directional lights, with a shadow ray each;
//! - direct light from emissive triangles, one next-event sample per path (power-proportional
//!   triangle choice, uniform point);
//! - the constant environment on diffuse lobes, [`SKY_RAYS`] cosine-sampled visibility rays per
//!   path, stratified 2 x 2 over the hemisphere (ambient occlusion weighted by the sky radiance);
//! - perfect mirror and smooth dielectric chains (Fresnel-weighted stochastic choice between
//!   reflection and refraction), up to [`MAX_SPECULAR_DEPTH`] bounces;
//! - emission seen directly or through a specular chain.

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, Hit};
use parallax_core::Ray;
use parallax_core::math::Frame;
use parallax_core::sampling::{Rng, warp};
use parallax_scene::{MaterialKind, Scene};

use super::surface::SurfacePoint;
use crate::brdf::{self, Surface};
use crate::lights::{EmitterSampler, analytic_light_at};

/// Longest chain of mirror / glass bounces followed.
pub const MAX_SPECULAR_DEPTH: u32 = 8;

/// Sky visibility rays per shading point, one per cell of a 2 x 2 stratification of the
/// cosine-hemisphere square. With one ray the sky term was binary per sample, which made
/// shadowed regions lit only by the sky very noisy at low spp (measured: the demo's shadows);
/// four stratified rays cost three extra shadow rays per path.
pub const SKY_RAYS: u32 = 4;

/// Shades camera rays against a scene and its BVH.
pub struct Shader<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a Bvh,
    pub emitters: EmitterSampler,
}

impl<'a> Shader<'a> {
    pub fn new(scene: &'a Scene, bvh: &'a Bvh) -> Self {
        Self {
            scene,
            bvh,
            emitters: EmitterSampler::new(scene),
        }
    }

    /// Radiance arriving along `ray`; `rays` counts every ray traced.
    pub fn radiance(&self, ray: Ray, rng: &mut Rng, rays: &mut u64) -> Vec3 {
        self.radiance_from(ray, None, rng, rays)
    }

    /// Radiance arriving along `ray` whose first surface is the known `hit` (not traced, not
    /// counted): shades a surface found by another visibility method, e.g. a rasterized depth
    /// layer behind the nearest surface (view synthesis, `parallax_synth`). Everything after
    /// the first surface (shadow rays, specular chains) is traced as in [`Self::radiance`].
    pub fn radiance_from_hit(&self, ray: Ray, hit: Hit, rng: &mut Rng, rays: &mut u64) -> Vec3 {
        self.radiance_from(ray, Some(hit), rng, rays)
    }

    fn radiance_from(
        &self,
        mut ray: Ray,
        mut first: Option<Hit>,
        rng: &mut Rng,
        rays: &mut u64,
    ) -> Vec3 {
        let mut throughput = Vec3::ONE;
        let mut radiance = Vec3::ZERO;
        for _ in 0..=MAX_SPECULAR_DEPTH {
            let hit = match first.take() {
                Some(h) => h,
                None => {
                    *rays += 1;
                    let Some(hit) = self.bvh.closest_hit(&ray) else {
                        return radiance + throughput * self.scene.environment;
                    };
                    hit
                }
            };
            let s = SurfacePoint::new(self.scene, &ray, &hit);
            let wo = -ray.dir;
            if s.front_face {
                radiance += throughput * s.material.emissive;
            }
            let n = s.shading_normal;
            let next_dir = match s.material.kind {
                MaterialKind::Standard => {
                    return radiance + throughput * self.direct(&s, wo, rng, rays);
                }
                MaterialKind::Mirror => {
                    throughput *= s.albedo;
                    brdf::reflect(wo, n)
                }
                MaterialKind::Dielectric { ior } => {
                    let eta = if s.front_face { ior } else { 1.0 / ior };
                    let f = brdf::fresnel_dielectric(wo.dot(n).clamp(0.0, 1.0), eta);
                    match brdf::refract(wo, n, eta) {
                        Some(t) if rng.next_f32() >= f => t,
                        _ => brdf::reflect(wo, n),
                    }
                }
            };
            if throughput.max_element() <= 0.0 {
                break;
            }
            ray = Ray::new(s.spawn_origin(next_dir), next_dir);
        }
        radiance
    }

    /// Is the segment from `origin` along `dir` free of geometry up to `t_max`?
    fn visible(&self, origin: Vec3, dir: Vec3, t_max: f32, rays: &mut u64) -> bool {
        *rays += 1;
        !self.bvh.any_hit(&Ray::segment(origin, dir, 0.0, t_max))
    }

    /// Direct light at a standard (metallic-roughness) surface.
    fn direct(&self, s: &SurfacePoint, wo: Vec3, rng: &mut Rng, rays: &mut u64) -> Vec3 {
        let surf = Surface {
            albedo: s.albedo,
            roughness: s.material.roughness,
            metallic: s.material.metallic,
        };
        let n = s.shading_normal;
        let mut l = Vec3::ZERO;
        for light in &self.scene.lights {
            let Some((wi, dist, irradiance)) = analytic_light_at(light, s.position) else {
                continue;
            };
            let f = brdf::eval_cos(&surf, n, wo, wi);
            if f.max_element() <= 0.0 || wi.dot(s.geometric_normal) <= 0.0 {
                continue;
            }
            let o = s.spawn_origin(wi);
            let t_max = if dist.is_finite() {
                (s.position + wi * dist - o).length() * 0.999
            } else {
                f32::INFINITY
            };
            if self.visible(o, wi, t_max, rays) {
                l += f * irradiance;
            }
        }
        if let Some(e) = self
            .emitters
            .sample(self.scene, rng.next_f32(), rng.next_vec2())
        {
            let d = e.position - s.position;
            let dist2 = d.length_squared();
            let dist = dist2.sqrt();
            let wi = d / dist;
            let cos_l = e.normal.dot(-wi);
            let f = brdf::eval_cos(&surf, n, wo, wi);
            if cos_l > 0.0 && f.max_element() > 0.0 && wi.dot(s.geometric_normal) > 0.0 {
                let o = s.spawn_origin(wi);
                let t_max = (e.position - o).length() * 0.999;
                if self.visible(o, wi, t_max, rays) {
                    l += f * e.radiance * cos_l / (dist2 * e.pdf_area);
                }
            }
        }
        let env = self.scene.environment;
        if env.max_element() > 0.0 && surf.metallic < 1.0 {
            // Cosine-weighted directions: f_d * L_env * cos / pdf = albedo * L_env (pdf = cos/pi).
            let frame = Frame::from_normal(n);
            let mut visible = 0u32;
            for i in 0..SKY_RAYS {
                let u = rng.next_vec2();
                let cell = Vec2::new((i % 2) as f32, (i / 2) as f32);
                let wi = frame.to_world(warp::cosine_hemisphere((cell + u) * 0.5));
                if wi.dot(s.geometric_normal) > 0.0
                    && self.visible(s.spawn_origin(wi), wi, f32::INFINITY, rays)
                {
                    visible += 1;
                }
            }
            l += env * s.albedo * (1.0 - surf.metallic) * (visible as f32 / SKY_RAYS as f32);
        }
        l
    }
}

/// A film or lens sample: the stratum centre for one sample per pixel, random otherwise.
#[inline]
pub fn sample_2d(rng: &mut Rng, spp: u32) -> Vec2 {
    if spp <= 1 {
        Vec2::splat(0.5)
    } else {
        rng.next_vec2()
    }
}
