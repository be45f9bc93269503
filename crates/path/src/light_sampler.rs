//! Next-event estimation: which light a shading point connects to, and the density with which
//! it would have picked a direction that a BSDF sample found by chance (for MIS).
//!
//! Two connections per shading point with a smooth BSDF lobe:
//! - **delta lights** (point, spot, directional): one, chosen with probability proportional to
//!   the luminance of the irradiance it sends to the shading point, unoccluded (point
//!   `I / d²`, spot the same with its cone falloff, directional `E`), when the scene has at
//!   most [`LOCAL_CHOICE_MAX`] of them; with more, proportional to its power (point `4π I`,
//!   spot `2π (1 - (cos θ_in + cos θ_out)/2) I`, directional `π r² E` with `r` the scene's
//!   bounding radius), one table for the whole scene. The connection's value is the
//!   irradiance divided by the choice probability, so either choice has the same expectation;
//!   the choice at the point follows the light that dominates there (a lamp under an arcade
//!   where the sun is blocked: `docs/notes/path.md`, 2026-12-04, 1.6-12x less variance on the
//!   atrium). They cannot be hit by BSDF samples, so no MIS;
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
//! | [`LOCAL_CHOICE_MAX`] | usize | 8 | most delta lights chosen among per shading point (each is evaluated there) |
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
    delta_local: Vec<LocalWeight>,
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

/// Up to this many delta lights, the one a shading point connects to is chosen by the
/// irradiance each sends to the point; beyond, by power.
pub const LOCAL_CHOICE_MAX: usize = 8;

/// A delta light's weight in the choice at a shading point, with what it needs precomputed.
#[derive(Clone, Copy, Debug)]
enum LocalWeight {
    /// `lum(I) / |position - p|²`.
    Point { position: Vec3, lum: f32 },
    /// `lum(E)`, the same at every point.
    Directional { lum: f32 },
    /// The luminance of [`analytic_light_at`]'s irradiance (cone falloff included).
    Spot,
}

impl LocalWeight {
    fn new(light: &Light) -> Self {
        match *light {
            Light::Point {
                position,
                intensity,
            } => Self::Point {
                position,
                lum: luminance(intensity),
            },
            Light::Directional { irradiance, .. } => Self::Directional {
                lum: luminance(irradiance),
            },
            Light::Spot { .. } => Self::Spot,
        }
    }

    /// The luminance of the irradiance `light` (which this was made from) sends to `p`
    /// perpendicular to its direction; 0 where [`analytic_light_at`] gives none.
    #[inline]
    fn at(&self, light: &Light, p: Vec3) -> f32 {
        match *self {
            Self::Point { position, lum } => {
                let dist2 = (position - p).length_squared();
                if dist2 > 0.0 { lum / dist2 } else { 0.0 }
            }
            Self::Directional { lum } => lum,
            Self::Spot => analytic_light_at(light, p).map_or(0.0, |l| luminance(l.2)),
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
            delta_local: delta.iter().map(LocalWeight::new).collect(),
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

    /// One delta light seen from `p`, chosen with `u`: by its irradiance at `p` when there are
    /// at most [`LOCAL_CHOICE_MAX`] delta lights, else by power (see the module docs).
    #[inline]
    pub fn sample_delta(&self, p: Vec3, u: f32) -> Option<LightSample> {
        match self.delta.len() {
            0 => None,
            1 => {
                let (wi, dist, irradiance) = analytic_light_at(&self.delta[0], p)?;
                Some(LightSample {
                    wi,
                    dist,
                    value: irradiance,
                    pdf: 0.0,
                })
            }
            n if n <= LOCAL_CHOICE_MAX => self.sample_delta_local(p, u),
            _ => self.sample_delta_by_power(p, u),
        }
    }

    /// The delta light chosen with probability proportional to its weight at `p`
    /// ([`LocalWeight::at`]: the luminance of the irradiance it sends to `p`, unoccluded).
    /// Every light that can add something has a positive probability, and the value is
    /// divided by that probability, so the estimate keeps its expectation.
    #[inline]
    fn sample_delta_local(&self, p: Vec3, u: f32) -> Option<LightSample> {
        let mut weight = [0.0f32; LOCAL_CHOICE_MAX];
        let mut total = 0.0f32;
        for ((w, local), light) in weight.iter_mut().zip(&self.delta_local).zip(&self.delta) {
            // `max` also turns a NaN weight into 0; an infinite one fails the check below.
            *w = local.at(light, p).max(0.0);
            total += *w;
        }
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let target = u * total;
        let mut acc = 0.0f32;
        let mut chosen = None;
        for (k, &w) in weight[..self.delta.len()].iter().enumerate() {
            if w > 0.0 {
                acc += w;
                chosen = Some(k);
                if target < acc {
                    break;
                }
            }
        }
        let k = chosen?;
        let (wi, dist, irradiance) = analytic_light_at(&self.delta[k], p)?;
        Some(LightSample {
            wi,
            dist,
            value: irradiance * (total / weight[k]),
            pdf: 0.0,
        })
    }

    /// The delta light chosen by power (the scene-wide table), for scenes with many.
    fn sample_delta_by_power(&self, p: Vec3, u: f32) -> Option<LightSample> {
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

    /// The expectation over `u` of a delta connection's value (midpoint rule over `steps`).
    fn mean_delta_value(ls: &LightSampler, p: Vec3, steps: u32) -> Vec3 {
        (0..steps)
            .filter_map(|i| ls.sample_delta(p, (i as f32 + 0.5) / steps as f32))
            .map(|l| l.value)
            .sum::<Vec3>()
            / steps as f32
    }

    #[test]
    fn delta_choice_at_the_point_follows_irradiance_and_keeps_the_expectation() {
        let mut s = Scene::load("atrium").unwrap();
        // A near lamp (irradiance 2 at p), a far one (1/8) and the sun (1).
        s.lights = vec![
            Light::Point {
                position: Vec3::new(0.0, 1.0, 0.0),
                intensity: Vec3::splat(2.0),
            },
            Light::Point {
                position: Vec3::new(0.0, 4.0, 0.0),
                intensity: Vec3::splat(2.0),
            },
            Light::Directional {
                direction: Vec3::new(0.0, -1.0, 0.0),
                irradiance: Vec3::splat(1.0),
            },
        ];
        let ls = LightSampler::new(&s, 0.0);
        let total = 2.0 + 0.125 + 1.0;
        // u below 2 / total picks the near lamp: value = irradiance / (2 / total).
        let l = ls.sample_delta(Vec3::ZERO, 0.5).unwrap();
        assert_eq!(l.dist, 1.0);
        assert!((l.value.x - total).abs() < 1e-5, "{}", l.value);
        let l = ls.sample_delta(Vec3::ZERO, 0.99).unwrap();
        assert!(l.dist.is_infinite());
        assert!((l.value.x - total).abs() < 1e-5, "{}", l.value);
        // Every light is reached, and the mean over u is the sum of the irradiances.
        let mean = mean_delta_value(&ls, Vec3::ZERO, 4096);
        assert!((mean.x - total).abs() < 1e-3 * total, "{mean}");
        let far = (0..64)
            .filter_map(|i| ls.sample_delta(Vec3::ZERO, (i as f32 + 0.5) / 64.0))
            .filter(|l| l.dist == 4.0)
            .count();
        assert!(far > 0);
    }

    #[test]
    fn many_delta_lights_are_chosen_by_power_with_the_same_expectation() {
        let mut s = Scene::load("atrium").unwrap();
        s.lights = (0..LOCAL_CHOICE_MAX + 2)
            .map(|i| Light::Point {
                position: Vec3::new(i as f32, 3.0, 0.0),
                intensity: Vec3::splat(1.0 + i as f32),
            })
            .collect();
        let ls = LightSampler::new(&s, 0.0);
        let p = Vec3::new(2.0, 0.0, 1.0);
        let want: f32 = s
            .lights
            .iter()
            .map(|l| analytic_light_at(l, p).unwrap().2.x)
            .sum();
        let mean = mean_delta_value(&ls, p, 1 << 14);
        assert!((mean.x - want).abs() < 2e-3 * want, "{mean} vs {want}");
        // By power: equal intensities at different distances get equal probabilities.
        let l = ls.sample_delta(p, 0.0).unwrap();
        let pmf = l.value.x.recip() * analytic_light_at(&s.lights[0], p).unwrap().2.x;
        assert!((pmf - ls.delta_pmf[0]).abs() < 1e-5);
    }

    #[test]
    fn delta_choice_is_by_irradiance_and_divides_by_it() {
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
