//! HVVR's Table 6 (Hunt et al. 2018, §6): the beam caster against general ray tracers on the
//! *same* subsample rays — Embree 3 (`rtcIntersect1`, `rtcIntersect16`; with the `embree`
//! feature, [`parallax_embree`]), our BVH's 16-ray packets (`Bvh::closest_hit_packet`) and its
//! single rays (`Bvh::closest_hit`).
//!
//! The rays are the `normal` scheme's (pinhole stereo eyes, [`SampleSet::grid`]):
//! [`SampleSet::subsample_ray`] of every (sample, subsample), the rays the beam caster
//! generates just in time, bit for bit. For the ray tracers they are generated up front in
//! bands of [`BAND_ROWS`] pixel rows per eye (generation is not timed: the paper times
//! "traversal and intersect time only" for the ray tracers), ordered by 4x4-pixel tiles
//! (tile after tile, row-major pixels within a tile, a pixel's subsamples innermost), so a
//! packet of 16 consecutive rays is one pixel's 16 subsamples at 16 spp (MSAA-style
//! packets), half a pixel at 32, two pixels at 8, one 4x4-pixel tile at 1 spp. The beam
//! caster is timed over the whole frame of a moving head: both eyes, each with its hierarchy
//! (built once, outside the timed region) moved from the previous frame's pose, turned by
//! a degree, to this one ([`crate::Hierarchy::repose`], HVVR §5.1's bounds moved per
//! frame), then the cast; visibility only (the paper's HVVR figure includes shading).
//!
//! Timing: rounds; in each round the beam caster casts the frame, then every band is
//! generated and traced by each ray tracer in turn (round robin, all rayon threads, chunks of
//! [`CHUNK`] rays); per method the best round's total counts, and each round's speed-up of the
//! beam caster over each ray tracer (the same round's two times) is reported as a median and
//! range ([`Spread`]): a host whose speed drifts between rounds moves both times of a round
//! alike. Agreement: per ray tracer, the
//! fraction of rays whose primitive (or miss) equals the beam caster's (`same_prim`), or
//! whose hit lies at the same distance within 1e-5 relative (`same_t`: a shared edge or a
//! coplanar copy).
//!
//! | option ([`Table6Options`]) | type | default (CLI) | meaning |
//! |---|---|---|---|
//! | `width`, `height` | u32 | 2160, 1200 | both eyes' film (each eye `width / 2`) |
//! | `spp` | `Vec<u32>` | `--msaa` | subsamples per pixel (1, 4, 8, 16, 32) |
//! | `repeats` | u32 | 3 | timed rounds (the best counts; the per-round speed-ups use all) |

use std::time::Instant;

use parallax_bvh::{Bvh, PACKET_SIZE};
use parallax_core::spread::Spread;
use parallax_core::{NO_ID, Ray};
use parallax_embree::{EmbreeHit, EmbreeScene, Options};
use parallax_scene::camera::CameraModel;
use parallax_scene::{CameraDesc, Scene};
use rayon::prelude::*;
use serde::Serialize;

use super::scheme_sets;
use crate::frame::{Visibility, VrError, prepare, visibility_into};
use crate::{SampleSet, VisibilityBuffer};

/// Pixel rows per band of generated rays (a multiple of the 4-pixel tile).
pub const BAND_ROWS: u32 = 16;
/// Rays per parallel work item (a multiple of every packet width and of every spp).
pub const CHUNK: usize = 1024;

/// What to measure (module docs).
#[derive(Clone, Debug)]
pub struct Table6Options {
    pub width: u32,
    pub height: u32,
    pub spp: Vec<u32>,
    pub repeats: u32,
}

/// One method at one spp.
#[derive(Clone, Debug, Serialize)]
pub struct Table6Row {
    pub scene: String,
    /// `beam`, `embree rtcIntersect1`, `embree rtcIntersect16`, `bvh packet16`, `bvh single`.
    pub method: String,
    /// What one packet of the method is (module docs).
    pub packet: String,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub rays: u64,
    /// Best round (ms, wall): the whole cast for the beam caster, tracing only for the others.
    pub ms_trace: f64,
    pub mrays_per_s: f64,
    /// The beam caster's throughput over this method's (best rounds of each).
    pub beam_speedup: f64,
    /// The same per round (the round's beam cast against the round's trace): median, min, max.
    pub beam_speedup_rounds: Spread,
    /// Every round's ms (the field `ms_trace` is the least of them), in round order.
    pub ms_trace_rounds: Vec<f64>,
    /// Fraction of rays with the beam caster's primitive (or both miss).
    pub same_prim: f64,
    /// Fraction with the same primitive or a hit at the same `t` (1e-5 relative).
    pub same_t: f64,
    pub threads: usize,
}

/// The rows and, when Embree is not built in, how to get its rows.
#[derive(Clone, Debug, Serialize)]
pub struct Table6Report {
    pub rows: Vec<Table6Row>,
    pub embree_missing: Option<String>,
}

/// A ray tracer of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Tracer {
    Embree1,
    Embree16,
    BvhPacket16,
    BvhSingle,
}

impl Tracer {
    fn name(self) -> &'static str {
        match self {
            Tracer::Embree1 => "embree rtcIntersect1",
            Tracer::Embree16 => "embree rtcIntersect16",
            Tracer::BvhPacket16 => "bvh packet16",
            Tracer::BvhSingle => "bvh single",
        }
    }

    fn packets(self) -> bool {
        matches!(self, Tracer::Embree16 | Tracer::BvhPacket16)
    }

    /// Traces one chunk of rays into `out`.
    fn trace(self, bvh: &Bvh, emb: Option<&EmbreeScene>, rays: &[Ray], out: &mut [Answer]) {
        let ph = |h: Option<parallax_bvh::Hit>| h.map(|h| (h.prim, h.t));
        match self {
            Tracer::BvhSingle => {
                for (r, o) in rays.iter().zip(out) {
                    *o = ph(bvh.closest_hit(r));
                }
            }
            Tracer::BvhPacket16 => {
                let mut tmp = [None; PACKET_SIZE];
                for (p, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
                    bvh.closest_hit_packet(p, &mut tmp);
                    for (o, h) in o.iter_mut().zip(tmp) {
                        *o = ph(h);
                    }
                }
            }
            Tracer::Embree1 | Tracer::Embree16 => {
                let emb = emb.expect("an Embree tracer without an Embree scene");
                let mut tmp = [None::<EmbreeHit>; CHUNK];
                let tmp = &mut tmp[..rays.len()];
                if self == Tracer::Embree1 {
                    emb.closest_hits(rays, tmp);
                } else {
                    emb.closest_hit_packets(rays, 16, tmp);
                }
                for (o, h) in out.iter_mut().zip(tmp.iter()) {
                    *o = h.map(|h| (h.prim, h.t));
                }
            }
        }
    }
}

/// A ray's answer: (mesh triangle, t), `None` for a miss.
type Answer = Option<(u32, f32)>;

/// What a 16-ray packet covers at `spp` (module docs).
fn packet_name(spp: u32) -> String {
    match spp {
        1 => "4x4 pixels".into(),
        16 => "1 pixel".into(),
        s if s > 16 => format!("1/{} pixel", s / 16),
        s => format!("{} pixels", 16 / s),
    }
}

/// Rays of pixel rows `y0..y1` of `set` in 4x4-tile order (module docs) and their indices in
/// the visibility buffer.
fn band_rays(set: &SampleSet, y0: u32, y1: u32) -> (Vec<Ray>, Vec<u32>) {
    let w = set.camera.width();
    let spp = set.spp;
    let tiles: Vec<(u32, u32)> = (y0..y1)
        .step_by(4)
        .flat_map(|ty| (0..w.div_ceil(4)).map(move |tx| (4 * tx, ty)))
        .collect();
    tiles
        .par_iter()
        .flat_map_iter(|&(x0, ty)| {
            (ty..(ty + 4).min(y1)).flat_map(move |y| {
                (x0..(x0 + 4).min(w)).flat_map(move |x| {
                    let i = (y * w + x) as usize;
                    (0..spp as usize).filter_map(move |k| {
                        let r = set.subsample_ray(i, k)?;
                        Some((r, (i * spp as usize + k) as u32))
                    })
                })
            })
        })
        .unzip()
}

/// Per-method totals of one round.
#[derive(Clone, Copy, Default)]
struct Tally {
    same: u64,
    same_t: u64,
}

/// Runs the table (module docs): for every spp, the beam caster and the ray tracers on both
/// eyes' subsample rays of the `normal` scheme.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    head: &CameraDesc,
    opts: &Table6Options,
) -> Result<Table6Report, VrError> {
    let threads = rayon::current_num_threads();
    let (emb, embree_missing) = match EmbreeScene::new(&scene.mesh, Options::default()) {
        Ok(s) => (Some(s), None),
        Err(e) => (None, Some(e.to_string())),
    };
    let tracers: Vec<Tracer> = [
        Tracer::Embree1,
        Tracer::Embree16,
        Tracer::BvhPacket16,
        Tracer::BvhSingle,
    ]
    .into_iter()
    .filter(|t| emb.is_some() || !matches!(t, Tracer::Embree1 | Tracer::Embree16))
    .collect();
    let mut rows = Vec::new();
    for &spp in &opts.spp {
        let sets = scheme_sets("normal", head, opts.width, opts.height, spp)?;
        for s in &sets {
            let (w, h) = (s.camera.width(), s.camera.height());
            if s.samples.len() != (w * h) as usize {
                return Err(VrError::Invalid(
                    "table 6 needs one sample per pixel (a pinhole grid)".into(),
                ));
            }
        }
        let mut hier = [
            prepare(Visibility::Beam, &sets[0])?,
            prepare(Visibility::Beam, &sets[1])?,
        ];
        // The previous frame's head (module docs): turned by a degree.
        let before = scheme_sets("normal", &head.turned(1.0), opts.width, opts.height, spp)?;
        let mut out = [
            VisibilityBuffer::new(&sets[0]),
            VisibilityBuffer::new(&sets[1]),
        ];
        let rays: u64 = sets.iter().map(|s| s.ray_count() as u64).sum();
        let mut beam_rounds = Vec::new();
        let mut rounds: Vec<Vec<f64>> = vec![Vec::new(); tracers.len()];
        let mut tally = vec![Tally::default(); tracers.len()];
        let mut traced = 0u64;
        let mut answers: Vec<Vec<Answer>> = vec![Vec::new(); tracers.len()];
        for round in 0..opts.repeats.max(1) {
            for (h, b) in hier.iter_mut().zip(&before) {
                if let Some(h) = h {
                    h.repose(b)?;
                }
            }
            let t0 = Instant::now();
            for e in 0..2 {
                if let Some(h) = &mut hier[e] {
                    h.repose(&sets[e])?;
                }
                visibility_into(
                    Visibility::Beam,
                    bvh,
                    &sets[e],
                    hier[e].as_ref(),
                    &mut out[e],
                )?;
            }
            beam_rounds.push(t0.elapsed().as_secs_f64() * 1e3);
            let mut sum = vec![0.0f64; tracers.len()];
            for (e, set) in sets.iter().enumerate() {
                let h = set.camera.height();
                for y0 in (0..h).step_by(BAND_ROWS as usize) {
                    let (band, idx) = band_rays(set, y0, (y0 + BAND_ROWS).min(h));
                    if round == 0 {
                        traced += band.len() as u64;
                    }
                    for (ti, &t) in tracers.iter().enumerate() {
                        let a = &mut answers[ti];
                        a.clear();
                        a.resize(band.len(), None);
                        let c = Instant::now();
                        band.par_chunks(CHUNK)
                            .zip(a.par_chunks_mut(CHUNK))
                            .for_each(|(r, o)| t.trace(bvh, emb.as_ref(), r, o));
                        sum[ti] += c.elapsed().as_secs_f64() * 1e3;
                        if round == 0 {
                            let (s, st) = agreement(a, &idx, &out[e]);
                            tally[ti].same += s;
                            tally[ti].same_t += st;
                        }
                    }
                }
            }
            for (r, s) in rounds.iter_mut().zip(sum) {
                r.push(s);
            }
        }
        let best_beam = Spread::of(&beam_rounds).min;
        let beam_mrays = rays as f64 / (best_beam * 1e3);
        // Per round: (this method's ms / its rays) over (the beam's ms / its rays).
        let speedups = |ms: &[f64], n: u64| -> Vec<f64> {
            ms.iter()
                .zip(&beam_rounds)
                .map(|(m, b)| (m / n.max(1) as f64) / (b / rays.max(1) as f64))
                .collect()
        };
        let row = |method: &str, packet: String, ms_rounds: &[f64], n: u64, t: Tally| {
            let ms = Spread::of(ms_rounds).min;
            Table6Row {
                scene: scene.name.clone(),
                method: method.into(),
                packet,
                width: opts.width,
                height: opts.height,
                samples_per_pixel: spp,
                rays: n,
                ms_trace: ms,
                mrays_per_s: n as f64 / (ms * 1e3),
                beam_speedup: beam_mrays / (n as f64 / (ms * 1e3)),
                beam_speedup_rounds: Spread::of(&speedups(ms_rounds, n)),
                ms_trace_rounds: ms_rounds.to_vec(),
                same_prim: t.same as f64 / n.max(1) as f64,
                same_t: t.same_t as f64 / n.max(1) as f64,
                threads,
            }
        };
        let full = Tally {
            same: rays,
            same_t: rays,
        };
        rows.push(row("beam", "tile".into(), &beam_rounds, rays, full));
        for (ti, &t) in tracers.iter().enumerate() {
            let packet = if t.packets() {
                packet_name(spp)
            } else {
                "single ray".into()
            };
            rows.push(row(t.name(), packet, &rounds[ti], traced, tally[ti]));
        }
    }
    Ok(Table6Report {
        rows,
        embree_missing,
    })
}

/// (same primitive, same primitive or `t`) counts of `a` against the beam caster's buffer.
fn agreement(a: &[Answer], idx: &[u32], beam: &VisibilityBuffer) -> (u64, u64) {
    a.par_iter()
        .zip(idx)
        .map(|(x, &i)| {
            let (p, t) = (beam.prim[i as usize], beam.t[i as usize]);
            let b = (p != NO_ID).then_some((p, t));
            let same = x.map(|h| h.0) == b.map(|h| h.0);
            let same_t = same
                || matches!((x, b), (Some(x), Some(b))
                    if (x.1 - b.1).abs() <= 1e-5 * x.1.abs().max(b.1.abs()));
            (same as u64, same_t as u64)
        })
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// The rows as a Markdown table (and the hint when Embree is missing).
pub fn markdown(r: &Table6Report) -> String {
    let mut s = String::from(
        "| spp | method | packet | rays | ms | Mrays/s | beam speed-up | per round: median [min, max] | same prim | same t |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for x in &r.rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.1} | {:.2} | {:.2}x | {:.2}x [{:.2}, {:.2}] | {:.4}% | {:.4}% |\n",
            x.samples_per_pixel,
            x.method,
            x.packet,
            x.rays,
            x.ms_trace,
            x.mrays_per_s,
            x.beam_speedup,
            x.beam_speedup_rounds.median,
            x.beam_speedup_rounds.min,
            x.beam_speedup_rounds.max,
            100.0 * x.same_prim,
            100.0 * x.same_t,
        );
    }
    if let Some(m) = &r.embree_missing {
        s += &format!("\n{m}\n");
    }
    s
}
