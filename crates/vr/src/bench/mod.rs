//! `parallax bench vr`: HVVR's Tables 2-6 (Hunt et al. 2018, §6) on our scenes — stage times
//! (visibility, shading) of both eyes per sampling scheme and samples per pixel, shade samples
//! per non-empty pixel for MSAA and SSAA, and ray throughput against the per-ray BVH baseline.
//!
//! Every scheme is run with each visibility method through
//! [`frame::visibility()`](crate::frame::visibility); a method that cannot run gives a row with
//! `available = false` and the reason, not an error. Per-ray visibility fuses traversal and intersection, so its
//! `ms_traversal` is the whole trace and `ms_intersect` is `None`. Times are the best of
//! `repeats` runs (least disturbed by other processes); the frame is both eyes.
//!
//! Schemes (Table 5): `normal` (pinhole grid, 90 deg vertical), `post-distort` (rift-cv1,
//! per-channel subpixel rays: 3 samples per pixel), `wide` (210 x 130 fisheye), `dof-0.5`,
//! `dof-0.25`, `dof-0.1` (rift-cv1 field of view, 3 mm pupil, focus in metres; thin lens, see
//! [`crate::presets`]), `foveated` (pinhole eye, [`SampleSet::foveated`] with the gaze at the
//! centre, a fovea of [`FOVEA_RADIUS_FRACTION`] of the eye height and footprints growing by
//! [`FOVEA_SLOPE`] per pixel of eccentricity beyond it).
//!
//! The beam caster's hierarchy is built once per sample set outside the timed region (HVVR
//! builds it once per sample pattern) for the head of the frame before, turned by a degree,
//! and each timed run moves it to this frame's head first ([`crate::Hierarchy::repose`], every
//! scheme's camera model; the move is part of the frame, as in Table 6); `ms_traversal` = the
//! block and tile culls and `ms_intersect` = sample test, each as CPU time divided by the thread count (the stages run interleaved over
//! blocks), and `mrays_per_s` is from the wall time of the whole cast into a visibility buffer
//! allocated once and reused by every method and repeat (per-ray and beam alike: paging in a
//! fresh buffer inside the timed region would be timed too, `docs/notes/vr.md`).
//! Not reproduced: HVVR's "pre-distort" row (a larger pinhole eye buffer resampled afterwards).

pub mod table3;
pub mod table6;

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_scene::animation::Animation;
use parallax_scene::{CameraDesc, Scene};
use serde::Serialize;

use crate::VisibilityBuffer;
use crate::frame::{Visibility, VrError, prepare, update_scene, visibility_into};
use crate::patterns::{FOVEA_RADIUS_FRACTION, FOVEA_SLOPE};
use crate::presets::{Dof, Preset, eye_cameras};
use crate::resolve::{ShadingMode, resolve};
use crate::shade::{ShadeOptions, VrShader};
use crate::{CastStats, Hierarchy, SampleSet};

/// The sampling schemes of Table 5 we reproduce.
pub const SCHEMES: &[&str] = &[
    "normal",
    "post-distort",
    "wide",
    "dof-0.5",
    "dof-0.25",
    "dof-0.1",
    "foveated",
];

/// One row of the VR benchmark.
#[derive(Clone, Debug, Serialize)]
pub struct VrBenchRow {
    pub scheme: String,
    pub scene: String,
    pub visibility: String,
    pub shading: String,
    /// Both eyes side by side.
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    /// Samples of both eyes (3 per pixel for per-channel schemes).
    pub samples: u64,
    pub rays: u64,
    pub available: bool,
    /// Why a row is unavailable, or what a figure means.
    pub note: String,
    pub ms_traversal: Option<f64>,
    pub ms_intersect: Option<f64>,
    pub ms_shade: Option<f64>,
    /// Shade invocations per sample with any hit.
    pub shades_per_nonempty_pixel: Option<f64>,
    /// Rays per second of the visibility stage, in millions.
    pub mrays_per_s: Option<f64>,
    /// The per-ray baseline's rate (our BVH's single rays, `per-ray`) for the same scheme.
    pub baseline_mrays_per_s: Option<f64>,
    pub threads: usize,
}

/// What to measure.
#[derive(Clone, Debug)]
pub struct VrBenchOptions {
    /// Both eyes (each eye gets `width / 2`).
    pub width: u32,
    pub height: u32,
    pub spp: Vec<u32>,
    pub schemes: Vec<String>,
    pub shading: Vec<ShadingMode>,
    pub visibility: Vec<Visibility>,
    pub repeats: u32,
}

/// Eye sample sets of a scheme, or why it cannot be run.
pub(crate) fn scheme_sets(
    scheme: &str,
    head: &CameraDesc,
    w: u32,
    h: u32,
    spp: u32,
) -> Result<[SampleSet; 2], VrError> {
    let (preset, dof) = match scheme {
        "normal" => (Preset::Custom, None),
        "post-distort" => (Preset::RiftCv1, None),
        "wide" => (Preset::Wide210x130, None),
        "foveated" => (Preset::Custom, None),
        s => match s.strip_prefix("dof-").and_then(|f| f.parse::<f32>().ok()) {
            Some(focus) => (
                Preset::RiftCv1,
                Some(Dof {
                    aperture: 0.003,
                    focus,
                }),
            ),
            None => {
                return Err(VrError::Invalid(format!(
                    "unknown scheme {s:?}; expected one of {}",
                    SCHEMES.join(", ")
                )));
            }
        },
    };
    let mut spec = preset.spec();
    spec.width = (w / 2).max(1);
    spec.height = h.max(1);
    let [l, r] = eye_cameras(&spec, head, dof)?;
    if scheme == "foveated" {
        let fov = |c| {
            let gaze = glam::Vec2::new(spec.width as f32, spec.height as f32) * 0.5;
            let radius = FOVEA_RADIUS_FRACTION * spec.height as f32;
            SampleSet::foveated(c, gaze, radius, FOVEA_SLOPE, spp)
        };
        return Ok([fov(l)?, fov(r)?]);
    }
    Ok([SampleSet::grid(l, spp), SampleSet::grid(r, spp)])
}

/// The best wall time of `repeats` runs of `f` (ms) and the last run's value.
fn best_of<T>(
    repeats: u32,
    mut f: impl FnMut() -> Result<T, VrError>,
) -> Result<(f64, T), VrError> {
    best_of_moved(repeats, &mut [None, None], &[], |_| f())
}

/// [`best_of`] of a frame of a moving head: before each run (untimed) both eyes' hierarchies
/// are moved back to the frame before's sets `before`; `f` moves them on and casts.
fn best_of_moved<T>(
    repeats: u32,
    prepared: &mut [Option<Hierarchy>; 2],
    before: &[SampleSet],
    mut f: impl FnMut(&mut [Option<Hierarchy>; 2]) -> Result<T, VrError>,
) -> Result<(f64, T), VrError> {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeats.max(1) {
        for (h, b) in prepared.iter_mut().zip(before) {
            if let Some(h) = h {
                h.repose(b)?;
            }
        }
        let t = Instant::now();
        let v = f(prepared)?;
        best = best.min(t.elapsed().as_secs_f64() * 1e3);
        out = Some(v);
    }
    Ok((best, out.expect("at least one run")))
}

/// Runs the benchmark. Errors on invalid options (unknown scheme, bad spp); a visibility
/// method that fails on a scheme gives a row with `available = false` and the reason.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    head: &CameraDesc,
    opts: &VrBenchOptions,
) -> Result<Vec<VrBenchRow>, VrError> {
    for &s in &opts.spp {
        if !matches!(s, 1 | 4 | 8 | 16 | 32) {
            return Err(VrError::Invalid(format!(
                "samples per pixel must be 1, 4, 8, 16 or 32, got {s}"
            )));
        }
    }
    let threads = rayon::current_num_threads();
    let shader = VrShader::new(scene, bvh, ShadeOptions::default());
    let mut rows = Vec::new();
    for scheme in &opts.schemes {
        for &spp in &opts.spp {
            let base = |vis: Visibility, shading: ShadingMode| VrBenchRow {
                scheme: scheme.clone(),
                scene: scene.name.clone(),
                visibility: vis.name().into(),
                shading: shading.name().into(),
                width: opts.width,
                height: opts.height,
                samples_per_pixel: spp,
                samples: 0,
                rays: 0,
                available: false,
                note: String::new(),
                ms_traversal: None,
                ms_intersect: None,
                ms_shade: None,
                shades_per_nonempty_pixel: None,
                mrays_per_s: None,
                baseline_mrays_per_s: None,
                threads,
            };
            let sets = scheme_sets(scheme, head, opts.width, opts.height, spp)?;
            let samples: u64 = sets.iter().map(|s| s.samples.len() as u64).sum();
            let rays: u64 = sets.iter().map(|s| s.ray_count() as u64).sum();
            let mut baseline = None;
            // One visibility buffer per eye, reused by every method and repeat (as frame
            // after frame in a renderer): the timed region writes results, it does not
            // allocate and page in ~10 bytes per ray.
            let mut out = [
                VisibilityBuffer::new(&sets[0]),
                VisibilityBuffer::new(&sets[1]),
            ];
            // The frame before's head (module docs): turned by a degree, the same samples.
            let before = scheme_sets(scheme, &head.turned(1.0), opts.width, opts.height, spp)?;
            for &v in &opts.visibility {
                let mut prepared = [prepare(v, &before[0])?, prepare(v, &before[1])?];
                let traced = best_of_moved(opts.repeats, &mut prepared, &before, |prepared| {
                    let [o0, o1] = &mut out;
                    let mut eye = |e: usize, o: &mut VisibilityBuffer| {
                        if let Some(h) = &mut prepared[e] {
                            h.repose(&sets[e])?;
                        }
                        visibility_into(v, bvh, &sets[e], prepared[e].as_ref(), o)
                    };
                    let a = eye(0, o0)?;
                    let b = eye(1, o1)?;
                    Ok::<_, VrError>([a, b])
                });
                let (trace_ms, stats) = match traced {
                    Ok(x) => x,
                    Err(e) => {
                        for &m in &opts.shading {
                            rows.push(VrBenchRow {
                                samples,
                                rays,
                                note: e.to_string(),
                                baseline_mrays_per_s: baseline,
                                ..base(v, m)
                            });
                        }
                        continue;
                    }
                };
                let mrays = rays as f64 / (trace_ms * 1e3);
                // Beam stages: CPU time over both eyes / threads (see the module docs).
                let stage_ms = |f: fn(&CastStats) -> std::time::Duration| {
                    let cpu: f64 = stats
                        .iter()
                        .filter_map(|s| s.as_ref())
                        .map(|s| f(s).as_secs_f64())
                        .sum();
                    cpu * 1e3 / threads as f64
                };
                let beam = stats[0].is_some();
                let (ms_trav, ms_isect) = if beam {
                    (
                        stage_ms(|s| s.block_cull + s.tile_cull),
                        Some(stage_ms(|s| s.sample_test)),
                    )
                } else {
                    (trace_ms, None)
                };
                let bufs = [&out[0], &out[1]];
                if v == Visibility::PerRay {
                    baseline = Some(mrays);
                }
                for &m in &opts.shading {
                    let (shade_ms, resolved) = best_of(opts.repeats, || {
                        Ok([
                            resolve(&sets[0], bufs[0], &shader, m),
                            resolve(&sets[1], bufs[1], &shader, m),
                        ])
                    })?;
                    let shades: u64 = resolved.iter().map(|r| r.shades).sum();
                    let nonempty: u64 = resolved.iter().map(|r| r.nonempty).sum();
                    rows.push(VrBenchRow {
                        samples,
                        rays,
                        available: true,
                        note: if v == Visibility::PerRay {
                            "per-ray: traversal and intersection fused in ms_traversal".into()
                        } else {
                            String::new()
                        },
                        ms_traversal: Some(ms_trav),
                        ms_intersect: ms_isect,
                        ms_shade: Some(shade_ms),
                        shades_per_nonempty_pixel: Some(shades as f64 / nonempty.max(1) as f64),
                        mrays_per_s: Some(mrays),
                        baseline_mrays_per_s: baseline,
                        ..base(v, m)
                    });
                }
            }
        }
    }
    Ok(rows)
}

/// HVVR Table 1: the scene update of one frame — rigid animation of the scene's props (the
/// "vert xform" column) and the BVH refit (the other columns together), against a full build.
#[derive(Clone, Debug, Serialize)]
pub struct UpdateRow {
    pub scene: String,
    pub vertices: usize,
    pub triangles: usize,
    pub moving_objects: usize,
    pub moving_vertices: usize,
    pub build_ms: f64,
    pub animate_ms: f64,
    pub refit_ms: f64,
}

/// Measures [`UpdateRow`] (best of `repeats` updates to t = 1 s, on a copy of the mesh).
pub fn update_row(scene: &Scene, repeats: u32) -> Result<UpdateRow, VrError> {
    let mut mesh = scene.mesh.clone();
    let t = Instant::now();
    let mut bvh = Bvh::try_build(&mesh)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let anim = Animation::for_scene(scene);
    let (mut animate_ms, mut refit_ms) = (f64::INFINITY, f64::INFINITY);
    for k in 0..repeats.max(1) {
        let u = update_scene(&anim, &mut mesh, &mut bvh, 1.0 + k as f32 * 0.1)?;
        animate_ms = animate_ms.min(u.animate_ms);
        refit_ms = refit_ms.min(u.refit_ms);
    }
    Ok(UpdateRow {
        scene: scene.name.clone(),
        vertices: mesh.vertex_count(),
        triangles: mesh.triangle_count(),
        moving_objects: anim.moving_objects(),
        moving_vertices: anim.moving_vertices(&mesh),
        build_ms,
        animate_ms,
        refit_ms,
    })
}

/// The rows as a Markdown table.
pub fn markdown(rows: &[VrBenchRow]) -> String {
    let f = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    let mut s = String::from(
        "| scheme | scene | visibility | shading | size | spp | rays | traversal ms | intersect ms | shade ms | shades/px | Mrays/s | per-ray Mrays/s | note |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.scheme,
            r.scene,
            r.visibility,
            r.shading,
            r.width,
            r.height,
            r.samples_per_pixel,
            r.rays,
            f(r.ms_traversal, 1),
            f(r.ms_intersect, 1),
            f(r.ms_shade, 1),
            f(r.shades_per_nonempty_pixel, 2),
            f(r.mrays_per_s, 2),
            f(r.baseline_mrays_per_s, 2),
            if r.available { "" } else { "unavailable: " }.to_string() + &r.note,
        );
    }
    s
}
