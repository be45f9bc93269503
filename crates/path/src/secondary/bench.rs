//! `parallax bench ldc`: the layered depth cube paper's Table 1 (Bürger et al. 2007, §3) —
//! LDC build time (A) and secondary-ray trace time (B) at several LDI resolutions (the paper:
//! 512² and 1024²), the layers the scene needs (its depth complexity), with the BVH's build
//! and trace times on the same rays in the same run, and the hit agreement.
//!
//! **Rays.** From the rasterized view (the primary hits of every pixel): a mirror reflection
//! ray (`reflect`), a refraction ray into the surface (`refract`, ior 1.5 or the material's),
//! and a shadow ray to each light (`shadow`) — every surface is treated as reflective,
//! refractive and lit, so each effect has a ray per pixel whatever the materials are; plus
//! the synthetic sets of [`super::rays`] (`axis`, `random`, `surface`). The BVH answers them
//! first (the reference); then both tracers replay all of them in interleaved rounds (best
//! round per tracer and set). The view is also rendered with the scene's own materials by
//! each tracer ([`super::render()`]), and the LDC image is scored against the BVH image.
//!
//! **Times** are wall-clock on all threads of the run; the build is timed once per
//! resolution (`ms_build` = assignment + peeling + orientation + grid + the tracer's layout,
//! each also reported), the traces are the best of `repeats` rounds.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `resolutions` | `Vec<u32>` | 512, 1024 | LDI resolutions (pixels along the box's longest side) |
//! | `ldc` | [`LdcSettings`] | defaults | build and trace options (resolution overridden) |
//! | `secondary` | [`SecondaryOptions`] | defaults | the rendered image's effects and bounces |
//! | `synthetic_rays` | usize | 2^18 | rays per synthetic set |
//! | `repeats` | u32 | 3 | interleaved timing rounds |
//! | `tolerance` | `Option<f32>` | the LDC's `eps` | agreement distance (world units) |
//! | `seed` | u64 | 7 | synthetic ray streams |
//! | `view_roi` | `Option<f32>` | none | fit the cube to the view ([`super::roi::view_roi`], this margin) instead of `ldc.build.roi` |

use glam::Vec3;
use parallax_core::image::GBuffer;
use parallax_core::{Aabb, Ray};
use parallax_raster::ldc::{LayeredDepthCube, LdcStats};
use parallax_render::brdf;
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::camera::{Camera, Pinhole};
use parallax_scene::{MaterialKind, Scene};
use parallax_screen::ldc::LdcTracer;
use rayon::prelude::*;
use serde::Serialize;

use super::classify::{Classifier, Disagreements};
use super::lights::{light_at, whitted_lights};
use super::rays::{RaySet, ray_set};
use super::render::{Answers, pixel_ray, trace_closest, trace_occluded};
use super::replay::{Contender, EffectRow, RayBatch, replay_rows, score};
use super::roi::{DEFAULT_TRIM, view_roi};
use super::{Effect, SecondaryError, SecondaryOptions, render};
use crate::tracers::{BuiltTracer, LdcSettings, TracerKind, TracerOptions, build_tracer};

/// Bench options (module table).
#[derive(Clone, Debug)]
pub struct LdcBenchSetup {
    pub resolutions: Vec<u32>,
    pub ldc: LdcSettings,
    pub secondary: SecondaryOptions,
    pub synthetic_rays: usize,
    pub repeats: u32,
    pub tolerance: Option<f32>,
    pub seed: u64,
    pub view_roi: Option<f32>,
}

impl Default for LdcBenchSetup {
    fn default() -> Self {
        Self {
            resolutions: vec![512, 1024],
            ldc: LdcSettings::default(),
            secondary: SecondaryOptions::default(),
            synthetic_rays: 1 << 18,
            repeats: 3,
            tolerance: None,
            seed: 7,
            view_roi: None,
        }
    }
}

/// One row: a tracer at one resolution on one ray set (`rays_set = "view"`: the three view
/// effects together).
#[derive(Clone, Debug, Default, Serialize)]
pub struct LdcBenchRow {
    pub scene: String,
    pub method: String,
    /// LDI resolution (0 for the BVH).
    pub resolution: u32,
    pub rays_set: String,
    pub rays: u64,
    pub width: u32,
    pub height: u32,
    /// Depth complexity: the most samples of one LDI pixel (0 for the BVH).
    pub layers: u32,
    pub layers_per_axis: [u32; 3],
    pub samples: usize,
    pub bytes: usize,
    /// `bytes / layers` (the LDC's memory per layer).
    pub bytes_per_layer: f64,
    pub ms_build: f64,
    pub ms_assign: f64,
    pub ms_peel: f64,
    pub ms_orient: f64,
    pub ms_grid: f64,
    /// The tracer's block-major layout.
    pub ms_setup: f64,
    pub ms_trace: f64,
    pub mrays_per_s: f64,
    /// `ms_trace` over the BVH's on the same rays.
    pub trace_vs_bvh: f64,
    pub agreement: f64,
    pub only_bvh: u64,
    pub only_ldc: u64,
    pub differ: u64,
    pub early: u64,
    pub outside: u64,
    pub nodes_per_ray: f64,
    pub tests_per_ray: f64,
    pub steps_per_ray: f64,
    pub pct_truncated: f64,
    /// The tracer's own secondary render of the view (scene materials) against the BVH's.
    pub psnr: f64,
    pub ssim: f64,
    pub ms_render: f64,
    pub eps: f32,
    pub sample_test: String,
    pub roi: bool,
    /// The LDC's disagreements by class ([`super::classify`]).
    pub classes: Disagreements,
    /// The LDC's box (the padded scene or region-of-interest bounds; zero for the BVH).
    pub box_min: [f32; 3],
    pub box_max: [f32; 3],
    pub threads: usize,
}

/// The view's ray sets.
const VIEW: [&str; 3] = ["reflect", "refract", "shadow"];

/// The layered depth cube as the bench builds it (the tracer factory's `ldc`, kept concrete
/// for the classifier).
struct LdcBuilt {
    tracer: LdcTracer,
    build_ms: f64,
    bounds: Option<Aabb>,
}

impl LdcBuilt {
    fn build(scene: &Scene, s: &LdcSettings) -> Result<Self, SecondaryError> {
        let start = std::time::Instant::now();
        let cube = LayeredDepthCube::build(scene, s.resolution, &s.build)?;
        let bounds = s.build.roi.map(|_| cube.bounds);
        let tracer = LdcTracer::new(cube, s.trace)
            .map_err(|e| SecondaryError::InvalidOptions(e.to_string()))?;
        Ok(Self {
            tracer,
            build_ms: start.elapsed().as_secs_f64() * 1e3,
            bounds,
        })
    }
}

/// The view's reflection, refraction and shadow rays (module docs), in pixel order.
pub fn view_rays(scene: &Scene, camera: &Pinhole, g: &GBuffer) -> Vec<(Effect, Vec<Ray>)> {
    let lights = whitted_lights(scene);
    let (w, h) = (camera.width, camera.height);
    let per_pixel: Vec<(Option<Ray>, Option<Ray>, Vec<Ray>)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let (Some(ray), true) = (pixel_ray(camera, x, y), g.is_hit(x, y)) else {
                return (None, None, Vec::new());
            };
            let k = g.index(x, y);
            let t = (g.position[k] - ray.origin).dot(ray.dir) / ray.dir.length_squared();
            let hit = parallax_core::WorldHit::exact(&ray, t, g.primitive_id[k], g.barycentrics[k]);
            let s = SurfacePoint::from_world_hit(scene, &ray, &hit);
            let (wo, n) = (-ray.dir.normalize(), s.shading_normal);
            let reflect = brdf::reflect(wo, n);
            let ior = match s.material.kind {
                MaterialKind::Dielectric { ior } => ior,
                _ => 1.5,
            };
            let eta = if s.front_face { ior } else { 1.0 / ior };
            let refract = brdf::refract(wo, n, eta);
            let spawn = |d: Vec3| Ray::new(s.spawn_origin(d), d);
            let shadows = lights
                .iter()
                .filter_map(|l| {
                    let (wi, dist, _) = light_at(l, s.position)?;
                    (wi.dot(s.geometric_normal) > 0.0).then(|| {
                        let o = s.spawn_origin(wi);
                        let t_max = if dist.is_finite() {
                            (s.position + wi * dist - o).length() * 0.999
                        } else {
                            f32::INFINITY
                        };
                        Ray::segment(o, wi, 0.0, t_max)
                    })
                })
                .collect();
            (Some(spawn(reflect)), refract.map(spawn), shadows)
        })
        .collect();
    let mut reflect = Vec::new();
    let mut refract = Vec::new();
    let mut shadow = Vec::new();
    for (a, b, c) in per_pixel {
        reflect.extend(a);
        refract.extend(b);
        shadow.extend(c);
    }
    vec![
        (Effect::Reflect, reflect),
        (Effect::Refract, refract),
        (Effect::Shadow, shadow),
    ]
}

/// A labelled ray set with the reference's answers.
struct RefSet {
    label: &'static str,
    rays: Vec<Ray>,
    answers: Answers,
}

fn reference_sets(
    scene: &Scene,
    camera: &Pinhole,
    g: &GBuffer,
    bvh: &BuiltTracer,
    bounds: &Aabb,
    setup: &LdcBenchSetup,
) -> Vec<RefSet> {
    let mut sets = Vec::new();
    for (effect, rays) in view_rays(scene, camera, g) {
        let answers = if effect == Effect::Shadow {
            Answers::Occluded(trace_occluded(bvh.tracer.as_ref(), &rays).0)
        } else {
            Answers::Closest(trace_closest(bvh.tracer.as_ref(), &rays).0)
        };
        sets.push(RefSet {
            label: effect.name(),
            rays,
            answers,
        });
    }
    for set in RaySet::ALL {
        let rays = ray_set(set, scene, bounds, setup.synthetic_rays, setup.seed);
        let answers = Answers::Closest(trace_closest(bvh.tracer.as_ref(), &rays).0);
        sets.push(RefSet {
            label: set.name(),
            rays,
            answers,
        });
    }
    sets
}

fn fill(row: &mut LdcBenchRow, r: &EffectRow) {
    row.rays_set = r.effect.clone();
    row.rays = r.rays;
    row.ms_trace = r.ms_trace;
    row.mrays_per_s = r.mrays_per_s;
    row.agreement = r.agreement;
    row.only_bvh = r.counts.only_reference;
    row.only_ldc = r.counts.only_other;
    row.differ = r.counts.differ;
    row.early = r.counts.early;
    row.outside = r.counts.outside;
    row.nodes_per_ray = r.nodes_per_ray;
    row.tests_per_ray = r.tests_per_ray;
    row.steps_per_ray = r.steps_per_ray;
    row.pct_truncated = r.pct_truncated;
}

fn ldc_fields(row: &mut LdcBenchRow, s: &LdcStats) {
    row.layers = s.max_depth_complexity;
    row.layers_per_axis = s.ldis.map(|l| l.capture.max_depth_complexity);
    row.samples = s.samples;
    row.ms_assign = s.assign_ms;
    row.ms_peel = s.peel_ms;
    row.ms_orient = s.orient_ms;
    row.ms_grid = s.grid_ms;
    row.roi = s.roi;
    row.box_min = s.box_min.to_array();
    row.box_max = s.box_max.to_array();
}

/// Runs the bench on `scene` seen by `camera` (module docs).
pub fn run(
    scene: &Scene,
    camera: &Pinhole,
    setup: &LdcBenchSetup,
) -> Result<Vec<LdcBenchRow>, SecondaryError> {
    setup.secondary.validate()?;
    if setup.resolutions.is_empty() {
        return Err(SecondaryError::InvalidOptions(
            "no LDI resolution given".into(),
        ));
    }
    let view = parallax_raster::View::from_pinhole(camera)?;
    let g = parallax_raster::capture_gbuffer(scene, &view)?
        .layers
        .layers
        .remove(0);
    let cam = Camera::Pinhole(camera.clone());
    let mut base_ldc = setup.ldc;
    if let Some(margin) = setup.view_roi {
        base_ldc.build.roi = view_roi(scene, camera, &g, DEFAULT_TRIM, margin);
    }
    let build = |kind, ldc: &LdcSettings| {
        build_tracer(
            kind,
            scene,
            &cam,
            &TracerOptions {
                ldc: *ldc,
                ..TracerOptions::default()
            },
        )
    };
    let bvh = build(TracerKind::Bvh, &base_ldc)?;
    let truth = render(scene, camera, &g, bvh.tracer.as_ref(), &setup.secondary)?;
    // Synthetic origins fill the LDC's box (the ROI when one is given).
    let bounds = match base_ldc.build.roi {
        Some([lo, hi]) => Aabb::new(
            scene.mesh.bounds().min.max(lo),
            scene.mesh.bounds().max.min(hi),
        ),
        None => scene.mesh.bounds(),
    };
    let sets = reference_sets(scene, camera, &g, &bvh, &bounds, setup);
    let batches: Vec<RayBatch> = sets
        .iter()
        .map(|s| RayBatch {
            label: s.label,
            bounce: -1,
            rays: &s.rays,
            answers: &s.answers,
        })
        .collect();
    let tolerance = setup.tolerance.unwrap_or(base_ldc.trace.eps);
    let base = LdcBenchRow {
        scene: scene.name.clone(),
        width: camera.width,
        height: camera.height,
        eps: setup.ldc.trace.eps,
        sample_test: setup.ldc.trace.test.name().to_string(),
        threads: rayon::current_num_threads(),
        ..LdcBenchRow::default()
    };
    let mut out = Vec::new();
    for &res in &setup.resolutions {
        let settings = LdcSettings {
            resolution: res,
            ..base_ldc
        };
        let ldc = LdcBuilt::build(scene, &settings)?;
        let image = render(scene, camera, &g, &ldc.tracer, &setup.secondary)?;
        let (psnr, ssim) = score(&image.image, &truth.image)?;
        let contenders = [
            Contender {
                tracer: bvh.tracer.as_ref(),
                build_ms: bvh.build_ms,
                bounds: None,
            },
            Contender {
                tracer: &ldc.tracer,
                build_ms: ldc.build_ms,
                bounds: ldc.bounds,
            },
        ];
        let rows = replay_rows(&batches, &contenders, setup.repeats, tolerance);
        let stats = ldc.tracer.cube().stats;
        let classifier = Classifier {
            scene,
            ldc: &ldc.tracer,
            bvh: bvh.tracer.as_ref(),
        };
        let classes: Vec<(&str, Disagreements)> = sets
            .iter()
            .map(|s| (s.label, classifier.classify(&s.rays, &s.answers, tolerance)))
            .collect();
        let view_total = |method: &str| -> EffectRow {
            let mut t = EffectRow {
                method: method.to_string(),
                effect: "view".into(),
                bounce: -1,
                ..EffectRow::default()
            };
            let (mut nodes, mut tests, mut steps, mut trunc) = (0.0, 0.0, 0.0, 0.0);
            for r in rows
                .iter()
                .filter(|r| r.method == method && VIEW.contains(&r.effect.as_str()))
            {
                t.rays += r.rays;
                t.counts += r.counts;
                t.ms_trace += r.ms_trace;
                let n = r.rays as f64;
                nodes += r.nodes_per_ray * n;
                tests += r.tests_per_ray * n;
                steps += r.steps_per_ray * n;
                trunc += r.pct_truncated * n;
            }
            let n = (t.rays as f64).max(1.0);
            t.agreement = t.counts.fraction();
            t.mrays_per_s = t.rays as f64 / (t.ms_trace * 1e3).max(1e-12);
            (
                t.nodes_per_ray,
                t.tests_per_ray,
                t.steps_per_ray,
                t.pct_truncated,
            ) = (nodes / n, tests / n, steps / n, trunc / n);
            t
        };
        let totals = [view_total("bvh"), view_total("ldc")];
        let bvh_ms = |label: &str| {
            rows.iter()
                .chain(&totals)
                .find(|r| r.method == "bvh" && r.effect == label)
                .map_or(f64::NAN, |r| r.ms_trace)
        };
        for r in rows.iter().chain(&totals) {
            let mut row = base.clone();
            fill(&mut row, r);
            row.trace_vs_bvh = r.ms_trace / bvh_ms(&r.effect);
            row.method = r.method.clone();
            if r.method == "ldc" {
                row.resolution = res;
                ldc_fields(&mut row, &stats);
                row.bytes = ldc.tracer.bytes();
                row.bytes_per_layer = row.bytes as f64 / stats.max_depth_complexity.max(1) as f64;
                row.classes = classes
                    .iter()
                    .filter(|(l, _)| *l == r.effect || r.effect == "view" && VIEW.contains(l))
                    .fold(Disagreements::default(), |mut a, (_, d)| {
                        a += *d;
                        a
                    });
                row.ms_build = ldc.build_ms;
                row.ms_setup = ldc.build_ms - stats.total_ms;
                row.psnr = psnr;
                row.ssim = ssim;
                row.ms_render = image.ms;
            } else {
                row.bytes = bvh.bytes;
                row.ms_build = bvh.build_ms;
                row.psnr = f64::INFINITY;
                row.ssim = 1.0;
                row.ms_render = truth.ms;
            }
            out.push(row);
        }
    }
    Ok(out)
}
