//! `parallax bench dof`: Widmer et al. 2015, Table 4 (depth of field: `N_pri / N_sec` lens
//! rays / colour samples per ray, 1 and 2 layers, quad-tree and DDA; `T_ref`, `T_dof`,
//! Mrays/s, FPS) and Fig. 8 (equal-time noise with and without secondary samples), scored
//! against the converged BVH thin-lens image ([`crate::dof::truth::thin_lens_truth`]).
//!
//! **Rows.** Per layer count one guarded reference is captured and shaded (`T_ref` =
//! capture + shade + the structure's build; the reference is `guard` pixels wider on every
//! side, [`crate::dof::setup`]); every entrant ([`DofEntry`]: method, inpainting, DDA max
//! steps, `N_pri / N_sec`) renders the same lens view. PSNR / SSIM over the whole image and
//! `psnr_edges` over the pixels within the circle of confusion of a large layer-0 depth
//! discontinuity ([`crate::dof::truth::discontinuity_mask`], Fig. 9's case).
//!
//! **Interleaved rounds** (as `bench warp`): all structures of a layer count are built
//! first, then each of `repeats` rounds renders every entrant once; `ms_dof` is the best
//! round. Within a round the entrants run grouped by `N_pri / N_sec` (so the quad-tree and
//! the DDA at the same lens rays run back to back), and every second round in the reverse
//! order (A B, then B A: a load change during a round weighs on both sides alike);
//! `ms_dof_cpu_rounds` keeps every round's CPU time for per-round ratios. Mrays/s = lens rays (`N_pri` per pixel, secondaries not counted: they are not
//! traced) / `T_dof`.
//!
//! **Fig. 8** ([`equal_time`]): with `N_sec > 1` an image costs more than `N_pri` lens rays
//! but less than `N_pri N_sec`; each secondary row gets `psnr_equal_time`, the PSNR that
//! plain lens sampling (`N_sec = 1`, same method and layers, `N_pri` in a sweep) reaches in
//! the same `T_dof` (CPU time of the rendering threads, robust on a shared machine),
//! interpolated linearly in `log T_dof` between the sweep's rows, and
//! `psnr_self`, the PSNR against the method's own converged image (`N_pri` =
//! `own_spp`, no secondaries): its noise alone, without the layers' bias.

use parallax_bvh::Bvh;
use parallax_core::spread::Spread;
use parallax_core::{Image, Rgb};
use parallax_render::score::{Shading, score};
use parallax_scene::Scene;
use parallax_screen::CubeNear;
use serde::Serialize;

use crate::SynthError;
use crate::dof::truth::{discontinuity_mask, masked_psnr, thin_lens_truth};
use crate::dof::{DofImage, DofOptions, DofSetup, DofStructure, capture_dof_reference, render_dof};
use crate::layers::Reference;
use crate::method::{Method, MethodOptions, cube_near_name};
use crate::warp::Resample;

/// One configuration of Table 4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DofEntry {
    pub method: Method,
    pub layers: usize,
    /// Quad-tree single-layer inpainting traversal (§4.1, Fig. 9c).
    pub inpaint: bool,
    pub dda_max_steps: u32,
    pub n_pri: u32,
    pub n_sec: u32,
}

impl DofEntry {
    /// The structure this entry traces (entries differing only in `N_pri / N_sec` share it).
    fn structure_key(&self) -> (Method, bool, u32) {
        let steps = if self.method == Method::Dda {
            self.dda_max_steps
        } else {
            0
        };
        (self.method, self.inpaint, steps)
    }

    /// `quadtree`, `quadtree+inpaint`, `dda`.
    pub fn label(&self) -> String {
        if self.inpaint {
            format!("{}+inpaint", self.method)
        } else {
            self.method.to_string()
        }
    }
}

/// The view and settings of a depth-of-field benchmark.
#[derive(Clone, Debug)]
pub struct DofBench {
    pub setup: DofSetup,
    pub shading: Shading,
    pub seed: u64,
    /// Lens samples per pixel of the BVH ground truth.
    pub truth_spp: u32,
    /// Interleaved timing rounds (best kept), >= 1.
    pub repeats: u32,
    pub cube_near: CubeNear,
    pub sigma: f32,
    pub secondary_resample: Resample,
}

/// One row of Table 4 / Fig. 8.
#[derive(Clone, Debug, Default, Serialize)]
pub struct DofRow {
    pub method: String,
    pub layers: usize,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub inpaint: bool,
    pub n_pri: u32,
    pub n_sec: u32,
    pub sigma: f32,
    pub aperture_m: f32,
    pub focus_m: f32,
    pub guard_px: u32,
    pub cube_near: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dda_max_steps: Option<u32>,
    pub repeats: u32,
    /// `T_ref`: capture + shade + build of the guarded reference.
    pub ms_ref: f64,
    pub ms_capture: f64,
    pub ms_shade: f64,
    pub ms_build: f64,
    /// `T_dof`: the depth-of-field image, best round (wall clock).
    pub ms_dof: f64,
    /// CPU milliseconds of the rendering threads, best round (the time column to compare
    /// methods by on a loaded machine).
    pub ms_dof_cpu: f64,
    /// The CPU milliseconds of every round, in round order (per-round ratios between
    /// entries: rows of one layer count ran in the same rounds).
    pub ms_dof_cpu_rounds: Vec<f64>,
    /// `1000 / (T_ref + T_dof)`.
    pub fps: f64,
    /// Lens rays per second of `T_dof` (millions).
    pub mrays_per_s: f64,
    /// Lens rays per CPU-second of the rendering threads (millions).
    pub mrays_per_cpu_s: f64,
    pub nodes_per_ray: f64,
    pub tests_per_ray: f64,
    pub pct_layer2: f64,
    pub pct_miss: f64,
    pub pct_occlusion: f64,
    pub pct_truncated: f64,
    /// Mean weight of a secondary sample (NaN without secondaries).
    pub secondary_weight: f64,
    pub psnr: f64,
    pub ssim: f64,
    /// PSNR over the pixels near large depth discontinuities.
    pub psnr_edges: f64,
    /// Fig. 8: PSNR against the method's own converged image (NaN when not computed).
    pub psnr_self: f64,
    /// Fig. 8: PSNR of plain lens sampling at the same `T_dof` (NaN when not computed).
    pub psnr_equal_time: f64,
    /// The equal-quality comparison with the DDA (quad-tree rows of `bench dof
    /// --equal-quality`, [`super::dof_equal`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub equal_quality: Option<EqualQuality>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

/// The DDA's CPU time at a quad-tree row's PSNR, and the ratio ([`super::dof_equal`]). JSON:
/// the `equal_quality` object of the quad-tree's [`DofRow`].
#[derive(Clone, Debug, Serialize)]
pub struct EqualQuality {
    pub dda_max_steps: u32,
    /// `N_pri` of the two DDA rows bracketing the quad-tree's PSNR (`None`: outside the
    /// DDA's measured range).
    pub dda_n_pri_bracket: Option<[u32; 2]>,
    /// Their PSNR (dB).
    pub dda_psnr_bracket: Option<[f64; 2]>,
    /// The DDA's interpolated CPU ms at the quad-tree's PSNR, from the best rounds (NaN
    /// when not bracketed).
    pub ms_dda_cpu_at_psnr: f64,
    /// `ms_dof_cpu / ms_dda_cpu_at_psnr`: quad-tree over DDA CPU time at equal PSNR.
    pub cpu_ratio: f64,
    /// The same ratio per round (that round's times only).
    pub cpu_ratio_rounds: Vec<f64>,
    pub cpu_ratio_spread: Spread,
    /// Whether the DDA's / the quad-tree's PSNR rises strictly with `N_pri` over the sweep.
    pub dda_psnr_rising: bool,
    pub quadtree_psnr_rising: bool,
}

/// A built structure and the entries tracing it.
struct Built {
    key: (Method, bool, u32),
    structure: Result<DofStructure, String>,
    build_ms: f64,
}

/// Measures `entries` (module docs) against `truth`, reference by reference; `progress(msg)`
/// reports stages. Returns the rows in the order of `entries` and each row's image.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    bench: &DofBench,
    entries: &[DofEntry],
    opts: &MethodOptions,
    truth: &Image<Rgb>,
    progress: &dyn Fn(&str),
) -> Result<Vec<(DofRow, Option<DofImage>)>, SynthError> {
    let mut out: Vec<Option<(DofRow, Option<DofImage>)>> =
        (0..entries.len()).map(|_| None).collect();
    let mut layer_counts: Vec<usize> = entries.iter().map(|e| e.layers).collect();
    layer_counts.sort_unstable();
    layer_counts.dedup();
    for n in layer_counts {
        progress(&format!("reference, {n} layer(s)"));
        let mut r = capture_dof_reference(scene, bvh, &bench.setup, n, bench.shading, bench.seed)?;
        r.fit_cube(bench.cube_near)?;
        let (w, h) = (
            bench.setup.lens.pinhole.width,
            bench.setup.lens.pinhole.height,
        );
        let mask = discontinuity_mask(&r, bench.setup.guard, w, h, bench.setup.guard);
        let idx: Vec<usize> = (0..entries.len())
            .filter(|&i| entries[i].layers == n)
            .collect();
        let mut built: Vec<Built> = Vec::new();
        for &i in &idx {
            let e = &entries[i];
            if built.iter().any(|b| b.key == e.structure_key()) {
                continue;
            }
            progress(&format!("build {}, {n} layer(s)", e.label()));
            let mo = MethodOptions {
                inpaint: e.inpaint,
                dda_max_steps: e.dda_max_steps,
                cube_near: bench.cube_near,
                ..*opts
            };
            let t = std::time::Instant::now();
            let structure = DofStructure::build(e.method, &r, &mo).map_err(|e| e.to_string());
            built.push(Built {
                key: e.structure_key(),
                structure,
                build_ms: t.elapsed().as_secs_f64() * 1e3,
            });
        }
        let mut images: Vec<Result<DofImage, String>> =
            idx.iter().map(|_| Err("not run".to_string())).collect();
        let mut rounds_cpu: Vec<Vec<f64>> = idx.iter().map(|_| Vec::new()).collect();
        // Grouped by lens rays, inpainting last (stable otherwise), reversed every
        // second round (module docs).
        let mut order: Vec<usize> = (0..idx.len()).collect();
        order.sort_by_key(|&k| {
            let e = &entries[idx[k]];
            (e.n_pri, e.n_sec, e.inpaint)
        });
        for round in 0..bench.repeats.max(1) {
            if round > 0 {
                order.reverse();
            }
            for &k in &order {
                let i = idx[k];
                let e = &entries[i];
                let b = built
                    .iter()
                    .find(|b| b.key == e.structure_key())
                    .expect("built");
                let Ok(st) = &b.structure else {
                    images[k] = Err(b.structure.as_ref().err().cloned().unwrap_or_default());
                    continue;
                };
                if round > 0 && images[k].is_err() {
                    continue;
                }
                progress(&format!(
                    "round {}/{}: {} {}/{}, {n} layer(s)",
                    round + 1,
                    bench.repeats.max(1),
                    e.label(),
                    e.n_pri,
                    e.n_sec
                ));
                let o = DofOptions {
                    n_pri: e.n_pri,
                    n_sec: e.n_sec,
                    sigma: bench.sigma,
                    seed: bench.seed,
                    warp: opts.warp,
                    secondary_resample: bench.secondary_resample,
                };
                let img = render_dof(st, &r, &bench.setup.lens, &o);
                if let Ok(img) = &img {
                    rounds_cpu[k].push(img.cpu_ms);
                }
                match (img, &mut images[k]) {
                    (Ok(img), Ok(best)) => {
                        best.ms = best.ms.min(img.ms);
                        best.cpu_ms = best.cpu_ms.min(img.cpu_ms);
                    }
                    (Ok(img), slot) => *slot = Ok(img),
                    (Err(err), slot) => *slot = Err(err.to_string()),
                }
            }
        }
        for (k, &i) in idx.iter().enumerate() {
            let e = &entries[i];
            let b = built
                .iter()
                .find(|b| b.key == e.structure_key())
                .expect("built");
            let img = std::mem::replace(&mut images[k], Err(String::new()));
            let mut done = finish(scene, bench, e, &r, b.build_ms, img, truth, &mask);
            done.0.ms_dof_cpu_rounds = std::mem::take(&mut rounds_cpu[k]);
            out[i] = Some(done);
        }
    }
    Ok(out
        .into_iter()
        .map(|o| o.expect("every entry measured"))
        .collect())
}

#[allow(clippy::too_many_arguments)]
fn finish(
    scene: &Scene,
    bench: &DofBench,
    e: &DofEntry,
    r: &Reference,
    build_ms: f64,
    img: Result<DofImage, String>,
    truth: &Image<Rgb>,
    mask: &[bool],
) -> (DofRow, Option<DofImage>) {
    let lens = &bench.setup.lens;
    let mut row = DofRow {
        method: e.label(),
        layers: e.layers,
        scene: scene.name.clone(),
        width: lens.pinhole.width,
        height: lens.pinhole.height,
        inpaint: e.inpaint,
        n_pri: e.n_pri,
        n_sec: e.n_sec,
        sigma: bench.sigma,
        aperture_m: lens.aperture_radius,
        focus_m: lens.focus_distance,
        guard_px: bench.setup.guard,
        cube_near: cube_near_name(bench.cube_near),
        dda_max_steps: (e.method == Method::Dda).then_some(e.dda_max_steps),
        repeats: bench.repeats.max(1),
        ms_capture: r.times.capture_ms,
        ms_shade: r.times.shade_ms,
        ms_build: build_ms,
        ms_ref: r.times.capture_ms + r.times.shade_ms + build_ms,
        psnr: f64::NAN,
        ssim: f64::NAN,
        psnr_edges: f64::NAN,
        psnr_self: f64::NAN,
        psnr_equal_time: f64::NAN,
        secondary_weight: f64::NAN,
        ..DofRow::default()
    };
    let img = match img {
        Ok(i) => i,
        Err(err) => {
            row.error = Some(err);
            return (row, None);
        }
    };
    let rays = img.stats.rays.max(1) as f64;
    row.ms_dof = img.ms;
    row.ms_dof_cpu = img.cpu_ms;
    row.fps = 1e3 / (row.ms_ref + row.ms_dof);
    row.mrays_per_s = img.mrays_per_s();
    row.mrays_per_cpu_s = img.mrays_per_cpu_s();
    row.nodes_per_ray = if img.stats.nodes_visited > 0 {
        img.stats.nodes_visited
    } else {
        img.stats.steps
    } as f64
        / rays;
    row.tests_per_ray = (img.stats.box_tests + img.stats.plane_tests) as f64 / rays;
    let lr = img.lens_rays.max(1) as f64;
    row.pct_layer2 = img.pct_deep();
    row.pct_miss = 100.0 * img.misses as f64 / lr;
    row.pct_occlusion = 100.0 * img.occlusions as f64 / lr;
    row.pct_truncated = 100.0 * img.stats.truncated as f64 / rays;
    if e.n_sec > 1 {
        row.secondary_weight = img.secondary.mean_weight();
    }
    match score(&img.image, truth) {
        Ok(s) => (row.psnr, row.ssim) = (s.psnr, s.ssim),
        Err(err) => row.error = Some(err.to_string()),
    }
    if let Ok(p) = masked_psnr(&img.image, truth, mask) {
        row.psnr_edges = p;
    }
    (row, Some(img))
}

/// The entries of Table 4 for `layers`: the quad-tree at `N_pri / N_sec` in {4/1, 8/1, 4/4,
/// 8/4}, the DDA (at `dda_steps`, one entry per value) at {4/1, 8/1}, and with one layer the
/// quad-tree's inpainting mode at every quad-tree configuration.
pub fn table4_entries(layers: &[usize], dda_steps: &[u32], methods: &[Method]) -> Vec<DofEntry> {
    let mut v = Vec::new();
    let qt = [(4, 1), (8, 1), (4, 4), (8, 4)];
    for &n in layers {
        let modes: &[bool] = if n == 1 { &[false, true] } else { &[false] };
        for &m in methods {
            match m {
                Method::QuadTree => {
                    for &inpaint in modes {
                        for (p, s) in qt {
                            v.push(DofEntry {
                                method: m,
                                layers: n,
                                inpaint,
                                dda_max_steps: 0,
                                n_pri: p,
                                n_sec: s,
                            });
                        }
                    }
                }
                m => {
                    for &st in dda_steps {
                        for p in [4, 8] {
                            v.push(DofEntry {
                                method: m,
                                layers: n,
                                inpaint: false,
                                dda_max_steps: st,
                                n_pri: p,
                                n_sec: 1,
                            });
                        }
                    }
                }
            }
        }
    }
    v
}

/// Fig. 8's entries for the quad-tree with `layers` layers: plain lens sampling at
/// `N_pri` in {4, 8, 16, 32} and the secondary configurations of the figure (4/8, 8/4) and
/// of Table 4 (4/4).
pub fn fig8_entries(layers: usize, inpaint: bool) -> Vec<DofEntry> {
    [(4, 1), (8, 1), (16, 1), (32, 1), (4, 4), (4, 8), (8, 4)]
        .into_iter()
        .map(|(p, s)| DofEntry {
            method: Method::QuadTree,
            layers,
            inpaint,
            dda_max_steps: 0,
            n_pri: p,
            n_sec: s,
        })
        .collect()
}

/// Fills `psnr_self` (against `own`, the method's converged image) and `psnr_equal_time`
/// (module docs) of `rows`, matched to plain-sampling rows of the same method and layers.
pub fn equal_time(rows: &mut [(DofRow, Option<DofImage>)], own: Option<&Image<Rgb>>) {
    if let Some(own) = own {
        for (row, img) in rows.iter_mut() {
            if let Some(Ok(s)) = img.as_ref().map(|i| score(&i.image, own)) {
                row.psnr_self = s.psnr;
            }
        }
    }
    let plain: Vec<(String, usize, f64, f64)> = rows
        .iter()
        .filter(|(r, _)| r.n_sec == 1 && r.error.is_none())
        .map(|(r, _)| (r.method.clone(), r.layers, r.ms_dof_cpu, r.psnr))
        .collect();
    for (row, _) in rows
        .iter_mut()
        .filter(|(r, _)| r.n_sec > 1 && r.error.is_none())
    {
        let mut curve: Vec<(f64, f64)> = plain
            .iter()
            .filter(|p| p.0 == row.method && p.1 == row.layers)
            .map(|p| (p.2.ln(), p.3))
            .collect();
        curve.sort_by(|a, b| a.0.total_cmp(&b.0));
        row.psnr_equal_time = interpolate(&curve, row.ms_dof_cpu.ln());
    }
}

/// Linear interpolation of `(x, y)` points sorted by `x` at `x`; NaN outside their range.
fn interpolate(curve: &[(f64, f64)], x: f64) -> f64 {
    for w in curve.windows(2) {
        let ((x0, y0), (x1, y1)) = (w[0], w[1]);
        if x >= x0 && x <= x1 {
            return if x1 > x0 {
                y0 + (y1 - y0) * (x - x0) / (x1 - x0)
            } else {
                y0
            };
        }
    }
    f64::NAN
}

/// The converged BVH thin-lens image of `bench` (its `truth_spp`).
pub fn truth(scene: &Scene, bvh: &Bvh, bench: &DofBench) -> Result<Image<Rgb>, SynthError> {
    thin_lens_truth(
        scene,
        bvh,
        &bench.setup.lens,
        bench.truth_spp,
        bench.shading,
        bench.seed,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_in_range_only() {
        let c = [(0.0, 10.0), (1.0, 20.0), (3.0, 30.0)];
        assert_eq!(interpolate(&c, 0.5), 15.0);
        assert_eq!(interpolate(&c, 2.0), 25.0);
        assert!(interpolate(&c, 3.5).is_nan());
        assert!(interpolate(&[], 1.0).is_nan());
    }

    #[test]
    fn table4_has_the_papers_configurations() {
        let e = table4_entries(&[1, 2], &[25], &[Method::QuadTree, Method::Dda]);
        // 1 layer: 4 quad-tree + 4 inpaint + 2 DDA; 2 layers: 4 + 2.
        assert_eq!(e.len(), 16);
        assert!(e.iter().all(|e| e.method != Method::Dda || e.n_sec == 1));
        assert_eq!(e.iter().filter(|e| e.inpaint).count(), 4);
    }
}
