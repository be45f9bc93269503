//! `parallax bench reflect`: Widmer et al. 2015, Table 5 — multi-bounce glossy reflections
//! through a cube map of 1 and 2 layers, `N_p/N_s/N_b` in {1/8/1, 3/8/1, 3/4/3, 3/8/3}, for
//! the quad-tree and the DDA of every face and the BVH on the same rays ([`crate::reflect`]).
//!
//! Per layer count the cube map and the view are captured once (`T_cm` = capture + shade +
//! the structure's build; `T_ref` = the view's capture + shade); per configuration the BVH
//! render is the truth and every structure renders the same rays, the reflectors in
//! interleaved rounds (best wall time kept, `T_rr`). Scores: PSNR over the reflective pixels
//! (`psnr`), over the whole image (`psnr_image`) and SSIM, against the BVH render. `fps` is
//! `1000 / (T_ref + T_rr)` (the paper's: the cube map is static, built once). The BVH's
//! `T_rr` includes shading every hit it finds with shadow rays (its colours are computed,
//! not stored), so tracing speed is compared on a **trace-only pass**: the first-segment
//! rays of the configuration, identical for every structure, closest hits only
//! (`ms_trace`, `trace_mrays_per_s`, and hit `agreement` with the BVH).
//!
//! **Antialiased rows** (`spp` = `s²` > 1): the view is captured at `s` times its size and
//! every reflector renders all its `s x s` rays per pixel, box-filtered to the view's size
//! ([`crate::reflect::ReflectionImage::box_filtered`]); the truth is the BVH reflector on the
//! same rays with the same filter, so PSNR compares filtered images of identical ray sets.
//! Ray counts and times are those of all the rays (`rays_per_pixel` per filtered pixel).
//!
//! **Cube maps at the objects** (`cube_at` = `objects`, **not the paper's method**,
//! [`crate::reflect::objects`]): one cube map per reflective object (`T_cm` is all of them);
//! `psnr` is then against the truth coloured towards the centre of the cube each ray is
//! traced in. **Physical truth** (`physical_truth`, not the paper's measurement): a second
//! BVH render colouring every hit by its radiance along the ray
//! ([`crate::reflect::TruthColour::AlongTheRay`]) — the same image whatever the cube maps'
//! placement — scored over the same pixels (`psnr_physical`).

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_render::score::{Shading, score};
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;
use serde::Serialize;

use crate::SynthError;
use crate::dof::truth::masked_psnr;
use crate::layers::{Reference, capture_reference};
use crate::lightfield::{spp_side, supersampled};
use crate::method::{Method, MethodOptions};
use crate::reflect::render::primary_rays;
use crate::reflect::{
    CubeAt, CubeMaps, ReflectOptions, ReflectionImage, Reflector, SurfaceHit, TruthColour,
    render_reflections,
};
use parallax_core::{Ray, WorldStats};
use rayon::prelude::*;
use std::time::Instant;

/// Table 5's `N_p/N_s/N_b` configurations.
pub const TABLE5: [(u32, u32, u32); 4] = [(1, 8, 1), (3, 8, 1), (3, 4, 3), (3, 8, 3)];

/// One row of Table 5.
#[derive(Clone, Debug, Serialize)]
pub struct ReflectRow {
    pub method: String,
    /// Where the cube maps are (`camera`, the paper's, or `objects`) and how many.
    pub cube_at: String,
    pub cubes: usize,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub face: u32,
    pub n_p: u32,
    pub n_s: u32,
    pub n_b: u32,
    /// Primary rays per pixel (`s x s`, box-filtered).
    pub spp: u32,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dda_max_steps: Option<u32>,
    /// `T_cm`: cube capture + shade + build (the BVH's build for its row).
    pub ms_cm: f64,
    pub ms_build: f64,
    /// `T_ref`: the view's capture + shade.
    pub ms_ref: f64,
    /// `T_rr`: the reflection pass, best of the rounds; CPU ms of its threads.
    pub ms_rr: f64,
    pub ms_rr_cpu: f64,
    pub fps: f64,
    /// Traced segments per second of `T_rr`.
    pub mrays_per_s: f64,
    pub rays: u64,
    /// Traced segments per reflective pixel.
    pub rays_per_pixel: f64,
    pub reflective_pixels: usize,
    /// Nodes visited per traced segment, % of segments cut by a step bound.
    pub nodes_per_ray: f64,
    pub pct_truncated: f64,
    /// Trace-only pass over the first-segment rays of the configuration (the same rays for
    /// every row, [`primary_rays`]): best wall ms, closest hits per second, and the share of
    /// those rays whose hit lies within 5% of the BVH's hit distance of it (or both miss).
    pub trace_rays: usize,
    pub ms_trace: f64,
    pub trace_mrays_per_s: f64,
    pub agreement: f64,
    /// Mean weight of the extra samples' plane lookups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lookup_weight: Option<f64>,
    pub psnr: f64,
    /// PSNR over the reflective pixels against the physical truth (`--physical-truth`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub psnr_physical: Option<f64>,
    pub psnr_image: f64,
    pub ssim: f64,
}

/// What a Table 5 run measures.
#[derive(Clone, Debug)]
pub struct ReflectBench {
    pub camera: Pinhole,
    pub face: u32,
    pub layers: Vec<usize>,
    pub configs: Vec<(u32, u32, u32)>,
    /// Primary rays per pixel, one set of rows per value (squares `s x s`, [`spp_side`]).
    pub spp: Vec<u32>,
    /// One DDA row per value.
    pub dda_steps: Vec<u32>,
    pub quadtree: bool,
    pub opts: MethodOptions,
    pub reflect: ReflectOptions,
    pub repeats: u32,
    /// Relative thickness of the cube map's surfaces ([`parallax_screen::CubeMapTracer::thickness`];
    /// `None`: the paper's occlusion volumes).
    pub thickness: Option<f32>,
    /// Where the cube maps are (the paper: the camera; `objects` is not the paper's method,
    /// [`crate::reflect::objects`]).
    pub cube_at: CubeAt,
    /// Also score against the physical truth ([`TruthColour::AlongTheRay`]: one more BVH
    /// render per configuration), column `psnr_physical`.
    pub physical_truth: bool,
}

/// Table 5 (module docs); `progress` gets a line per step.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    b: &ReflectBench,
    progress: &dyn Fn(&str),
) -> Result<Vec<ReflectRow>, SynthError> {
    let seed = b.reflect.seed;
    let mut references = Vec::new();
    for &spp in &b.spp {
        let side = spp_side(spp)?;
        progress(&format!("view, {spp} ray(s) per pixel"));
        let cam = supersampled(&b.camera, side);
        let reference = capture_reference(scene, bvh, &cam, 1, Shading::Fixed, seed)?;
        references.push((spp, side, reference));
    }
    let eye = b.camera.frame.position;
    let mut rows = Vec::new();
    for &layers in &b.layers {
        progress(&format!(
            "cube map(s) at the {}, {layers} layer(s), {1}x{1} faces",
            b.cube_at, b.face
        ));
        let cubes = CubeMaps::capture(scene, bvh, b.cube_at, eye, b.face, layers, seed)?;
        let mut structures = Vec::new();
        if b.quadtree {
            let (r, t) = cubes.reflector(scene, Method::QuadTree, &b.opts, b.thickness)?;
            structures.push((r, None, t));
        }
        for &st in &b.dda_steps {
            let o = MethodOptions {
                dda_max_steps: st,
                ..b.opts
            };
            let (r, t) = cubes.reflector(scene, Method::Dda, &o, b.thickness)?;
            structures.push((r, Some(st), t));
        }
        let truth_tracer = cubes.truth(scene, bvh, eye, seed, TruthColour::TowardsCube);
        let physical = cubes.truth(scene, bvh, eye, seed, TruthColour::AlongTheRay);
        let runs = b
            .configs
            .iter()
            .flat_map(|c| references.iter().map(move |r| (c, r)));
        for (&(n_p, n_s, n_b), (spp, side, reference)) in runs {
            let (spp, side) = (*spp, *side);
            let ms_ref = reference.times.capture_ms + reference.times.shade_ms;
            let opts = ReflectOptions {
                n_p,
                n_s,
                n_b,
                ..b.reflect
            };
            progress(&format!("{layers} layer(s), {n_p}/{n_s}/{n_b}, {spp} spp"));
            let mut reflectors: Vec<&dyn Reflector> = vec![&truth_tracer];
            reflectors.extend(structures.iter().map(|(s, _, _)| s.as_ref()));
            let best = best_of(&reflectors, reference, eye, b, &opts, side)?;
            let truth = &best[0];
            let truth_physical = if b.physical_truth {
                Some(
                    render_reflections(&physical, reference, eye, b.face, &opts)?
                        .box_filtered(side)?,
                )
            } else {
                None
            };
            let rays = primary_rays(scene, reference, eye, b.face, &opts)?;
            let traced = trace_only(&reflectors, &rays, b.repeats);
            let truth_hits = &traced[0].1;
            let mut traced = traced.iter();
            let mut row = |name: String, img: &ReflectionImage, steps, ms_cm, ms_build| {
                let (ms_trace, hits) = traced.next().expect("one per reflector");
                let s = score(&img.image, &truth.image)?;
                let n = img.reflective_pixels();
                let psnr_physical = match &truth_physical {
                    Some(t) => Some(masked_psnr(&img.image, &t.image, &t.mask)?),
                    None => None,
                };
                Ok::<_, SynthError>(ReflectRow {
                    method: name,
                    cube_at: b.cube_at.to_string(),
                    cubes: cubes.count(),
                    layers,
                    scene: scene.name.clone(),
                    width: b.camera.width,
                    height: b.camera.height,
                    face: b.face,
                    n_p,
                    n_s,
                    n_b,
                    spp,
                    dda_max_steps: steps,
                    ms_cm,
                    ms_build,
                    ms_ref,
                    ms_rr: img.ms,
                    ms_rr_cpu: img.cpu_ms,
                    fps: 1e3 / (ms_ref + img.ms),
                    mrays_per_s: img.mrays_per_s(),
                    rays: img.stats.rays,
                    rays_per_pixel: img.stats.rays as f64 / n.max(1) as f64,
                    reflective_pixels: n,
                    nodes_per_ray: img.stats.per_ray(img.stats.nodes),
                    pct_truncated: 100.0 * img.stats.per_ray(img.stats.truncated),
                    trace_rays: rays.len(),
                    ms_trace: *ms_trace,
                    trace_mrays_per_s: rays.len() as f64 / (ms_trace * 1e3),
                    agreement: agreement(&rays, hits, truth_hits),
                    lookup_weight: (img.lookups > 0).then(|| img.mean_lookup_weight()),
                    psnr: masked_psnr(&img.image, &truth.image, &truth.mask)?,
                    psnr_physical,
                    psnr_image: s.psnr,
                    ssim: s.ssim,
                })
            };
            rows.push(row("bvh".into(), truth, None, f64::NAN, f64::NAN)?);
            for ((s, steps, times), img) in structures.iter().zip(&best[1..]) {
                rows.push(row(
                    s.name(),
                    img,
                    *steps,
                    times.total_ms(),
                    times.build_ms,
                )?);
            }
        }
    }
    Ok(rows)
}

/// Every reflector's render of `opts` over `reference` (the view at `side` times its size),
/// box-filtered by `side`, in `b.repeats` interleaved rounds, the fastest kept.
fn best_of(
    reflectors: &[&dyn Reflector],
    reference: &Reference,
    eye: Vec3,
    b: &ReflectBench,
    opts: &ReflectOptions,
    side: u32,
) -> Result<Vec<ReflectionImage>, SynthError> {
    let mut best: Vec<Option<ReflectionImage>> = vec![None; reflectors.len()];
    for _ in 0..b.repeats.max(1) {
        for (r, slot) in reflectors.iter().zip(best.iter_mut()) {
            let img = render_reflections(*r, reference, eye, b.face, opts)?;
            if slot.as_ref().is_none_or(|s| img.ms < s.ms) {
                *slot = Some(img);
            }
        }
    }
    best.into_iter()
        .map(|b| b.expect("one round").box_filtered(side))
        .collect()
}

/// Closest hits of `rays` through every reflector in parallel chunks, `repeats` interleaved
/// rounds, the best wall ms and the hits of each.
fn trace_only(
    reflectors: &[&dyn Reflector],
    rays: &[(Ray, u32)],
    repeats: u32,
) -> Vec<(f64, Vec<Option<SurfaceHit>>)> {
    let mut out: Vec<(f64, Vec<Option<SurfaceHit>>)> =
        vec![(f64::INFINITY, Vec::new()); reflectors.len()];
    for _ in 0..repeats.max(1) {
        for (r, slot) in reflectors.iter().zip(out.iter_mut()) {
            let t = Instant::now();
            let hits: Vec<Option<SurfaceHit>> = rays
                .par_chunks(1024)
                .flat_map_iter(|chunk| {
                    let mut s = WorldStats::default();
                    chunk
                        .iter()
                        .map(move |(ray, from)| r.trace_from(ray, *from, &mut s))
                        .collect::<Vec<_>>()
                })
                .collect();
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if ms < slot.0 {
                *slot = (ms, hits);
            }
        }
    }
    out
}

/// The share of `rays` whose hit in `hits` lies within 5% of the distance of the hit in
/// `truth` (or both miss).
fn agreement(
    rays: &[(Ray, u32)],
    hits: &[Option<SurfaceHit>],
    truth: &[Option<SurfaceHit>],
) -> f64 {
    let ok = rays
        .iter()
        .zip(hits.iter().zip(truth))
        .filter(|((ray, _), (a, b))| match (a, b) {
            (Some(a), Some(b)) => {
                (a.position - b.position).length() <= 0.05 * (b.position - ray.origin).length()
            }
            (None, None) => true,
            _ => false,
        })
        .count();
    ok as f64 / rays.len().max(1) as f64
}
