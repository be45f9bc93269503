//! `parallax bench dirt`: DIRT's Tables 1-3 (Vardis et al. 2017, §5.2-5.3) for DIRT against
//! the BVH in the same run, on the same rays.
//!
//! - **Build** (Table 2's "Build", and the paper's claim of fast construction): the BVH build
//!   and DIRT's build (triangle buffer, camera view, cube map; per stage) in interleaved
//!   rounds, best round each.
//! - **Table 1** (Mrays/s per ray type for the first path event): the rays of [`super::dirt_rays`]
//!   traced by DIRT and by the BVH, interleaved round by round (best round each), timed in
//!   thread CPU time (summed over rayon's chunks; a busy machine inflates wall time, not CPU
//!   time) and wall time; DIRT's work per ray (views, texels, cells, buckets, triangle tests)
//!   and its agreement with the BVH (same triangle, ties at equal `t`).
//! - **Table 3** (memory per buffer): the paper's per-pixel formula beside the bytes measured.
//! - **Sweeps** (Fig. 10): build time, memory and diffuse-ray speed over `B` and `S`.
//! - **Path tracing** (§5.1, optional): the reference path tracer with the BVH and with DIRT
//!   behind it, same seed, every ray recorded ([`super::dirt_path`]): per-bounce agreement and
//!   PSNR.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `views` | [`DirtViewsOptions`] | [`DIRT_DEFAULTS`]: face 128, S 4, B 16 | the configuration of the build and Table 1 |
//! | `repeats` | u32 | 3 | interleaved rounds per measurement (best reported) |
//! | `sweep_buckets` | `Vec<u32>` | 1, 4, 8, 16, 32 | `B` values of the bucket sweep (at the configured `S`) |
//! | `sweep_tiles` | `Vec<u32>` | 1, 2, 4, 8 | `S` values of the tile sweep (at the configured `B`) |
//! | `rays` | [`RayOptions`] | seed 1, roughness 0.3 | ray generation |
//! | `path_spp` | u32 | 0 | samples per pixel of the path-tracing comparison (0: skipped) |
//! | `path_max_depth` | u32 | 5 | its longest path (segments) |
//! | `camera_view` | bool | true | build and trace DIRT's camera view (false: the cube map alone answers every ray; the path-tracing comparison keeps the camera view) |

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
use parallax_core::{Ray, WorldHit};
use parallax_raster::dirt::{DirtError, DirtOptions, DirtViews, DirtViewsOptions};
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use parallax_screen::{DirtCounters, DirtTracer};
use rayon::prelude::*;
use serde::Serialize;

use super::dirt_path::{PathAgreement, path_agreement};
use super::dirt_rays::{RayOptions, RaySet, RayType, ray_sets};
use crate::estimator::PathState;
use crate::options::PathOptions;
use crate::tracers::{DIRT_DEFAULTS, TracerOptions, camera_centre};

/// Options of [`run`] (see the module table).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DirtBenchOptions {
    pub views: DirtViewsOptions,
    pub repeats: u32,
    pub sweep_buckets: Vec<u32>,
    pub sweep_tiles: Vec<u32>,
    pub rays: RayOptions,
    pub path_spp: u32,
    pub path_max_depth: u32,
    pub camera_view: bool,
}

impl Default for DirtBenchOptions {
    fn default() -> Self {
        Self {
            views: DIRT_DEFAULTS,
            repeats: 3,
            sweep_buckets: vec![1, 4, 8, 16, 32],
            sweep_tiles: vec![1, 2, 4, 8],
            rays: RayOptions::default(),
            path_spp: 0,
            path_max_depth: 5,
            camera_view: true,
        }
    }
}

/// Why the benchmark could not run.
#[derive(Debug, thiserror::Error)]
pub enum DirtBenchError {
    #[error(transparent)]
    Dirt(#[from] DirtError),
    #[error(transparent)]
    Bvh(#[from] parallax_bvh::BvhError),
    #[error(transparent)]
    Path(#[from] crate::error::PathError),
}

/// One build measurement.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRow {
    pub scene: String,
    pub method: String,
    pub triangles: u64,
    /// Wall ms of the whole build (DIRT: capture + tracer).
    pub ms_build: f64,
    /// DIRT's tracer construction: view constants and the walk's slab-masked texels.
    pub ms_tracer: f64,
    /// DIRT's capture stages (zero for the BVH).
    pub ms_triangles: f64,
    pub ms_camera: f64,
    pub ms_cube: f64,
    /// DIRT's capture stages summed over the views.
    pub ms_setup: f64,
    pub ms_fill: f64,
    pub ms_assemble: f64,
    pub ms_mip: f64,
    pub bytes: u64,
    /// `ms_build` over the BVH's.
    pub build_vs_bvh: f64,
}

/// One method on one ray type (Table 1).
#[derive(Clone, Debug, Serialize)]
pub struct RayRow {
    pub scene: String,
    pub ray_type: RayType,
    pub method: String,
    pub rays: u64,
    /// Thread CPU time of the pass (summed over rayon's chunks).
    pub ms_trace_cpu: f64,
    pub ms_trace: f64,
    /// Rays per second of wall time.
    pub mrays_per_s: f64,
    /// Rays per second of thread CPU time, times the thread count.
    pub cpu_mrays_per_s: f64,
    /// CPU time per ray over the BVH's.
    pub time_vs_bvh: f64,
    pub hit_rate: f64,
    /// Fraction of rays whose answer is the BVH's (same triangle, or both miss).
    pub same_prim: f64,
    /// Rays with a different triangle at exactly the BVH's `t`.
    pub ties: u64,
    pub views_per_ray: f64,
    pub texels_per_ray: f64,
    pub cells_per_ray: f64,
    pub buckets_per_ray: f64,
    pub tests_per_ray: f64,
    pub pct_truncated: f64,
}

/// One buffer of Table 3.
#[derive(Clone, Debug, Serialize)]
pub struct MemoryRow {
    pub scene: String,
    pub buffer: String,
    /// What the formula counts per unit.
    pub formula: String,
    /// Units the formula is per (view cells `p_l` or film pixels `p_h`).
    pub units: u64,
    pub formula_bytes: f64,
    pub measured_bytes: u64,
    pub note: String,
}

/// One configuration of the `B` / `S` sweeps.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    pub scene: String,
    pub tile: u32,
    pub buckets: u32,
    pub face: u32,
    pub ms_build: f64,
    pub build_vs_bvh: f64,
    pub bytes: u64,
    pub entries: u64,
    pub diffuse_mrays_per_s: f64,
    pub diffuse_time_vs_bvh: f64,
    pub tests_per_ray: f64,
}

/// Everything `bench dirt` measures.
#[derive(Clone, Debug, Serialize)]
pub struct DirtBenchReport {
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    pub options: DirtBenchOptions,
    pub build: Vec<BuildRow>,
    pub rays: Vec<RayRow>,
    pub memory: Vec<MemoryRow>,
    pub sweep: Vec<SweepRow>,
    pub path: Option<PathAgreement>,
}

/// Runs the benchmark on `scene` seen by `camera` (a pinhole camera is DIRT's camera view;
/// other models use the cube map alone, around the camera's position).
pub fn run(
    scene: &Scene,
    camera: &Camera,
    opts: &DirtBenchOptions,
) -> Result<DirtBenchReport, DirtBenchError> {
    let pinhole = match camera {
        Camera::Pinhole(p) if opts.camera_view => Some(p),
        _ => None,
    };
    let eye = camera_centre(camera);
    let repeats = opts.repeats.max(1);
    let name = scene.name.clone();

    // Builds, interleaved.
    let (mut bvh_ms, mut dirt_best) = (f64::INFINITY, None::<BuiltDirt>);
    let mut bvh = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let b = Bvh::try_build(&scene.mesh)?;
        bvh_ms = bvh_ms.min(ms(t));
        bvh = Some(b);
        let d = BuiltDirt::build(scene, pinhole, eye, &opts.views)?;
        if dirt_best.as_ref().is_none_or(|best| d.ms() < best.ms()) {
            dirt_best = Some(d);
        }
    }
    let (bvh, built) = (bvh.expect("built"), dirt_best.expect("built"));
    let build = build_rows(&name, scene, bvh_ms, &built);
    let memory = memory_rows(&name, camera, &built.tracer);
    let dirt = built.tracer;

    let sets = ray_sets(scene, &bvh, camera, &opts.rays);
    let mut rays = Vec::new();
    for set in &sets {
        rays.extend(ray_rows(&name, &bvh, &dirt, set, repeats));
    }
    drop(dirt);

    let mut sweep = Vec::new();
    let diffuse = sets.iter().find(|s| s.kind == RayType::Diffuse);
    let configs = opts
        .sweep_buckets
        .iter()
        .map(|&b| (opts.views.capture.tile_size, b))
        .chain(
            opts.sweep_tiles
                .iter()
                .map(|&s| (s, opts.views.capture.buckets)),
        );
    for (tile, buckets) in configs {
        let v = DirtViewsOptions {
            capture: DirtOptions {
                tile_size: tile,
                buckets,
                ..opts.views.capture
            },
            ..opts.views
        };
        sweep.push(sweep_row(
            &name, scene, &bvh, pinhole, eye, &v, diffuse, repeats,
        )?);
    }
    let path = (opts.path_spp > 0)
        .then(|| {
            let o = PathOptions {
                spp: opts.path_spp,
                max_depth: opts.path_max_depth,
                seed: opts.rays.seed,
                ..PathOptions::default()
            };
            path_agreement(
                scene,
                camera,
                &o,
                &TracerOptions {
                    dirt: opts.views,
                    ..TracerOptions::default()
                },
            )
            .map(|r| r.0)
        })
        .transpose()?;
    Ok(DirtBenchReport {
        path,
        threads: rayon::current_num_threads(),
        width: camera.width(),
        height: camera.height(),
        options: opts.clone(),
        build,
        rays,
        memory,
        sweep,
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// DIRT's build as the bench times it: the capture ([`DirtViews::build`]) and the tracer's
/// own per-view data ([`DirtTracer::new`]: view constants, the walk's texels with their slab
/// masks), both made per frame.
struct BuiltDirt {
    tracer: DirtTracer,
    tracer_ms: f64,
}

impl BuiltDirt {
    fn build(
        scene: &Scene,
        pinhole: Option<&parallax_scene::camera::Pinhole>,
        eye: glam::Vec3,
        opts: &DirtViewsOptions,
    ) -> Result<BuiltDirt, DirtBenchError> {
        let views = DirtViews::build(&scene.mesh, pinhole, eye, opts)?;
        let t = Instant::now();
        let tracer = DirtTracer::new(views);
        Ok(BuiltDirt {
            tracer,
            tracer_ms: ms(t),
        })
    }

    /// Capture and tracer, wall ms.
    fn ms(&self) -> f64 {
        self.tracer.views().stats.total_ms + self.tracer_ms
    }

    fn bytes(&self) -> u64 {
        self.tracer.views().bytes() + self.tracer.texel_bytes() + self.tracer.cell_line_bytes()
    }
}

fn build_rows(name: &str, scene: &Scene, bvh_ms: f64, built: &BuiltDirt) -> Vec<BuildRow> {
    let views = built.tracer.views();
    let tris = scene.mesh.triangle_count() as u64;
    let sum = |f: fn(&parallax_raster::dirt::DirtStats) -> f64| -> f64 {
        views.views().map(|v| f(v.stats())).sum()
    };
    let s = &views.stats;
    vec![
        BuildRow {
            scene: name.into(),
            method: "bvh".into(),
            triangles: tris,
            ms_build: bvh_ms,
            ms_tracer: 0.0,
            ms_triangles: 0.0,
            ms_camera: 0.0,
            ms_cube: 0.0,
            ms_setup: 0.0,
            ms_fill: 0.0,
            ms_assemble: 0.0,
            ms_mip: 0.0,
            bytes: 0,
            build_vs_bvh: 1.0,
        },
        BuildRow {
            scene: name.into(),
            method: "dirt".into(),
            triangles: tris,
            ms_build: built.ms(),
            ms_tracer: built.tracer_ms,
            ms_triangles: s.triangles_ms,
            ms_camera: s.camera_ms,
            ms_cube: s.cube_ms,
            ms_setup: sum(|v| v.setup_ms),
            ms_fill: sum(|v| v.fill_ms),
            ms_assemble: sum(|v| v.assemble_ms),
            ms_mip: sum(|v| v.mip_ms),
            bytes: built.bytes(),
            build_vs_bvh: built.ms() / bvh_ms,
        },
    ]
}

/// Times of one pass and what it found.
#[derive(Clone, Copy, Debug)]
struct Pass {
    wall_ms: f64,
    cpu_ms: f64,
    hits: u64,
    counters: DirtCounters,
}

/// Rays per rayon task: large enough to amortise the clock reads.
const CHUNK: usize = 1024;

fn pass(rays: &[Ray], f: impl Fn(&Ray, &mut DirtCounters) -> bool + Sync) -> Pass {
    let start = Instant::now();
    let (hits, cpu_ms, counters) = rays
        .par_chunks(CHUNK)
        .map(|c| {
            let c0 = thread_cpu_ns();
            let mut k = DirtCounters::default();
            let hits = c.iter().filter(|r| f(r, &mut k)).count() as u64;
            (hits, ms_between(c0, thread_cpu_ns()), k)
        })
        .reduce(
            || (0, 0.0, DirtCounters::default()),
            |a, b| {
                let mut k = a.2;
                k += b.2;
                (a.0 + b.0, a.1 + b.1, k)
            },
        );
    Pass {
        wall_ms: ms(start),
        cpu_ms,
        hits,
        counters,
    }
}

/// Interleaved rounds of DIRT and the BVH on one ray set; best round each.
fn time_both(bvh: &Bvh, dirt: &DirtTracer, set: &RaySet, repeats: u32) -> (Pass, Pass) {
    let occ = set.kind.is_occlusion();
    let run_dirt = |r: &Ray, k: &mut DirtCounters| {
        if occ {
            dirt.occluded_counted(r, k)
        } else {
            dirt.closest_hit_counted(r, k).is_some()
        }
    };
    let run_bvh = |r: &Ray, _: &mut DirtCounters| {
        if occ {
            bvh.any_hit(r)
        } else {
            bvh.closest_hit(r).is_some()
        }
    };
    let best = |a: Option<Pass>, b: Pass| match a {
        Some(a) if a.cpu_ms <= b.cpu_ms => Some(a),
        _ => Some(b),
    };
    let (mut d, mut b) = (None, None);
    for _ in 0..repeats {
        d = best(d, pass(&set.rays, run_dirt));
        b = best(b, pass(&set.rays, run_bvh));
    }
    (d.expect("ran"), b.expect("ran"))
}

/// DIRT's answers against the BVH's: (same triangle or both miss, ties at equal `t`).
fn agreement(bvh: &Bvh, dirt: &DirtTracer, set: &RaySet) -> (u64, u64) {
    set.rays
        .par_chunks(CHUNK)
        .map(|c| {
            let mut k = DirtCounters::default();
            c.iter().fold((0, 0), |(same, ties), r| {
                if set.kind.is_occlusion() {
                    let eq = bvh.any_hit(r) == dirt.occluded_counted(r, &mut k);
                    return (same + eq as u64, ties);
                }
                let d: Option<WorldHit> = dirt.closest_hit_counted(r, &mut k);
                match (bvh.closest_hit(r), d) {
                    (None, None) => (same + 1, ties),
                    (Some(a), Some(b)) if a.prim == b.prim => (same + 1, ties),
                    (Some(a), Some(b)) if a.t == b.t => (same, ties + 1),
                    _ => (same, ties),
                }
            })
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

fn ray_rows(name: &str, bvh: &Bvh, dirt: &DirtTracer, set: &RaySet, repeats: u32) -> Vec<RayRow> {
    let (d, b) = time_both(bvh, dirt, set, repeats);
    let (same, ties) = agreement(bvh, dirt, set);
    let n = set.rays.len().max(1) as f64;
    let threads = rayon::current_num_threads() as f64;
    let row = |method: &str, p: &Pass, counted: bool| {
        let per = |x: u64| if counted { x as f64 / n } else { 0.0 };
        RayRow {
            scene: name.into(),
            ray_type: set.kind,
            method: method.into(),
            rays: set.rays.len() as u64,
            ms_trace_cpu: p.cpu_ms,
            ms_trace: p.wall_ms,
            mrays_per_s: n / (p.wall_ms * 1e3),
            cpu_mrays_per_s: n * threads / (p.cpu_ms * 1e3),
            time_vs_bvh: p.cpu_ms / b.cpu_ms,
            hit_rate: p.hits as f64 / n,
            same_prim: if counted { same as f64 / n } else { 1.0 },
            ties: if counted { ties } else { 0 },
            views_per_ray: per(p.counters.views),
            texels_per_ray: per(p.counters.texels),
            cells_per_ray: per(p.counters.cells),
            buckets_per_ray: per(p.counters.buckets),
            tests_per_ray: per(p.counters.tests),
            pct_truncated: 100.0 * per(p.counters.truncated),
        }
    };
    vec![row("dirt", &d, true), row("bvh", &b, false)]
}

/// Table 3: the paper's per-unit formulas (`size(node_id) = 8`, `size(node_hit) =
/// size(node_sb) = 32`, `c * n_p` = the entries measured) beside the bytes measured.
fn memory_rows(name: &str, camera: &Camera, tracer: &DirtTracer) -> Vec<MemoryRow> {
    let views = tracer.views();
    let (mut cells, mut texels, mut entries, mut bucket_heads) = (0u64, 0u64, 0u64, 0u64);
    let (mut bounds_bytes, mut id_bytes) = (0u64, 0u64);
    for v in views.views() {
        let (nx, ny) = v.cells();
        cells += nx as u64 * ny as u64;
        let (levels, b) = v.mip_arrays();
        texels += b.len() as u64;
        bounds_bytes += std::mem::size_of_val(b) as u64
            + std::mem::size_of_val(v.recip_mip()) as u64
            + std::mem::size_of_val(levels) as u64
            + std::mem::size_of_val(v.cell_records()) as u64;
        entries += v.stats().entries;
        bucket_heads += nx as u64 * ny as u64 * v.buckets() as u64;
        id_bytes +=
            std::mem::size_of_val(v.offsets()) as u64 + std::mem::size_of_val(v.ids()) as u64;
    }
    let pixels = camera.width() as u64 * camera.height() as u64;
    // The wavefront path tracer keeps its hit and shading buffers per worker, for one tile of
    // paths at a time (crate::wavefront), not for the whole film.
    let in_flight = {
        let tile = PathOptions::default().tile as u64;
        (tile * tile * rayon::current_num_threads() as u64).min(pixels)
    };
    let hit_record = std::mem::size_of::<Option<WorldHit>>() as u64;
    let shading_record = (std::mem::size_of::<Option<SurfacePoint<'static>>>()
        + std::mem::size_of::<PathState>()) as u64;
    let row = |buffer: &str, formula: &str, units, fb: f64, mb, note: &str| MemoryRow {
        scene: name.into(),
        buffer: buffer.into(),
        formula: formula.into(),
        units,
        formula_bytes: fb,
        measured_bytes: mb,
        note: note.into(),
    };
    vec![
        row(
            "depth bounds texture",
            "11 ≈ 8 x 1.33 per p_l",
            cells,
            11.0 * cells as f64,
            bounds_bytes + tracer.texel_bytes() + tracer.cell_line_bytes(),
            &format!(
                "{texels} texels over all mip levels, [min, max] f32 and its reciprocal [1 / max, 1 / min]; + a 16-byte cell record (bounds, bucket scale, bucket mask) per cell; + the walk's 16-byte texel per mip texel (reciprocal bounds and depth-slab mask); + the walk's 64-byte line per cell (the record, bucket ends and first 14 list entries as u16) and the lists' further entries after the lines"
            ),
        ),
        row(
            "id buffer",
            "4·B + c·n_p·8 per p_l",
            cells,
            4.0 * bucket_heads as f64 + 8.0 * entries as f64,
            id_bytes,
            &format!(
                "CSR: 4-byte offsets per cell-bucket, 4-byte ids ({entries} entries), no next pointers"
            ),
        ),
        row(
            "vertex buffer",
            "(not counted by the paper)",
            views.triangles.len() as u64,
            0.0,
            views.triangles.bytes(),
            "36 bytes per triangle: three f32 corners",
        ),
        row(
            "hit buffer",
            "4 + 32 per p_h",
            pixels,
            36.0 * pixels as f64,
            hit_record * in_flight,
            &format!(
                "one Option<WorldHit> ({hit_record} bytes) per path in flight: {in_flight} = a \
                 32x32 tile per worker"
            ),
        ),
        row(
            "shading buffer",
            "3 x 32 per p_h",
            pixels,
            96.0 * pixels as f64,
            shading_record * in_flight,
            &format!(
                "per path in flight: the fetched Option<SurfacePoint> (G_k+1) and the PathState \
                 (ray, throughput, previous vertex's pdf and normal: G_k, G_k-1), {shading_record} bytes"
            ),
        ),
        row(
            "mask texture",
            "2 per p_h",
            pixels,
            2.0 * pixels as f64,
            0,
            "none: the CPU fetch pass visits only the paths with a hit",
        ),
    ]
}

#[allow(clippy::too_many_arguments)]
fn sweep_row(
    name: &str,
    scene: &Scene,
    bvh: &Bvh,
    pinhole: Option<&parallax_scene::camera::Pinhole>,
    eye: glam::Vec3,
    opts: &DirtViewsOptions,
    diffuse: Option<&RaySet>,
    repeats: u32,
) -> Result<SweepRow, DirtBenchError> {
    let (mut bvh_ms, mut best) = (f64::INFINITY, None::<BuiltDirt>);
    for _ in 0..repeats {
        let t = Instant::now();
        std::hint::black_box(Bvh::try_build(&scene.mesh)?);
        bvh_ms = bvh_ms.min(ms(t));
        let d = BuiltDirt::build(scene, pinhole, eye, opts)?;
        if best.as_ref().is_none_or(|b| d.ms() < b.ms()) {
            best = Some(d);
        }
    }
    let built = best.expect("built");
    let (ms_build, bytes) = (built.ms(), built.bytes());
    let entries = built
        .tracer
        .views()
        .views()
        .map(|v| v.stats().entries)
        .sum();
    let dirt = built.tracer;
    let (mrays, ratio, tests) = match diffuse {
        Some(set) if !set.rays.is_empty() => {
            let (d, b) = time_both(bvh, &dirt, set, repeats);
            let n = set.rays.len() as f64;
            (
                n / (d.wall_ms * 1e3),
                d.cpu_ms / b.cpu_ms,
                d.counters.tests as f64 / n,
            )
        }
        _ => (0.0, 0.0, 0.0),
    };
    Ok(SweepRow {
        scene: name.into(),
        tile: opts.capture.tile_size,
        buckets: opts.capture.buckets,
        face: opts.face_size,
        ms_build,
        build_vs_bvh: ms_build / bvh_ms,
        bytes,
        entries,
        diffuse_mrays_per_s: mrays,
        diffuse_time_vs_bvh: ratio,
        tests_per_ray: tests,
    })
}
