//! DIRT's deferred traversal stage (Vardis et al. 2017, §4.2, Fig. 5 right) on the CPU: paths
//! advance breadth-first, one bounce at a time, over a tile of pixels. Per bounce:
//!
//! 1. **trace** (§4.2.1): the live paths' rays go to the tracer in one batch
//!    ([`WorldTracer::closest_hits`]) and fill the hit buffer (primitive, `t`, barycentrics);
//! 2. **fetch** (§4.2.2): the attributes of each hit (normals, texture, material) are
//!    gathered into the shading buffer ([`SurfacePoint::from_world_hit`]) — only for hits,
//!    once per hit;
//! 3. **shade** (§4.2.3): the estimator ([`Integrator::shade`]) turns each path's current
//!    vertex into emission, shadow rays and the next ray, and the shading buffer shifts
//!    (`G_k = G_{k+1}`: the hit becomes the start of the next segment);
//! 4. **occlusion**: the shadow rays go to the tracer ([`WorldTracer::occluded`]); unblocked
//!    ones add their contribution to their path; ended paths are written to the film and
//!    the survivors compacted for the next bounce.
//!
//! Where the paper keeps `G_{k-1}, G_k, G_{k+1}` per pixel, a path here keeps the little of
//! the previous vertex that MIS needs (pdf, normal, delta flag) in its [`PathState`].
//!
//! | parameter | type | meaning |
//! |---|---|---|
//! | `seed` | u64 | seed of the per-pixel streams `Rng::for_pixel(seed, x, y, sample)` |
//! | tile | [`Tile`] | the pixels one wavefront covers (from the film) |
//! | [`CAMERA_BLOCK`] | u32 | 4: camera paths start in 4x4 pixel blocks (coherent packets) |
//!
//! **Invariants:** a path's random numbers come from its own stream (channel `c > 0` of a
//! per-channel camera from the seed mixed with `c`); paths of sample `s + 1` start after every
//! path of sample `s` in the tile has ended, so each pixel adds its samples in order; all
//! buffers live in [`Scratch`] and are reused (no allocation per ray).

use std::ops::Range;
use std::sync::LazyLock;
use std::time::Instant;

use glam::Vec2;
use parallax_core::sampling::Rng;
use parallax_core::sampling::rng::splitmix64;
use parallax_core::{NO_ID, Ray, WorldHit, WorldStats, WorldTracer};
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};

use crate::estimator::{ALL_CHANNELS, Integrator, PathState, ShadowRay};
use crate::film::{Tile, TileFilm};
use crate::record::{PathRecord, RayRecord, ShadowRecord};
use crate::stats::PathStats;

/// Hints the cache to load what the fetch pass reads for every hit of the wavefront: the
/// triangle's indices, then its vertices' positions, normals and uvs, then the base-colour
/// texels. A wavefront knows all its hits before it shades any, so the loads overlap instead
/// of missing one after another (the fetch pass is bound by these misses on large scenes).
fn prefetch_attributes(scene: &Scene, hits: &[Option<WorldHit>]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let mesh = &scene.mesh;
        let prims = || {
            hits.iter()
                .flatten()
                .filter(|h| (h.prim as usize) < mesh.indices.len())
                .map(|h| h.prim as usize)
        };
        for p in prims() {
            // SAFETY: prefetching is a hint without memory effects; the address is in bounds.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(mesh.indices.as_ptr().add(p) as *const i8) };
        }
        for p in prims() {
            for &v in &mesh.indices[p] {
                let v = v as usize;
                // SAFETY: as above; vertex indices are in range (scene invariant).
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(mesh.positions.as_ptr().add(v) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(mesh.normals.as_ptr().add(v) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(mesh.uvs.as_ptr().add(v) as *const i8);
                }
            }
        }
        for h in hits.iter().flatten() {
            let Some(&m) = mesh.material_ids.get(h.prim as usize) else {
                continue;
            };
            let Some(t) = scene.materials[m as usize].base_color_texture else {
                continue;
            };
            let tex = &scene.textures[t as usize];
            let uv = mesh.uv(h.prim as usize, h.barycentrics.x, h.barycentrics.y);
            if let Some((a, b)) = tex.tap_rows(uv) {
                // SAFETY: as above; `tap_rows` returns indices inside the texel array.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(tex.texels.as_ptr().add(a) as *const i8);
                    _mm_prefetch::<_MM_HINT_T0>(tex.texels.as_ptr().add(b) as *const i8);
                }
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (scene, hits);
}

/// Edge of the pixel blocks the camera paths are laid out in (4x4: one 16-ray packet of
/// [`parallax_bvh::PACKET_SIZE`]).
pub const CAMERA_BLOCK: u32 = 4;

/// The fixed inputs of every wavefront of a render.
pub struct Wavefront<'a> {
    pub scene: &'a Scene,
    pub camera: &'a Camera,
    pub tracer: &'a dyn WorldTracer,
    pub integrator: &'a Integrator<'a>,
    pub seed: u64,
}

/// The reusable buffers of one worker: path states, hit buffer, shading buffer, shadow rays.
#[derive(Default)]
pub struct Scratch<'a> {
    paths: Vec<PathState>,
    next: Vec<PathState>,
    rays: Vec<Ray>,
    hits: Vec<Option<WorldHit>>,
    surfaces: Vec<Option<SurfacePoint<'a>>>,
    alive: Vec<bool>,
    shadows: Vec<ShadowRay>,
}

/// The pass clock: the calling thread's CPU time (a descheduled worker does not inflate the
/// pass it was in), monotonic time where the platform has no thread clock.
#[inline]
fn clock_ns() -> u64 {
    static EPOCH: LazyLock<Instant> = LazyLock::new(Instant::now);
    parallax_core::cpu_time::thread_cpu_ns().unwrap_or_else(|| EPOCH.elapsed().as_nanos() as u64)
}

#[inline]
fn ns_since(t: u64) -> u64 {
    clock_ns().saturating_sub(t)
}

impl<'a> Wavefront<'a> {
    /// Seeds the camera paths of sample `s` over `tile` into `scratch.paths` and counts the
    /// sample at every pixel. Pixels go in [`CAMERA_BLOCK`]² blocks, so that a pinhole's camera
    /// rays reach the tracer as coherent packets (a pixel's sums do not depend on the order in
    /// which pixels are visited).
    fn camera_paths(&self, tile: &Tile, s: u32, film: &mut TileFilm, scratch: &mut Scratch<'a>) {
        let channels = self.camera.channel_count();
        scratch.paths.clear();
        for i in tile.block_order(CAMERA_BLOCK) {
            let (x, y) = tile.coords(i);
            film.count_sample(i);
            let mut rng = Rng::for_pixel(self.seed, x, y, s);
            let film_pos = Vec2::new(x as f32, y as f32) + rng.next_vec2();
            let lens = rng.next_vec2();
            for c in 0..channels {
                let Some(cr) = self.camera.generate_ray(film_pos, lens, c) else {
                    continue;
                };
                let (path_rng, channel) = if channels == 1 {
                    (rng.clone(), ALL_CHANNELS)
                } else if c == 0 {
                    (rng.clone(), 0)
                } else {
                    let key = splitmix64(self.seed ^ (c as u64 + 1));
                    (Rng::for_pixel(key, x, y, s), c as u8)
                };
                scratch
                    .paths
                    .push(PathState::camera(cr.ray, path_rng, i as u32, channel));
            }
        }
    }

    /// Renders samples `samples` of the tile of `film`, adding them to it.
    pub fn run_tile(
        &self,
        film: &mut TileFilm,
        samples: Range<u32>,
        scratch: &mut Scratch<'a>,
        stats: &mut PathStats,
        mut record: Option<&mut PathRecord>,
    ) {
        let tile = film.tile;
        let mut world = WorldStats::default();
        for s in samples {
            self.camera_paths(&tile, s, film, scratch);
            stats.paths += scratch.paths.len() as u64;
            let mut bounce = 0u32;
            while !scratch.paths.is_empty() {
                let n = scratch.paths.len();
                // 1. Trace: the hit buffer.
                let t = clock_ns();
                scratch.rays.clear();
                scratch.rays.extend(scratch.paths.iter().map(|p| p.ray));
                scratch.hits.clear();
                scratch.hits.resize(n, None);
                self.tracer
                    .closest_hits(&scratch.rays, &mut scratch.hits, &mut world);
                let trace_ns = ns_since(t);
                if let Some(rec) = record.as_deref_mut() {
                    for (p, (ray, h)) in scratch
                        .paths
                        .iter()
                        .zip(scratch.rays.iter().zip(&scratch.hits))
                    {
                        let (x, y) = tile.coords(p.pixel as usize);
                        rec.rays.push(RayRecord {
                            sample: s,
                            bounce,
                            x,
                            y,
                            channel: p.channel,
                            ray: *ray,
                            prim: h.map_or(NO_ID, |h| h.prim),
                            t: h.map_or(f32::INFINITY, |h| h.t),
                        });
                    }
                }
                // 2. Fetch: the shading buffer.
                let t = clock_ns();
                prefetch_attributes(self.scene, &scratch.hits);
                scratch.surfaces.clear();
                scratch
                    .surfaces
                    .extend(scratch.rays.iter().zip(&scratch.hits).map(|(ray, h)| {
                        h.as_ref()
                            .map(|h| SurfacePoint::from_world_hit(self.scene, ray, h))
                    }));
                let fetch_ns = ns_since(t);
                // 3. Shade: emission, shadow rays, next rays.
                let t = clock_ns();
                scratch.shadows.clear();
                scratch.alive.clear();
                let mut hits = 0u64;
                for (i, path) in scratch.paths.iter_mut().enumerate() {
                    let alive = match (&scratch.hits[i], &scratch.surfaces[i]) {
                        (Some(h), Some(sp)) => {
                            hits += 1;
                            self.integrator
                                .shade(path, h, sp, &mut scratch.shadows, i as u32)
                        }
                        _ => {
                            self.integrator.miss(path);
                            false
                        }
                    };
                    scratch.alive.push(alive);
                }
                let shade_ns = ns_since(t);
                // 4. Occlusion, then write ended paths and compact the live ones.
                let t = clock_ns();
                for sh in &scratch.shadows {
                    let occluded = self.tracer.occluded(&sh.ray, &mut world);
                    if !occluded {
                        scratch.paths[sh.owner as usize].radiance += sh.contribution;
                    }
                    if let Some(rec) = record.as_deref_mut() {
                        let (x, y) = tile.coords(scratch.paths[sh.owner as usize].pixel as usize);
                        rec.shadows.push(ShadowRecord {
                            sample: s,
                            bounce,
                            x,
                            y,
                            ray: sh.ray,
                            occluded,
                        });
                    }
                }
                let shadow_ns = ns_since(t);
                scratch.next.clear();
                for (path, alive) in scratch.paths.drain(..).zip(&scratch.alive) {
                    if *alive {
                        scratch.next.push(path);
                    } else if path.channel == ALL_CHANNELS {
                        film.add(path.pixel as usize, path.radiance);
                    } else {
                        let c = path.channel as usize;
                        film.add_channel(path.pixel as usize, c, path.radiance[c]);
                    }
                }
                std::mem::swap(&mut scratch.paths, &mut scratch.next);
                let b = stats.bounce_mut(bounce);
                b.rays += n as u64;
                b.hits += hits;
                b.shadow_rays += scratch.shadows.len() as u64;
                b.trace_ns += trace_ns;
                b.fetch_ns += fetch_ns;
                b.shade_ns += shade_ns;
                b.shadow_ns += shadow_ns;
                bounce += 1;
            }
        }
        stats.world += world;
    }
}
