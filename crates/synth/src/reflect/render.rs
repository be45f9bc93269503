//! The reflection pass (module docs of [`super`]): per reflective pixel, `N_p` stratified
//! lobe samples, each traced as a path of up to `N_b` segments through a [`Reflector`], with
//! `N_s` extra samples per glossy primary ray; rows in parallel.

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
use parallax_core::sampling::Rng;
use parallax_core::{Image, Ray, Rgb, WorldStats};
use rayon::prelude::*;

use super::{Lobe, ReflectOptions, Reflector, SurfaceHit};
use crate::SynthError;
use crate::dof::lens_strata;
use crate::layers::Reference;
use parallax_scene::Scene;

/// A reflection image and what it cost.
#[derive(Clone, Debug)]
pub struct ReflectionImage {
    pub image: Image<Rgb>,
    /// Pixels whose primary surface reflects (the pixels traced).
    pub mask: Vec<bool>,
    /// Work of the traced segments (`rays` = segments traced).
    pub stats: WorldStats,
    /// Extra samples answered by plane lookups, and the sum of their weights.
    pub lookups: u64,
    pub lookup_weight: f64,
    /// Extra samples traced as paths because their plane lookup weighed less than
    /// `ReflectOptions::trace_below`.
    pub extras_traced: u64,
    /// Wall-clock milliseconds of the pass (`T_rr`).
    pub ms: f64,
    /// CPU milliseconds of the threads that rendered the rows (NaN without a thread clock).
    pub cpu_ms: f64,
}

impl ReflectionImage {
    /// Traced segments per second of `T_rr`, in millions.
    pub fn mrays_per_s(&self) -> f64 {
        if self.ms > 0.0 {
            self.stats.rays as f64 / (self.ms * 1e3)
        } else {
            0.0
        }
    }

    /// Pixels that reflect.
    pub fn reflective_pixels(&self) -> usize {
        self.mask.iter().filter(|&&m| m).count()
    }

    /// Mean weight of the extra samples' plane lookups (NaN without any).
    pub fn mean_lookup_weight(&self) -> f64 {
        self.lookup_weight / self.lookups as f64
    }

    /// The image of `s x s` rays per pixel (rendered over a reference of the view at `s`
    /// times its size, [`crate::lightfield::supersampled`]) box-filtered to the view's size
    /// ([`crate::lightfield::box_filter`], the antialiased light-field views' filter): a
    /// pixel reflects when any of its `s x s` rays does (the others keep the view's colour
    /// on every reflector, so they add no error over the mask). Counters and times are
    /// those of all the rays.
    pub fn box_filtered(self, s: u32) -> Result<Self, SynthError> {
        if s == 1 {
            return Ok(self);
        }
        let image = crate::lightfield::box_filter(&self.image, s)?;
        let (w, fine_w) = (image.width() as usize, self.image.width() as usize);
        let s = s as usize;
        let mask = (0..image.len())
            .map(|i| {
                let (x, y) = (i % w * s, i / w * s);
                (0..s).any(|j| (0..s).any(|k| self.mask[(y + j) * fine_w + x + k]))
            })
            .collect();
        Ok(Self {
            image,
            mask,
            ..self
        })
    }
}

/// Per-row counters.
#[derive(Clone, Copy, Default)]
struct RowCounts {
    stats: WorldStats,
    lookups: u64,
    lookup_weight: f64,
    extras_traced: u64,
    cpu_ms: f64,
}

impl RowCounts {
    fn add(mut self, o: Self) -> Self {
        self.stats += o.stats;
        self.lookups += o.lookups;
        self.lookup_weight += o.lookup_weight;
        self.extras_traced += o.extras_traced;
        self.cpu_ms += o.cpu_ms;
        self
    }
}

/// The `cols x rows` strata of `[0, 1)^2` for `n` lobe samples (the lens strata of depth of
/// field).
struct Strata {
    cols: u32,
    cell: Vec2,
}

impl Strata {
    fn new(n: u32) -> Self {
        let (cols, rows) = lens_strata(n);
        Self {
            cols,
            cell: Vec2::new(1.0 / cols as f32, 1.0 / rows as f32),
        }
    }

    /// A jittered sample of stratum `i`.
    fn sample(&self, i: u32, rng: &mut Rng) -> Vec2 {
        let corner = Vec2::new((i % self.cols) as f32, (i / self.cols) as f32);
        (corner + rng.next_vec2()) * self.cell
    }
}

/// A reflective primary surface: triangle, position, normal facing the eye, direction to the
/// eye, lobe.
struct Primary {
    prim: u32,
    position: Vec3,
    normal: Vec3,
    wo: Vec3,
    lobe: Lobe,
}

/// The reflective primary surface at pixel `(x, y)` of `reference`'s layer 0, if any.
fn reflective(scene: &Scene, reference: &Reference, x: u32, y: u32) -> Option<Primary> {
    let g = reference.layers.first()?;
    if !g.is_hit(x, y) {
        return None;
    }
    let i = g.index(x, y);
    let lobe = Lobe::of(scene.materials.get(g.material_id[i] as usize)?, g.albedo[i])?;
    let p = g.position[i];
    let wo = (reference.camera.frame.position - p).normalize();
    let n = g.normal[i];
    Some(Primary {
        prim: g.primitive_id[i],
        position: p,
        normal: if n.dot(wo) < 0.0 { -n } else { n },
        wo,
        lobe,
    })
}

/// Where reflection rays start: `offset_px` face pixel footprints off their surface.
struct RayStart {
    offset_px: f32,
    /// The cube map's eye and face size (where the footprints are measured).
    eye: Vec3,
    face: f32,
}

impl RayStart {
    /// A ray from surface point `p` (normal `n`) along `dir`, started off the surface by
    /// `offset_px` face pixel footprints at `p`'s distance from the eye.
    fn ray(&self, p: Vec3, n: Vec3, dir: Vec3) -> Ray {
        let scale = 1e-4 * p.abs().max_element().max(1.0);
        let side = if dir.dot(n) >= 0.0 { 1.0 } else { -1.0 };
        let origin = p + n * (scale * side);
        let depth = (p - self.eye).abs().max_element();
        let t_min = self.offset_px * 2.0 * depth / self.face;
        Ray::segment(origin, dir, t_min, f32::INFINITY)
    }
}

/// The renderer's shared state for one image.
struct Pass<'a> {
    reflector: &'a dyn Reflector,
    opts: &'a ReflectOptions,
    environment: Vec3,
    start: RayStart,
}

impl Pass<'_> {
    fn ray_from(&self, p: Vec3, n: Vec3, dir: Vec3) -> Ray {
        self.start.ray(p, n, dir)
    }

    /// Radiance of a path whose traced segment `ray` found `first`, with path weight `w`,
    /// bouncing on through reflective surfaces (stream `rng`) until `n_b` segments.
    fn path(
        &self,
        mut ray: Ray,
        mut first: Option<SurfaceHit>,
        mut w: Vec3,
        rng: &mut Rng,
        stats: &mut WorldStats,
    ) -> Vec3 {
        let r = self.reflector;
        for segment in 1..=self.opts.n_b {
            let Some(hit) = first else {
                return w * self.environment;
            };
            let lobe = match r.lobe(&hit) {
                Some(l) if segment < self.opts.n_b => l,
                _ => return w * r.colour(&ray, &hit),
            };
            let wo = -ray.dir;
            let (dir, f) = lobe.sample(wo, hit.normal, rng.next_vec2());
            w *= f;
            if w.max_element() <= 0.0 {
                return Vec3::ZERO;
            }
            ray = self.ray_from(hit.position, hit.normal, dir);
            first = r.trace_from(&ray, hit.prim, stats);
        }
        Vec3::ZERO
    }

    /// The reflected radiance at a reflective primary surface (module docs of [`super`]).
    fn pixel(&self, (x, y): (u32, u32), v: &Primary, c: &mut RowCounts) -> Vec3 {
        let o = self.opts;
        let r = self.reflector;
        let (p, n, wo, lobe) = (v.position, v.normal, v.wo, v.lobe);
        let strata = Strata::new(o.n_p);
        let mut rng = Rng::for_pixel(o.seed, x, y, 0);
        let extras = if lobe.is_delta() { 0 } else { o.n_s };
        let path_rng = |k: u32| Rng::for_pixel(o.seed, x, y, 1 + k);
        let mut sum = Vec3::ZERO;
        for i in 0..o.n_p {
            let (dir, w) = lobe.sample(wo, n, strata.sample(i, &mut rng));
            if w.max_element() <= 0.0 {
                // Below the surface: the stratum adds nothing (its extra samples' draws are
                // still taken, so later strata see the same stream).
                for _ in 0..extras {
                    strata.sample(i, &mut rng);
                }
                continue;
            }
            let ray = self.ray_from(p, n, dir);
            let first = r.trace_from(&ray, v.prim, &mut c.stats);
            let k0 = i * (1 + extras);
            let traced = self.path(ray, first, w, &mut path_rng(k0), &mut c.stats);
            let (mut num, mut den) = (traced, 1.0f32);
            // The traced ray ended on a diffuse surface (or missed): its extra samples.
            let ended = first.is_none_or(|h| r.lobe(&h).is_none() || o.n_b == 1);
            for j in 0..extras {
                let (dir_j, w_j) = lobe.sample(wo, n, strata.sample(i, &mut rng));
                if w_j.max_element() <= 0.0 {
                    den += 1.0;
                    continue;
                }
                let ray_j = self.ray_from(p, n, dir_j);
                let looked_up = match first {
                    _ if r.traces_extras() => None,
                    Some(h) if ended => Some(r.plane_sample(&h, &ray_j, o.sigma)),
                    None => Some((self.environment, 1.0)),
                    Some(_) => Some((Vec3::ZERO, 0.0)),
                };
                if let Some((_, weight)) = looked_up {
                    c.lookups += 1;
                    c.lookup_weight += weight as f64;
                }
                match looked_up {
                    Some((colour, weight)) if weight >= o.trace_below => {
                        num += w_j * colour * weight;
                        den += weight;
                    }
                    _ => {
                        c.extras_traced += looked_up.is_some() as u64;
                        let first_j = r.trace_from(&ray_j, v.prim, &mut c.stats);
                        num +=
                            self.path(ray_j, first_j, w_j, &mut path_rng(k0 + 1 + j), &mut c.stats);
                        den += 1.0;
                    }
                }
            }
            sum += num / den;
        }
        sum / o.n_p as f32
    }
}

/// The first-segment rays of [`render_reflections`] with `opts` (every reflective pixel's
/// `N_p` traced rays and its extra samples' rays, in pixel order; rays of zero weight and the
/// strata of a traced ray of zero weight left out), each with the triangle it leaves (for
/// [`Reflector::trace_from`]): the identical ray set every reflector is timed on.
pub fn primary_rays(
    scene: &Scene,
    reference: &Reference,
    eye: Vec3,
    face: u32,
    opts: &ReflectOptions,
) -> Result<Vec<(Ray, u32)>, SynthError> {
    opts.validate()?;
    let start = RayStart {
        offset_px: opts.offset_px,
        eye,
        face: face.max(1) as f32,
    };
    let (w, h) = (reference.width(), reference.height());
    let rows: Vec<Vec<(Ray, u32)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut out = Vec::new();
            for x in 0..w {
                let Some(v) = reflective(scene, reference, x, y) else {
                    continue;
                };
                let strata = Strata::new(opts.n_p);
                let mut rng = Rng::for_pixel(opts.seed, x, y, 0);
                let extras = if v.lobe.is_delta() { 0 } else { opts.n_s };
                for i in 0..opts.n_p {
                    let mut traced = true;
                    for _ in 0..=extras {
                        let (dir, f) = v.lobe.sample(v.wo, v.normal, strata.sample(i, &mut rng));
                        // A stratum whose traced direction is below the surface is skipped.
                        traced &= f.max_element() > 0.0;
                        if traced && f.max_element() > 0.0 {
                            out.push((start.ray(v.position, v.normal, dir), v.prim));
                        }
                    }
                }
            }
            out
        })
        .collect();
    Ok(rows.concat())
}

/// Renders the reflections of `reference`'s view (one layer: the primary surfaces and the
/// colours of the pixels that do not reflect) through `reflector`, whose cube map is centred
/// at `eye` with faces of `face` pixels (module docs of [`super`]).
pub fn render_reflections(
    reflector: &dyn Reflector,
    reference: &Reference,
    eye: Vec3,
    face: u32,
    opts: &ReflectOptions,
) -> Result<ReflectionImage, SynthError> {
    opts.validate()?;
    if face == 0 {
        return Err(SynthError::Invalid("cube face size must be > 0".into()));
    }
    if reference.layers.is_empty() {
        return Err(SynthError::Invalid("the reference has no layer".into()));
    }
    let colours = &reference.colors[0];
    let camera = &reference.camera;
    let (w, h) = (camera.width, camera.height);
    let pass = Pass {
        reflector,
        opts,
        environment: reference.background,
        start: RayStart {
            offset_px: opts.offset_px,
            eye,
            face: face as f32,
        },
    };
    let scene = reflector.scene();
    let mut image = vec![Rgb::ZERO; w as usize * h as usize];
    let mut mask = vec![false; image.len()];
    let start = Instant::now();
    let counts = image
        .par_chunks_mut(w as usize)
        .zip(mask.par_chunks_mut(w as usize))
        .enumerate()
        .map(|(y, (row, mrow))| {
            let c0 = thread_cpu_ns();
            let mut c = RowCounts::default();
            let y = y as u32;
            for (x, (out, m)) in row.iter_mut().zip(mrow.iter_mut()).enumerate() {
                let x = x as u32;
                *out = *colours.get(x, y);
                let Some(v) = reflective(scene, reference, x, y) else {
                    continue;
                };
                *m = true;
                *out = pass.pixel((x, y), &v, &mut c);
            }
            c.cpu_ms = ms_between(c0, thread_cpu_ns());
            c
        })
        .reduce(RowCounts::default, RowCounts::add);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(ReflectionImage {
        image: Image::from_vec(w, h, image)?,
        mask,
        stats: counts.stats,
        lookups: counts.lookups,
        lookup_weight: counts.lookup_weight,
        extras_traced: counts.extras_traced,
        ms,
        cpu_ms: counts.cpu_ms,
    })
}
