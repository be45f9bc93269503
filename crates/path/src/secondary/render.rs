//! The Whitted-style secondary-ray pass (module docs of [`super`]), level by level as a
//! wavefront: the surface points of one level are shaded in parallel, their shadow rays and
//! their reflection / refraction rays are gathered into one batch per effect, each batch is
//! traced in parallel chunks through the tracer, and the answers make the next level. Every
//! batch is kept ([`Batch`]: rays and answers) so other tracers can be asked the same rays.

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_core::image::GBuffer;
use parallax_core::{Image, Ray, Rgb, WorldHit, WorldStats, WorldTracer};
use parallax_render::brdf::{self, Surface};
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_scene::{MaterialKind, Scene};
use rayon::prelude::*;

use super::lights::{WhittedLight, light_at, whitted_lights};
use super::options::{Effect, SecondaryError, SecondaryOptions};

/// Rays handed to the tracer per parallel task.
pub const CHUNK: usize = 1024;

/// Children weaker than this (largest channel of the path weight) are not traced.
pub const MIN_WEIGHT: f32 = 1e-4;

/// A tracer's answers to one batch.
#[derive(Clone, Debug, PartialEq)]
pub enum Answers {
    /// Closest hits (reflection, refraction).
    Closest(Vec<Option<WorldHit>>),
    /// Occlusion (shadow rays).
    Occluded(Vec<bool>),
}

impl Answers {
    pub fn len(&self) -> usize {
        match self {
            Answers::Closest(v) => v.len(),
            Answers::Occluded(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The rays of one effect at one level, with the answers of the tracer that rendered them.
#[derive(Clone, Debug)]
pub struct Batch {
    pub effect: Effect,
    /// 0 = rays leaving the primary hits.
    pub bounce: u32,
    pub rays: Vec<Ray>,
    pub answers: Answers,
    pub stats: WorldStats,
    /// Wall time of tracing the batch.
    pub ms: f64,
}

/// A rendered image and the batches that made it.
#[derive(Clone, Debug)]
pub struct SecondaryImage {
    pub image: Image<Rgb>,
    pub batches: Vec<Batch>,
    /// Wall time of the whole pass (shading included).
    pub ms: f64,
}

impl SecondaryImage {
    /// Rays traced (all batches).
    pub fn rays(&self) -> usize {
        self.batches.iter().map(|b| b.rays.len()).sum()
    }
}

/// Closest hits of `rays`, in parallel chunks (answers in ray order), with work and wall ms.
pub fn trace_closest(
    tracer: &dyn WorldTracer,
    rays: &[Ray],
) -> (Vec<Option<WorldHit>>, WorldStats, f64) {
    let start = Instant::now();
    let mut out = vec![None; rays.len()];
    let stats = out
        .par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .map(|(o, r)| {
            let mut s = WorldStats::default();
            tracer.closest_hits(r, o, &mut s);
            s
        })
        .sum();
    (out, stats, start.elapsed().as_secs_f64() * 1e3)
}

/// Occlusion of `rays`, in parallel chunks, with work and wall ms.
pub fn trace_occluded(tracer: &dyn WorldTracer, rays: &[Ray]) -> (Vec<bool>, WorldStats, f64) {
    let start = Instant::now();
    let mut out = vec![false; rays.len()];
    let stats = out
        .par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .map(|(o, r)| {
            let mut s = WorldStats::default();
            for (o, ray) in o.iter_mut().zip(r) {
                *o = tracer.occluded(ray, &mut s);
            }
            s
        })
        .sum();
    (out, stats, start.elapsed().as_secs_f64() * 1e3)
}

/// A surface point reached by a ray, with the weight of its path.
#[derive(Clone, Copy, Debug)]
struct Vertex {
    pixel: u32,
    ray: Ray,
    weight: Vec3,
    hit: WorldHit,
}

/// A shadow ray and what it brings if unoccluded.
#[derive(Clone, Copy)]
struct ShadowRay {
    pixel: u32,
    ray: Ray,
    contribution: Vec3,
}

/// A reflection or refraction ray.
#[derive(Clone, Copy)]
struct Child {
    pixel: u32,
    ray: Ray,
    weight: Vec3,
    effect: Effect,
}

/// The pixel-centre camera ray of `(x, y)`.
pub fn pixel_ray(camera: &Pinhole, x: u32, y: u32) -> Option<Ray> {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    camera
        .generate_ray(film, Vec2::splat(0.5), 0)
        .map(|c| c.ray)
}

/// The primary hits of the rasterized G-buffer `g` as exact hits on their triangles (`t` from
/// the sample's position along the pixel's camera ray); pixels that saw nothing are `None`.
fn primary(camera: &Pinhole, g: &GBuffer) -> Vec<Option<Vertex>> {
    let w = camera.width;
    (0..camera.width * camera.height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let ray = pixel_ray(camera, x, y)?;
            if !g.is_hit(x, y) {
                return None;
            }
            let k = g.index(x, y);
            let t = (g.position[k] - ray.origin).dot(ray.dir) / ray.dir.length_squared();
            let hit = WorldHit::exact(&ray, t, g.primitive_id[k], g.barycentrics[k]);
            Some(Vertex {
                pixel: i,
                ray,
                weight: Vec3::ONE,
                hit,
            })
        })
        .collect()
}

struct Shading<'a> {
    scene: &'a Scene,
    lights: Vec<WhittedLight>,
    opts: SecondaryOptions,
}

impl Shading<'_> {
    fn surface(&self, v: &Vertex) -> SurfacePoint<'_> {
        SurfacePoint::from_world_hit(self.scene, &v.ray, &v.hit)
    }

    /// Emission and the ambient term of `v` (weighted).
    fn local(&self, v: &Vertex) -> Vec3 {
        let s = self.surface(v);
        let mut c = if s.front_face {
            s.material.emissive
        } else {
            Vec3::ZERO
        };
        if s.material.kind == MaterialKind::Standard {
            c += self.scene.environment * s.albedo * (1.0 - s.material.metallic);
        }
        v.weight * c
    }

    /// The shadow rays of `v` (standard surfaces only), one per light that reaches it.
    fn shadow_rays(&self, v: &Vertex) -> impl Iterator<Item = ShadowRay> + '_ {
        let s = self.surface(v);
        let standard = s.material.kind == MaterialKind::Standard;
        let surf = Surface {
            albedo: s.albedo,
            roughness: s.material.roughness,
            metallic: s.material.metallic,
        };
        let (wo, n, ng) = (-v.ray.dir.normalize(), s.shading_normal, s.geometric_normal);
        let (pixel, weight, position) = (v.pixel, v.weight, s.position);
        let origin = move |wi: Vec3| s.spawn_origin(wi);
        self.lights
            .iter()
            .filter(move |_| standard)
            .filter_map(move |light| {
                let (wi, dist, irradiance) = light_at(light, position)?;
                let f = brdf::eval_cos(&surf, n, wo, wi);
                if f.max_element() <= 0.0 || wi.dot(ng) <= 0.0 {
                    return None;
                }
                let o = origin(wi);
                let t_max = if dist.is_finite() {
                    (position + wi * dist - o).length() * 0.999
                } else {
                    f32::INFINITY
                };
                Some(ShadowRay {
                    pixel,
                    ray: Ray::segment(o, wi, 0.0, t_max),
                    contribution: weight * f * irradiance,
                })
            })
    }

    /// The reflection / refraction rays of `v` (mirror and glass).
    fn children(&self, v: &Vertex) -> [Option<Child>; 2] {
        let s = self.surface(v);
        let e = self.opts.effects;
        let wo = -v.ray.dir.normalize();
        let n = s.shading_normal;
        let child = |dir: Vec3, weight: Vec3, effect: Effect| {
            (weight.max_element() >= MIN_WEIGHT && e.has(effect)).then(|| Child {
                pixel: v.pixel,
                ray: Ray::new(s.spawn_origin(dir), dir),
                weight,
                effect,
            })
        };
        match s.material.kind {
            MaterialKind::Standard => [None, None],
            MaterialKind::Mirror => [
                child(brdf::reflect(wo, n), v.weight * s.albedo, Effect::Reflect),
                None,
            ],
            MaterialKind::Dielectric { ior } => {
                let eta = if s.front_face { ior } else { 1.0 / ior };
                let f = brdf::fresnel_dielectric(wo.dot(n).clamp(0.0, 1.0), eta);
                let refracted = brdf::refract(wo, n, eta);
                let f = if refracted.is_some() { f } else { 1.0 };
                [
                    child(brdf::reflect(wo, n), v.weight * f, Effect::Reflect),
                    refracted.and_then(|t| child(t, v.weight * (1.0 - f), Effect::Refract)),
                ]
            }
        }
    }
}

/// Renders `camera`'s view of `scene` from its rasterized G-buffer `gbuffer` (same size),
/// tracing every secondary ray through `tracer` (module docs of [`super`]).
pub fn render(
    scene: &Scene,
    camera: &Pinhole,
    gbuffer: &GBuffer,
    tracer: &dyn WorldTracer,
    opts: &SecondaryOptions,
) -> Result<SecondaryImage, SecondaryError> {
    opts.validate()?;
    let (w, h) = (camera.width, camera.height);
    if gbuffer.width() != w || gbuffer.height() != h {
        return Err(SecondaryError::InvalidOptions(format!(
            "G-buffer is {}x{}, the camera {w}x{h}",
            gbuffer.width(),
            gbuffer.height()
        )));
    }
    let start = Instant::now();
    let shading = Shading {
        scene,
        lights: whitted_lights(scene),
        opts: *opts,
    };
    let env = scene.environment;
    let mut color = vec![Vec3::ZERO; w as usize * h as usize];
    let mut vertices = Vec::new();
    for (i, v) in primary(camera, gbuffer).into_iter().enumerate() {
        match v {
            Some(v) => vertices.push(v),
            None => color[i] = env,
        }
    }
    let mut batches = Vec::new();
    for bounce in 0..=opts.bounces {
        if vertices.is_empty() {
            break;
        }
        let local: Vec<Vec3> = vertices.par_iter().map(|v| shading.local(v)).collect();
        for (v, c) in vertices.iter().zip(&local) {
            color[v.pixel as usize] += *c;
        }
        let shadows: Vec<ShadowRay> = vertices
            .par_iter()
            .flat_map_iter(|v| shading.shadow_rays(v))
            .collect();
        if opts.effects.shadow && !shadows.is_empty() {
            let rays: Vec<Ray> = shadows.iter().map(|s| s.ray).collect();
            let (occluded, stats, ms) = trace_occluded(tracer, &rays);
            for (s, &o) in shadows.iter().zip(&occluded) {
                if !o {
                    color[s.pixel as usize] += s.contribution;
                }
            }
            batches.push(Batch {
                effect: Effect::Shadow,
                bounce,
                rays,
                answers: Answers::Occluded(occluded),
                stats,
                ms,
            });
        } else {
            for s in &shadows {
                color[s.pixel as usize] += s.contribution;
            }
        }
        if bounce == opts.bounces {
            break;
        }
        let children: Vec<Child> = vertices
            .par_iter()
            .flat_map_iter(|v| shading.children(v).into_iter().flatten())
            .collect();
        let mut next = Vec::new();
        for effect in [Effect::Reflect, Effect::Refract] {
            let mine: Vec<&Child> = children.iter().filter(|c| c.effect == effect).collect();
            if mine.is_empty() {
                continue;
            }
            let rays: Vec<Ray> = mine.iter().map(|c| c.ray).collect();
            let (hits, stats, ms) = trace_closest(tracer, &rays);
            for (c, hit) in mine.iter().zip(&hits) {
                match hit {
                    None => color[c.pixel as usize] += c.weight * env,
                    Some(hit) => next.push(Vertex {
                        pixel: c.pixel,
                        ray: c.ray,
                        weight: c.weight,
                        hit: *hit,
                    }),
                }
            }
            batches.push(Batch {
                effect,
                bounce,
                rays,
                answers: Answers::Closest(hits),
                stats,
                ms,
            });
        }
        vertices = next;
    }
    Ok(SecondaryImage {
        image: Image::from_vec(w, h, color)?,
        batches,
        ms: start.elapsed().as_secs_f64() * 1e3,
    })
}
