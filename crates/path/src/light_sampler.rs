//! Next-event estimation: which light a shading point connects to, and the density with which
//! it would have picked a direction that a BSDF sample found by chance (for MIS).
//!
//! Two connections per shading point with a smooth BSDF lobe:
//! - **delta lights** (point, spot, directional): one, chosen with probability proportional to
//!   its power (point `4π I`, spot `2π (1 - (cos θ_in + cos θ_out)/2) I`, directional `π r² E` with
//!   `r` the scene's bounding radius). They cannot be hit by BSDF samples, so no MIS;
//! - **area-like lights**: the emissive triangles (one by power, a uniform point on it,
//!   [`EmitterSampler`]) and the constant environment (a cosine-weighted direction around the
//!   shading normal, which is where a constant sky's contribution to a Lambertian surface
//!   lies). The environment is chosen with probability `p_env = env_nee · share` (`share` = 1
//!   without emissive triangles, 1/2 with), the triangles with `1 - p_env`; without triangles
//!   no connection is made with probability `1 - p_env`. These are combined with BSDF sampling
//!   by the power heuristic ([`crate::mis`]).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `env_nee` | f32 | [`DEFAULT_ENV_NEE`] | how often a vertex connects to the constant environment, in [0, 1] |
//!
//! Why `env_nee` defaults to 0: BSDF sampling already importance-samples a *constant*
//! environment as well as a direction density can (the integrand is `f cos θ V`), so an
//! environment connection only adds a second sample of the same distribution (for Lambertian
//! surfaces), at the price of a long shadow ray. Whether the second sample pays depends on the
//! scene: measurements in `docs/notes/path.md`. With `env_nee > 0` the connection is
//! MIS-weighted as every other light.
//!
//! Mitsuba 3 instead picks one emitter uniformly and samples a constant environment uniformly
//! over the sphere: the estimators differ in variance, not in expectation.
//!
//! **Invariant:** [`LightSampler::pdf_emitter_hit`] and [`LightSampler::pdf_env`] return
//! exactly the density [`LightSampler::sample_area`] uses for the same direction (tested), so
//! the MIS weights of the two strategies sum to one.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};
use parallax_core::math::Frame;
use parallax_core::sampling::warp;
use parallax_render::bsdf::luminance;
use parallax_render::lights::{EmitterSampler, analytic_light_at};
use parallax_scene::{Light, Scene};

/// A connection to a light from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit world direction towards the light.
    pub wi: Vec3,
    /// Distance to the light point, infinite for the environment and directional lights.
    pub dist: f32,
    /// Radiance / pdf (area-like) or irradiance / choice probability (delta).
    pub value: Vec3,
    /// Solid-angle density of the direction, choice included (area-like; 0 for delta lights).
    pub pdf: f32,
}

/// The lights of a scene, ready to sample (see the module docs).
pub struct LightSampler<'a> {
    scene: &'a Scene,
    pub emitters: EmitterSampler,
    env: Vec3,
    /// Probability of connecting to the environment.
    p_env: f32,
    /// Probability of connecting to an emissive triangle.
    p_tri: f32,
    delta: Vec<Light>,
    delta_cdf: Vec<f32>,
    delta_pmf: Vec<f32>,
}

/// The power of a delta light for choosing among them.
fn delta_power(light: &Light, scene_radius: f32) -> f32 {
    match *light {
        Light::Point { intensity, .. } => 4.0 * PI * luminance(intensity),
        Light::Spot {
            intensity,
            inner_angle,
            outer_angle,
            ..
        } => {
            2.0 * PI * (1.0 - 0.5 * (inner_angle.cos() + outer_angle.cos())) * luminance(intensity)
        }
        Light::Directional { irradiance, .. } => {
            PI * scene_radius * scene_radius * luminance(irradiance)
        }
    }
}

/// Default of `env_nee` (see the module docs).
pub const DEFAULT_ENV_NEE: f32 = 0.0;

impl<'a> LightSampler<'a> {
    /// The lights of `scene`; `env_nee` (clamped to [0, 1]) as in the module table.
    pub fn new(scene: &'a Scene, env_nee: f32) -> Self {
        let emitters = EmitterSampler::new(scene);
        let env = scene.environment;
        let has_env = env.max_element() > 0.0;
        let q = if env_nee.is_finite() {
            env_nee.clamp(0.0, 1.0)
        } else {
            DEFAULT_ENV_NEE
        };
        let p_env = match (has_env, emitters.is_empty()) {
            (false, _) => 0.0,
            (true, true) => q,
            (true, false) => 0.5 * q,
        };
        let p_tri = if emitters.is_empty() {
            0.0
        } else {
            1.0 - p_env
        };
        let b = scene.bounds();
        let radius = if b.is_empty() {
            1.0
        } else {
            0.5 * b.extent().length().max(1e-3)
        };
        let mut delta = Vec::new();
        let mut weights = Vec::new();
        for l in &scene.lights {
            let w = delta_power(l, radius);
            if w > 0.0 && w.is_finite() {
                delta.push(l.clone());
                weights.push(w);
            }
        }
        let total: f32 = weights.iter().sum();
        let delta_pmf: Vec<f32> = weights.iter().map(|w| w / total).collect();
        let mut acc = 0.0;
        let mut delta_cdf: Vec<f32> = delta_pmf
            .iter()
            .map(|p| {
                acc += p;
                acc
            })
            .collect();
        if let Some(last) = delta_cdf.last_mut() {
            *last = 1.0;
        }
        Self {
            scene,
            emitters,
            env,
            p_env,
            p_tri,
            delta,
            delta_cdf,
            delta_pmf,
        }
    }

    /// True when there is a delta light to connect to.
    pub fn has_delta(&self) -> bool {
        !self.delta.is_empty()
    }

    /// True when there is an emissive triangle or an environment to connect to.
    pub fn has_area(&self) -> bool {
        self.p_env > 0.0 || self.p_tri > 0.0
    }

    /// The constant environment radiance.
    pub fn environment(&self) -> Vec3 {
        self.env
    }

    /// One delta light seen from `p`, chosen by power with `u`.
    #[inline]
    pub fn sample_delta(&self, p: Vec3, u: f32) -> Option<LightSample> {
        if self.delta.is_empty() {
            return None;
        }
        let k = self
            .delta_cdf
            .partition_point(|&c| c <= u)
            .min(self.delta.len() - 1);
        let (wi, dist, irradiance) = analytic_light_at(&self.delta[k], p)?;
        Some(LightSample {
            wi,
            dist,
            value: irradiance / self.delta_pmf[k],
            pdf: 0.0,
        })
    }

    /// One area-like light seen from `p` with unit shading normal `n`: `u_pick` chooses the
    /// light, `u` the point or direction.
    pub fn sample_area(&self, p: Vec3, n: Vec3, u_pick: f32, u: Vec2) -> Option<LightSample> {
        if u_pick < self.p_env {
            let wi = Frame::from_normal(n).to_world(warp::cosine_hemisphere(u));
            let pdf = self.pdf_env(n, wi);
            return (pdf > 0.0).then(|| LightSample {
                wi,
                dist: f32::INFINITY,
                value: self.env / pdf,
                pdf,
            });
        }
        if u_pick >= self.p_env + self.p_tri {
            return None; // no connection this time
        }
        let u_tri = ((u_pick - self.p_env) / self.p_tri).min(1.0);
        let e = self.emitters.sample(self.scene, u_tri, u)?;
        let d = e.position - p;
        let dist2 = d.length_squared();
        if !(dist2 > 0.0) {
            return None;
        }
        let dist = dist2.sqrt();
        let wi = d / dist;
        let cos_l = -e.normal.dot(wi);
        if cos_l <= 0.0 {
            return None; // the back of a one-sided emitter
        }
        let pdf = self.p_tri * e.pdf_area * dist2 / cos_l;
        (pdf > 0.0 && pdf.is_finite()).then(|| LightSample {
            wi,
            dist,
            value: e.radiance / pdf,
            pdf,
        })
    }

    /// Solid-angle density with which [`Self::sample_area`] picks the direction that reaches
    /// emissive triangle `prim` at distance `t` with `cos_l = |n_light · dir|`.
    pub fn pdf_emitter_hit(&self, prim: u32, t: f32, cos_l: f32) -> f32 {
        match self.emitters.pdf_area(prim) {
            Some(pa) if cos_l > 0.0 => self.p_tri * pa * t * t / cos_l,
            _ => 0.0,
        }
    }

    /// Solid-angle density with which [`Self::sample_area`] picks environment direction `dir`
    /// from a point with shading normal `n`.
    #[inline]
    pub fn pdf_env(&self, n: Vec3, dir: Vec3) -> f32 {
        self.p_env * n.dot(dir).max(0.0) * FRAC_1_PI
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    #[test]
    fn delta_choice_is_by_power_and_divides_by_it() {
        let mut s = Scene::load("atrium").unwrap();
        s.lights = vec![
            Light::Point {
                position: Vec3::new(0.0, 5.0, 0.0),
                intensity: Vec3::splat(1.0),
            },
            Light::Point {
                position: Vec3::new(0.0, 5.0, 0.0),
                intensity: Vec3::splat(3.0),
            },
        ];
        let ls = LightSampler::new(&s, 1.0);
        // u < 1/4 picks the weak light; either way value = irradiance / pmf = 4 / 25.
        for u in [0.1, 0.9] {
            let l = ls.sample_delta(Vec3::ZERO, u).unwrap();
            assert!((l.value.x - 4.0 / 25.0).abs() < 1e-6, "{}", l.value);
            assert_eq!(l.dist, 5.0);
        }
    }

    #[test]
    fn area_samples_report_the_density_of_the_hit_queries() {
        for (name, env, env_nee) in [
            ("cornell", Vec3::ZERO, 1.0),
            ("cornell", Vec3::splat(0.3), 1.0),
            ("cornell", Vec3::splat(0.3), 0.25),
        ] {
            let mut s = Scene::load(name).unwrap();
            s.environment = env;
            let ls = LightSampler::new(&s, env_nee);
            let bvh = parallax_bvh::Bvh::build(&s.mesh);
            let mut rng = Rng::new(3, 4);
            let p = Vec3::new(0.1, 0.5, 0.2);
            let n = Vec3::new(0.2, 1.0, 0.1).normalize();
            let mut checked = 0;
            for _ in 0..2000 {
                let Some(l) = ls.sample_area(p, n, rng.next_f32(), rng.next_vec2()) else {
                    continue;
                };
                let pdf = if l.dist.is_infinite() {
                    ls.pdf_env(n, l.wi)
                } else {
                    let ray = parallax_core::Ray::new(p, l.wi);
                    let Some(h) = bvh.closest_hit(&ray) else {
                        continue;
                    };
                    if ls.emitters.pdf_area(h.prim).is_none() {
                        continue; // occluded: another surface in front of the light
                    }
                    let cos_l = s.mesh.geometric_normal(h.prim as usize).dot(l.wi).abs();
                    ls.pdf_emitter_hit(h.prim, h.t, cos_l)
                };
                assert!(
                    (pdf - l.pdf).abs() <= 1e-3 * l.pdf,
                    "{name}: sampled pdf {} vs hit pdf {pdf}",
                    l.pdf
                );
                checked += 1;
            }
            assert!(checked > 500, "{checked}");
        }
    }
}
