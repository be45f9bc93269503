//! The path-tracing estimator of one path vertex: the shade pass of the deferred pipeline
//! (Vardis et al. 2017, §4.2.3: "computes the lighting contribution of the current scattering
//! event" from the shading buffer and prepares the next event), written as Mitsuba 3's `path`
//! integrator (`src/integrators/path.cpp`) computes it:
//!
//! 1. **emission** of the surface hit (or of the environment on a miss), weighted against the
//!    previous vertex's emitter sampling by the power heuristic unless the previous BSDF sample
//!    was a delta lobe;
//! 2. stop when `depth + 1 >= max_depth` (Mitsuba's `max_depth`: 1 = directly visible emitters);
//! 3. **next-event estimation** at smooth BSDF lobes ([`crate::light_sampler`]): one delta light
//!    and one area-like light, each as a shadow ray carrying its unoccluded contribution (the
//!    occlusion pass adds it when the ray is free);
//! 4. **BSDF sampling** of the next direction ([`parallax_render::bsdf`]); the throughput takes
//!    the sample weight, `eta` the relative index crossed;
//! 5. **Russian roulette** from `depth >= rr_depth` (after the increment, as Mitsuba): survive
//!    with `q = min(max(throughput) · eta², 0.95)`, divide the throughput by `q`.
//!
//! With [`Integrator::final_nee`], a smooth vertex whose BSDF sample could only add emission
//! (`depth + 2 >= max_depth`) takes its light connection with full weight (no MIS: no BSDF
//! sample competes) and ends the path there. The expectation is unchanged (every light path of
//! at most `max_depth` segments is still counted once); the last closest-hit ray is saved.
//! `max_depth = 3` with it is Mäkitalo et al. 2019's sample (§4.1: one primary ray, one
//! secondary ray, light connections at both vertices).
//!
//! **Invariants:** every random number a path uses comes from its own stream
//! ([`PathState::rng`], seeded by pixel, sample and channel), drawn in the same order whatever
//! the tracer and the thread, so equal hits give equal images; a path's radiance only grows by
//! finite, non-negative terms (non-finite BSDF or light values end the path).
//!
//! Shading frame: the interpolated normal of [`SurfacePoint`] (which faces the incoming ray),
//! flipped once more when `wo` lies behind it (silhouettes of interpolated normals), with the
//! model seen from that side ([`Bsdf::flipped`]; Mitsuba decides sides by the shading frame
//! too), so every model sees `wo.z >= 0`.

use glam::Vec3;
use parallax_core::math::Frame;
use parallax_core::sampling::Rng;
use parallax_core::{Ray, WorldHit};
use parallax_render::bsdf::{Bsdf, MaterialMode};
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::Scene;

use crate::light_sampler::LightSampler;
use crate::mis::power_heuristic;

/// Shadow rays stop this fraction short of the light point (so they do not hit the emitter).
pub const SHADOW_EPSILON: f32 = 1e-3;

/// [`PathState::channel`] of a path that carries all three colour channels.
pub const ALL_CHANNELS: u8 = 3;

/// The state of one path between bounces (the shading buffer's `G_k` plus the "operators"
/// of DIRT §4.2: throughput and the previous sample's pdf).
#[derive(Clone, Debug)]
pub struct PathState {
    /// The ray to trace next.
    pub ray: Ray,
    pub throughput: Vec3,
    /// Radiance gathered so far.
    pub radiance: Vec3,
    pub rng: Rng,
    /// Product of the relative indices of refraction crossed.
    pub eta: f32,
    /// Pdf of the BSDF sample that produced `ray` (solid angle, or lobe probability).
    pub prev_pdf: f32,
    /// Shading normal at the vertex `ray` leaves (for the environment's sampling density).
    pub prev_normal: Vec3,
    /// Tile-local pixel index.
    pub pixel: u32,
    /// Segments traced so far (0 while the camera ray is traced).
    pub depth: u32,
    /// Colour channel the path carries (0..3), or [`ALL_CHANNELS`].
    pub channel: u8,
    /// True when `ray` came from a delta lobe (or the camera).
    pub prev_delta: bool,
}

impl PathState {
    /// A path starting with camera ray `ray`.
    pub fn camera(ray: Ray, rng: Rng, pixel: u32, channel: u8) -> Self {
        Self {
            ray,
            throughput: Vec3::ONE,
            radiance: Vec3::ZERO,
            rng,
            eta: 1.0,
            prev_pdf: 1.0,
            prev_normal: Vec3::ZERO,
            pixel,
            depth: 0,
            channel,
            prev_delta: true,
        }
    }

    #[inline]
    fn add(&mut self, v: Vec3) {
        if v.is_finite() && v.min_element() >= 0.0 {
            self.radiance += v;
        }
    }
}

/// A shadow ray and the radiance it adds to path `owner` when nothing blocks it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRay {
    pub ray: Ray,
    pub contribution: Vec3,
    /// Index of the path in the current wavefront.
    pub owner: u32,
}

/// The estimator's fixed inputs.
pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub lights: LightSampler<'a>,
    pub materials: MaterialMode,
    pub max_depth: u32,
    pub rr_depth: u32,
    /// See the module docs; off by default.
    pub final_nee: bool,
}

/// A shadow ray from `s` towards `wi`, ending short of distance `dist` (infinite: unbounded).
fn shadow_ray(s: &SurfacePoint, wi: Vec3, dist: f32) -> Ray {
    let o = s.spawn_origin(wi);
    if dist.is_finite() {
        let d = s.position + wi * dist - o;
        let len = d.length();
        Ray::segment(o, d / len, 0.0, len * (1.0 - SHADOW_EPSILON))
    } else {
        Ray::new(o, wi)
    }
}

impl<'a> Integrator<'a> {
    pub fn new(
        scene: &'a Scene,
        materials: MaterialMode,
        max_depth: u32,
        rr_depth: u32,
        env_nee: f32,
    ) -> Self {
        Self {
            scene,
            lights: LightSampler::new(scene, env_nee),
            materials,
            max_depth,
            rr_depth,
            final_nee: false,
        }
    }

    /// A path whose ray left the scene: the environment, MIS-weighted.
    pub fn miss(&self, path: &mut PathState) {
        let env = self.lights.environment();
        if env.max_element() <= 0.0 {
            return;
        }
        let w = if path.prev_delta {
            1.0
        } else {
            power_heuristic(
                path.prev_pdf,
                self.lights.pdf_env(path.prev_normal, path.ray.dir),
            )
        };
        path.add(path.throughput * env * w);
    }

    /// Shades the vertex `s` of `path` (found by `hit`): adds emission, pushes shadow rays to
    /// `shadows` (owner `owner`), samples the next ray. Returns false when the path ends.
    pub fn shade(
        &self,
        path: &mut PathState,
        hit: &WorldHit,
        s: &SurfacePoint,
        shadows: &mut Vec<ShadowRay>,
        owner: u32,
    ) -> bool {
        let dir = path.ray.dir;
        let wo = -dir;
        // 1. Emission (one-sided: the front of the triangle).
        if s.front_face && s.material.is_emissive() {
            let w = if path.prev_delta {
                1.0
            } else {
                let cos_l = s.geometric_normal.dot(dir).abs();
                power_heuristic(
                    path.prev_pdf,
                    self.lights.pdf_emitter_hit(hit.prim, hit.t, cos_l),
                )
            };
            path.add(path.throughput * s.material.emissive * w);
        }
        // 2. Depth limit.
        if path.depth + 1 >= self.max_depth {
            return false;
        }
        let mut bsdf = Bsdf::from_surface(s.material, s.albedo, s.front_face, self.materials);
        let mut n = s.shading_normal;
        if wo.dot(n) < 0.0 {
            n = -n;
            bsdf = bsdf.flipped();
        }
        let frame = Frame::from_normal(n);
        let wo_l = frame.to_local(wo);
        // The last vertex of a `final_nee` path: light connections only, with full weight.
        let last = self.final_nee && path.depth + 2 >= self.max_depth && bsdf.has_smooth_lobe();
        // 3. Next-event estimation.
        if bsdf.has_smooth_lobe() {
            if self.lights.has_delta() {
                let u = path.rng.next_f32();
                if let Some(l) = self.lights.sample_delta(s.position, u) {
                    let f = bsdf.eval(wo_l, frame.to_local(l.wi));
                    let c = path.throughput * f * l.value;
                    if c.max_element() > 0.0 && c.is_finite() {
                        shadows.push(ShadowRay {
                            ray: shadow_ray(s, l.wi, l.dist),
                            contribution: c,
                            owner,
                        });
                    }
                }
            }
            if self.lights.has_area() {
                let u_pick = path.rng.next_f32();
                let u = path.rng.next_vec2();
                if let Some(l) = self.lights.sample_area(s.position, n, u_pick, u) {
                    let wi_l = frame.to_local(l.wi);
                    let f = bsdf.eval(wo_l, wi_l);
                    if f.max_element() > 0.0 {
                        let w = if last {
                            1.0
                        } else {
                            power_heuristic(l.pdf, bsdf.pdf(wo_l, wi_l))
                        };
                        let c = path.throughput * f * l.value * w;
                        if c.max_element() > 0.0 && c.is_finite() {
                            shadows.push(ShadowRay {
                                ray: shadow_ray(s, l.wi, l.dist),
                                contribution: c,
                                owner,
                            });
                        }
                    }
                }
            }
        }
        if last {
            return false;
        }
        // 4. BSDF sampling.
        let u_lobe = path.rng.next_f32();
        let u = path.rng.next_vec2();
        let Some(bs) = bsdf.sample(wo_l, u_lobe, u) else {
            return false;
        };
        let wi = frame.to_world(bs.wi);
        path.throughput *= bs.weight;
        path.eta *= bs.eta;
        path.prev_pdf = bs.pdf;
        path.prev_delta = bs.delta;
        path.prev_normal = n;
        path.depth += 1;
        // 5. Russian roulette.
        let t_max = path.throughput.max_element();
        if !(t_max > 0.0 && t_max.is_finite()) {
            return false;
        }
        if path.depth >= self.rr_depth {
            let q = (t_max * path.eta * path.eta).min(0.95);
            if path.rng.next_f32() >= q {
                return false;
            }
            path.throughput /= q;
        }
        path.ray = Ray::new(s.spawn_origin(wi), wi);
        true
    }
}
