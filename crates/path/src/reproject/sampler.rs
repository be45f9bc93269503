//! The paper's sample (Mäkitalo et al. 2019, §4.1: "we first path trace the complete right-eye
//! image with 1 spp (using one primary ray, one secondary ray, and two shadow rays)"): the
//! path tracer's estimator ([`Integrator`]) at `max_depth` 3 with [`Integrator::final_nee`], so
//! a sample is the primary ray, light connections at its hit, one BSDF-sampled secondary ray
//! and light connections at that hit (one per light kind the scene has: a delta light and an
//! area-like light, so two shadow rays per vertex in scenes with a sun and a sky).
//!
//! Pixels are traced one path at a time (depth first) rather than in wavefronts, because the
//! reprojection traces sparse pixel sets and needs each sample's primary hit as its G-buffer
//! texel; the random numbers are drawn in the wavefront's order ([`crate::wavefront`]: film
//! jitter, lens, then the path's stream), so sample 0 of stream `seed` at a pixel is the path
//! tracer's first sample there bit for bit (tested against [`crate::PathTracer`]).
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `materials` | [`MaterialMode`] | the scene's materials or all Lambertian |
//! | `seed` | u64 | the frame and eye's stream: pixel `(x, y)` uses `Rng::for_pixel(seed, x, y, 0)` |
//!
//! **Invariants:** a pixel's texel and radiance depend only on the scene, the camera, the seed
//! and the pixel (never on the thread count or on which other pixels are traced); bands of rows
//! are traced in parallel and write only their own pixels.

use glam::{Vec2, Vec3};
use parallax_core::sampling::Rng;
use parallax_core::{WorldStats, WorldTracer};
use parallax_render::bsdf::MaterialMode;
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, Pinhole};
use rayon::prelude::*;

use super::buffers::{EyeView, Texel};
use crate::estimator::{ALL_CHANNELS, Integrator, PathState, ShadowRay};
use crate::options::PathOptions;

/// Longest path of the paper's sample, in segments: camera ray, secondary ray, and the light
/// connection of the secondary vertex.
pub const PAPER_MAX_DEPTH: u32 = 3;

/// Rows per parallel work item.
const BAND_ROWS: usize = 4;

/// Rays and thread CPU time of one pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCost {
    pub samples: u64,
    pub closest_rays: u64,
    pub shadow_rays: u64,
    /// Thread CPU nanoseconds summed over the workers.
    pub cpu_ns: u64,
}

impl TraceCost {
    fn add(&mut self, o: &TraceCost) {
        self.samples += o.samples;
        self.closest_rays += o.closest_rays;
        self.shadow_rays += o.shadow_rays;
        self.cpu_ns += o.cpu_ns;
    }

    /// Sums per-band costs in band order (deterministic).
    fn sum<'c>(costs: impl IntoIterator<Item = &'c TraceCost>) -> TraceCost {
        let mut t = TraceCost::default();
        for c in costs {
            t.add(c);
        }
        t
    }
}

/// Thread CPU nanoseconds now (0 where the platform has no thread clock).
#[inline]
pub(crate) fn thread_ns() -> u64 {
    parallax_core::cpu_time::thread_cpu_ns().unwrap_or(0)
}

/// The paper's sample over one scene state and tracer.
pub struct PaperSampler<'a> {
    pub scene: &'a Scene,
    pub tracer: &'a dyn WorldTracer,
    integrator: Integrator<'a>,
}

impl<'a> PaperSampler<'a> {
    pub fn new(scene: &'a Scene, tracer: &'a dyn WorldTracer, materials: MaterialMode) -> Self {
        let mut integrator = Integrator::new(
            scene,
            materials,
            PAPER_MAX_DEPTH,
            PAPER_MAX_DEPTH,
            crate::light_sampler::DEFAULT_ENV_NEE,
        );
        integrator.final_nee = true;
        Self {
            scene,
            tracer,
            integrator,
        }
    }

    /// The path tracer's options of the same estimator (for references and the n-spp curve).
    pub fn path_options(materials: MaterialMode, spp: u32, seed: u64) -> PathOptions {
        PathOptions {
            spp,
            seed,
            max_depth: PAPER_MAX_DEPTH,
            rr_depth: PAPER_MAX_DEPTH,
            materials,
            final_nee: true,
            ..PathOptions::default()
        }
    }

    /// Sample 0 of stream `seed` at pixel `(x, y)`: the primary hit's texel and the radiance.
    fn sample(
        &self,
        camera: &Pinhole,
        seed: u64,
        x: u32,
        y: u32,
        shadows: &mut Vec<ShadowRay>,
        cost: &mut TraceCost,
    ) -> (Texel, Vec3) {
        let mut world = WorldStats::default();
        let mut rng = Rng::for_pixel(seed, x, y, 0);
        let film = Vec2::new(x as f32, y as f32) + rng.next_vec2();
        let lens = rng.next_vec2();
        cost.samples += 1;
        let Some(cr) = camera.generate_ray(film, lens, 0) else {
            return (Texel::MISS, Vec3::ZERO);
        };
        let mut path = PathState::camera(cr.ray, rng, 0, ALL_CHANNELS);
        let mut texel = Texel::MISS;
        loop {
            let ray = path.ray;
            cost.closest_rays += 1;
            let Some(hit) = self.tracer.closest_hit(&ray, &mut world) else {
                self.integrator.miss(&mut path);
                break;
            };
            let sp = SurfacePoint::from_world_hit(self.scene, &ray, &hit);
            if path.depth == 0 {
                texel = Texel {
                    position: sp.position,
                    depth: cr.view_depth(hit.t),
                    normal: sp.shading_normal,
                    albedo: sp.albedo,
                };
            }
            shadows.clear();
            let alive = self.integrator.shade(&mut path, &hit, &sp, shadows, 0);
            cost.shadow_rays += shadows.len() as u64;
            for sh in shadows.iter() {
                if !self.tracer.occluded(&sh.ray, &mut world) {
                    path.radiance += sh.contribution;
                }
            }
            if !alive {
                break;
            }
        }
        (texel, path.radiance)
    }

    /// The primary hit of sample 0 of stream `seed` at `(x, y)` (the first ray [`Self::sample`]
    /// traces), and the radiance when that ray misses (the environment).
    fn primary(&self, camera: &Pinhole, seed: u64, x: u32, y: u32) -> (Texel, Vec3) {
        let mut world = WorldStats::default();
        let mut rng = Rng::for_pixel(seed, x, y, 0);
        let film = Vec2::new(x as f32, y as f32) + rng.next_vec2();
        let lens = rng.next_vec2();
        let Some(cr) = camera.generate_ray(film, lens, 0) else {
            return (Texel::MISS, Vec3::ZERO);
        };
        match self.tracer.closest_hit(&cr.ray, &mut world) {
            Some(hit) => {
                let sp = SurfacePoint::from_world_hit(self.scene, &cr.ray, &hit);
                let texel = Texel {
                    position: sp.position,
                    depth: cr.view_depth(hit.t),
                    normal: sp.shading_normal,
                    albedo: sp.albedo,
                };
                (texel, Vec3::ZERO)
            }
            None => {
                let mut path = PathState::camera(cr.ray, rng, 0, ALL_CHANNELS);
                self.integrator.miss(&mut path);
                (Texel::MISS, path.radiance)
            }
        }
    }

    /// Traces every pixel of `view.camera`: its G-buffer into `view.texels`, the radiance of
    /// the sample into `radiance`.
    pub fn trace_eye(&self, seed: u64, view: &mut EyeView, radiance: &mut [Vec3]) -> TraceCost {
        let w = view.width() as usize;
        assert_eq!(radiance.len(), view.len());
        let camera = &view.camera;
        let costs: Vec<TraceCost> = view
            .texels
            .par_chunks_mut(w * BAND_ROWS)
            .zip(radiance.par_chunks_mut(w * BAND_ROWS))
            .enumerate()
            .map_init(Vec::new, |shadows, (band, (texels, rad))| {
                let t0 = thread_ns();
                let mut cost = TraceCost::default();
                for (i, (tx, r)) in texels.iter_mut().zip(rad.iter_mut()).enumerate() {
                    let (x, y) = ((i % w) as u32, (band * BAND_ROWS + i / w) as u32);
                    (*tx, *r) = self.sample(camera, seed, x, y, shadows, &mut cost);
                }
                cost.cpu_ns = thread_ns().saturating_sub(t0);
                cost
            })
            .collect();
        TraceCost::sum(&costs)
    }

    /// The G-buffer of every pixel (primary rays only, the first ray of the pixel's sample of
    /// stream `seed`); `background` gets the radiance of pixels whose primary ray misses (0 for
    /// hits).
    pub fn trace_gbuffer(
        &self,
        seed: u64,
        view: &mut EyeView,
        background: &mut [Vec3],
    ) -> TraceCost {
        let w = view.width() as usize;
        assert_eq!(background.len(), view.len());
        let camera = &view.camera;
        let costs: Vec<TraceCost> = view
            .texels
            .par_chunks_mut(w * BAND_ROWS)
            .zip(background.par_chunks_mut(w * BAND_ROWS))
            .enumerate()
            .map(|(band, (texels, bg))| {
                let t0 = thread_ns();
                for (i, (tx, b)) in texels.iter_mut().zip(bg.iter_mut()).enumerate() {
                    let (x, y) = ((i % w) as u32, (band * BAND_ROWS + i / w) as u32);
                    (*tx, *b) = self.primary(camera, seed, x, y);
                }
                TraceCost {
                    samples: 0,
                    closest_rays: texels.len() as u64,
                    shadow_rays: 0,
                    cpu_ns: thread_ns().saturating_sub(t0),
                }
            })
            .collect();
        TraceCost::sum(&costs)
    }

    /// The radiance of the samples of stream `seed` at the listed pixel indices (row-major in
    /// `camera`), into `out` (same order).
    pub fn trace_pixels(
        &self,
        camera: &Pinhole,
        seed: u64,
        pixels: &[u32],
        out: &mut [Vec3],
    ) -> TraceCost {
        assert_eq!(pixels.len(), out.len());
        let w = camera.width;
        const CHUNK: usize = 64;
        let costs: Vec<TraceCost> = pixels
            .par_chunks(CHUNK)
            .zip(out.par_chunks_mut(CHUNK))
            .map_init(Vec::new, |shadows, (ids, rad)| {
                let t0 = thread_ns();
                let mut cost = TraceCost::default();
                for (&i, r) in ids.iter().zip(rad.iter_mut()) {
                    *r = self
                        .sample(camera, seed, i % w, i / w, shadows, &mut cost)
                        .1;
                }
                cost.cpu_ns = thread_ns().saturating_sub(t0);
                cost
            })
            .collect();
        TraceCost::sum(&costs)
    }
}
