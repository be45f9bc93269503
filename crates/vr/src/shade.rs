//! Shading of HVVR visibility entries (Hunt et al. 2018, §5.6): a (triangle, ray) pair from the
//! visibility buffer becomes a colour. The hit is recomputed from the triangle — the buffer
//! keeps only triangle indices — by intersecting the ray with the triangle's plane; the
//! barycentrics of that point interpolate normals and texture coordinates, and the material /
//! texture lookup is the reference renderer's ([`SurfacePoint`]). The BRDF is the reference's
//! GGX + Lambert ([`parallax_render::brdf::eval_cos`], Walter et al. 2007).
//!
//! Light (direct only — HVVR is a primary-visibility ray caster, no secondary rays):
//! - analytic lights (point, spot, directional) of the scene;
//! - emissive triangles as point-like emitters at their centroids: a spot light of intensity
//!   `L_e * area` facing along the triangle's normal with a 90 degree cone, whose smooth
//!   KHR falloff is `cos^2` (a Lambertian patch would be `cos`: an approximation), up to
//!   [`MAX_EMITTERS`] of them by power (the reference samples them stochastically; this shader
//!   is deterministic so MSAA and SSAA differ only by where they shade);
//! - the environment as ambient `env * albedo * (1 - metallic)`, unoccluded without shadows;
//!   with shadows, times the sky visibility as the reference renderer estimates it, with
//!   [`SKY_RAYS`] cosine-distributed rays stratified 4 x 4 (the reference takes 4 per sample
//!   over several samples per pixel; this shader shades a pixel's triangle once), their jitter
//!   a hash of the shading point's position so the shader stays deterministic;
//! - emission seen directly.
//!
//! **Shadows are optional** ([`ShadeOptions::shadows`], off by default as in HVVR): one BVH
//! shadow ray per light and shading point, and the sky visibility rays. Mirrors and glass get no reflection / refraction:
//! they are shaded as smooth metal / smooth dielectric under the direct light (a simplification).
//!
//! Tonemapping is the filmic curve of the core PNG writer
//! ([`parallax_core::image::png::Tonemap::AcesFilmic`], Narkowicz 2015's ACES fit), applied
//! when images are written: shading returns linear radiance.

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, Hit};
use parallax_core::Ray;
use parallax_core::math::Frame;
use parallax_core::sampling::{Rng, splitmix64, warp};
use parallax_scene::{Light, MaterialKind, Scene};

use parallax_render::brdf::{self, Surface};
use parallax_render::lights::analytic_light_at;
use parallax_render::reference::surface::SurfacePoint;

/// Sky visibility rays per shading point with shadows on (4 x 4 strata).
pub const SKY_RAYS: u32 = 16;

/// Most emissive triangles used as lights (the most powerful ones).
pub const MAX_EMITTERS: usize = 256;

/// Shading switches.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadeOptions {
    /// Trace a shadow ray per light (not in HVVR; off by default).
    pub shadows: bool,
}

/// Deterministic direct-light shader for visibility entries.
pub struct VrShader<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a Bvh,
    pub opts: ShadeOptions,
    /// Analytic lights plus emissive triangles as point lights.
    lights: Vec<Light>,
}

/// Ray parameter and barycentrics `(t, u, v)` of the point where `ray` meets the plane of
/// triangle `[a, b, c]`, barycentrics clamped onto the triangle (rays from the visibility
/// buffer hit it; the clamp only absorbs rounding at edges). `None` for a ray parallel to the
/// plane or a degenerate triangle.
pub fn plane_hit(ray: &Ray, [a, b, c]: [Vec3; 3]) -> Option<(f32, f32, f32)> {
    let e1 = b - a;
    let e2 = c - a;
    let n = e1.cross(e2);
    let denom = n.dot(ray.dir);
    if denom == 0.0 || n.length_squared() == 0.0 {
        return None;
    }
    let t = n.dot(a - ray.origin) / denom;
    let p = ray.origin + ray.dir * t - a;
    // Solve p = u e1 + v e2 in the plane (normal equations, Cramer's rule).
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (p1, p2) = (p.dot(e1), p.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det == 0.0 || !t.is_finite() {
        return None;
    }
    let mut u = ((d22 * p1 - d12 * p2) / det).max(0.0);
    let mut v = ((d11 * p2 - d12 * p1) / det).max(0.0);
    let s = u + v;
    if s > 1.0 {
        u /= s;
        v /= s;
    }
    Some((t, u, v))
}

impl<'a> VrShader<'a> {
    pub fn new(scene: &'a Scene, bvh: &'a Bvh, opts: ShadeOptions) -> Self {
        let mut lights = scene.lights.clone();
        let mesh = &scene.mesh;
        let mut emitters: Vec<(f32, Light)> = Vec::new();
        for (i, &m) in mesh.material_ids.iter().enumerate() {
            let mat = &scene.materials[m as usize];
            if !mat.is_emissive() {
                continue;
            }
            let [a, b, c] = mesh.triangle(i);
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            let n = cross.normalize_or_zero();
            if area <= 0.0 || n == Vec3::ZERO {
                continue;
            }
            let centroid = (a + b + c) / 3.0;
            // A one-sided patch as a spot light with a 90 degree cone around its normal.
            let intensity = mat.emissive * area;
            emitters.push((
                intensity.max_element(),
                Light::Spot {
                    position: centroid + n * 1e-4,
                    direction: n,
                    intensity,
                    inner_angle: 0.0,
                    outer_angle: std::f32::consts::FRAC_PI_2,
                },
            ));
        }
        emitters.sort_by(|a, b| b.0.total_cmp(&a.0));
        lights.extend(emitters.into_iter().take(MAX_EMITTERS).map(|(_, l)| l));
        Self {
            scene,
            bvh,
            opts,
            lights,
        }
    }

    /// Radiance leaving triangle `prim` towards the origin of `ray` at the point `ray` meets
    /// it; the environment when the triangle cannot be hit by the ray (parallel).
    pub fn shade(&self, ray: &Ray, prim: u32) -> Vec3 {
        let Some((t, u, v)) = plane_hit(ray, self.scene.mesh.triangle(prim as usize)) else {
            return self.scene.environment;
        };
        let hit = Hit { prim, t, u, v };
        let s = SurfacePoint::new(self.scene, ray, &hit);
        let wo = -ray.dir;
        let mut l = if s.front_face {
            s.material.emissive
        } else {
            Vec3::ZERO
        };
        let surf = match s.material.kind {
            MaterialKind::Standard => Surface {
                albedo: s.albedo,
                roughness: s.material.roughness,
                metallic: s.material.metallic,
            },
            MaterialKind::Mirror => Surface {
                albedo: s.albedo,
                roughness: 0.05,
                metallic: 1.0,
            },
            MaterialKind::Dielectric { .. } => Surface {
                albedo: s.albedo,
                roughness: 0.05,
                metallic: 0.0,
            },
        };
        let n = s.shading_normal;
        for light in &self.lights {
            let Some((wi, dist, irradiance)) = analytic_light_at(light, s.position) else {
                continue;
            };
            if wi.dot(s.geometric_normal) <= 0.0 {
                continue;
            }
            let f = brdf::eval_cos(&surf, n, wo, wi);
            if f.max_element() <= 0.0 {
                continue;
            }
            if self.opts.shadows {
                let o = s.spawn_origin(wi);
                let t_max = if dist.is_finite() {
                    (s.position + wi * dist - o).length() * 0.999
                } else {
                    f32::INFINITY
                };
                if self.bvh.any_hit(&Ray::segment(o, wi, 0.0, t_max)) {
                    continue;
                }
            }
            l += f * irradiance;
        }
        let env = self.scene.environment;
        if env.max_element() <= 0.0 || surf.metallic >= 1.0 {
            return l;
        }
        let sky = if self.opts.shadows {
            self.sky_visibility(&s)
        } else {
            1.0
        };
        l + env * surf.albedo * (1.0 - surf.metallic) * sky
    }

    /// Fraction of [`SKY_RAYS`] cosine-distributed rays (4 x 4 strata over the hemisphere of
    /// the shading normal) from `s` that escape the scene, as the reference renderer's sky term;
    /// the jitter within each stratum comes from a hash of the position's bits.
    fn sky_visibility(&self, s: &SurfacePoint) -> f32 {
        let p = s.position.to_array().map(f32::to_bits);
        let key = (p[0] as u64) ^ ((p[1] as u64) << 21) ^ ((p[2] as u64) << 42);
        let mut rng = Rng::new(splitmix64(key), 0x5ca1ab1e);
        let frame = Frame::from_normal(s.shading_normal);
        let mut visible = 0u32;
        for i in 0..SKY_RAYS {
            let cell = Vec2::new((i % 4) as f32, (i / 4) as f32);
            let wi = frame.to_world(warp::cosine_hemisphere((cell + rng.next_vec2()) * 0.25));
            if wi.dot(s.geometric_normal) > 0.0
                && !self
                    .bvh
                    .any_hit(&Ray::segment(s.spawn_origin(wi), wi, 0.0, f32::INFINITY))
            {
                visible += 1;
            }
        }
        visible as f32 / SKY_RAYS as f32
    }

    /// Radiance of a subsample that hit nothing.
    pub fn background(&self) -> Vec3 {
        self.scene.environment
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_hit_recovers_barycentrics() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::NEG_Z);
        let (t, u, v) = plane_hit(&ray, tri).unwrap();
        assert!((t - 2.0).abs() < 1e-6 && (u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        // Outside: clamped onto the triangle.
        let ray = Ray::new(Vec3::new(1.0, 1.0, 1.0), Vec3::NEG_Z);
        let (_, u, v) = plane_hit(&ray, tri).unwrap();
        assert!((u + v - 1.0).abs() < 1e-6);
        assert!(plane_hit(&Ray::new(Vec3::Z, Vec3::X), tri).is_none());
    }
}
