//! `parallax bench rays`: BVH build time and closest-hit throughput of parallax's BVH against
//! Embree 3 (when built with the `embree` feature, [`parallax_embree`]) on the *same* rays, in
//! the same process.
//!
//! Ray sets ("modes"), generated up front (only tracing is timed):
//! - `primary`: one ray per pixel centre, pixels in 8x8 tiles (tile after tile in scanline
//!   order), each tile as four 4x4 tiles (top left, top right, bottom left, bottom right; scanline
//!   order within), so 16 consecutive rays are a 4x4 tile (the packets of the 16-ray methods; 8
//!   consecutive rays: half a tile, 4x2 pixels) and 64 an 8x8 tile (`bvh packet64`).
//! - `msaa16`: 16 subsample rays per pixel (the Sobol' (0,2) offsets of HVVR's sample sets,
//!   Hunt et al. 2018 §5.1), a pixel's 16 subsamples consecutive: a packet is one pixel
//!   (MSAA-style packets). Traced in bands of rows so memory stays bounded.
//! - `random`: a cosine-distributed bounce ray from each primary hit (incoherent), packets of
//!   16 consecutive rays (neighbouring pixels' bounces).
//!
//! Builds: parallax's BVH three times and each Embree quality twice, every build's memory
//! freed before the next (so later builds reuse the heap the first one grew, on both sides);
//! the fastest counts.
//!
//! Methods ([`Method`]): parallax's single rays and 16-ray packets, Embree's `rtcIntersect1`,
//! `rtcIntersect8`, `rtcIntersect16` and `rtcIntersect1M` streams. Timing: rounds of all
//! methods in turn (round robin, so a burst of load from other processes hurts one run of each
//! method, not all runs of one), best round per method and band, on all rayon threads, over
//! chunks of [`CHUNK`] rays; each row also has its ratio to the best Embree method per round
//! (median and range: the rounds share the host's state, so its drift cancels in each
//! ratio). Every method's answers are compared with parallax's single-ray answers (same
//! primitive, or both miss): parallax's packets must agree exactly, Embree on
//! almost every ray (its test is not watertight, so at a shared edge it may report the
//! neighbour).
//!
//! | option ([`RaysOptions`]) | type | default | meaning |
//! |---|---|---|---|
//! | `repeats` | u32 | 3 | timed rounds per band (the best counts) |
//! | `msaa` | bool | true | include the `msaa16` mode |
//! | `embree_quality` | [`Quality`] | `High` | Embree's build quality for the traced scene |
//! | `methods` | `Vec<Method>` | all | the traced methods (`bvh single`, the reference, always runs) |
//! | `bvh` | [`BuildOptions`] | default | parallax's BVH build (the default: spatial splits, SBVH; `spatial_splits: false` the object-split tree) |

use std::time::Instant;

use glam::Vec2;
use parallax_bvh::{BuildOptions, Bvh, BvhError, PACKET_SIZE, PACKET64_SIZE};
use parallax_core::Ray;
use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_core::math::Frame;
use parallax_core::sampling::lowdisc::sobol_2d;
use parallax_core::sampling::{Rng, warp};
use parallax_core::spread::Spread;
use parallax_embree::{EmbreeHit, EmbreeScene, Options, Quality};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use rayon::prelude::*;
use serde::Serialize;

/// Rays per parallel work item (a multiple of every packet width).
pub const CHUNK: usize = 1024;
/// Subsamples per pixel of the `msaa16` mode.
pub const MSAA_SPP: u32 = 16;
/// Rows per band of the `msaa16` mode (bounds its memory to ~45 rows x width x 16 rays).
const MSAA_BAND_ROWS: u32 = 45;

/// Bench options (table in the module docs).
#[derive(Clone, Debug)]
pub struct RaysOptions {
    pub repeats: u32,
    pub msaa: bool,
    pub embree_quality: Quality,
    /// Empty: every method.
    pub methods: Vec<Method>,
    pub bvh: BuildOptions,
}

impl Default for RaysOptions {
    fn default() -> Self {
        Self {
            repeats: 3,
            msaa: true,
            embree_quality: Quality::High,
            methods: Vec::new(),
            bvh: BuildOptions::default(),
        }
    }
}

/// One row of the rays benchmark: a build, or one method on one ray set.
#[derive(Clone, Debug, Serialize)]
pub struct RaysRow {
    /// `build`, `primary`, `msaa16` or `random` (module docs).
    pub mode: String,
    /// e.g. `bvh single`, `bvh packet16`, `embree rtcIntersect16`, `embree build high`.
    pub method: String,
    pub scene: String,
    pub rays: u64,
    /// Build of the structure the method traces (ms, wall).
    pub build_ms: f64,
    /// Best round, summed over bands (ms, wall).
    pub trace_ms: f64,
    /// CPU time of the process in that round (ms, all threads).
    pub trace_cpu_ms: f64,
    pub mrays_per_s: f64,
    /// Throughput over the best Embree method of the same mode (None without Embree).
    pub vs_embree_best: Option<f64>,
    /// The same per round (that round's times of this method and of that Embree method, summed
    /// over the mode's bands): median, min, max. On a host whose speed drifts between rounds
    /// the drift cancels in each round's ratio and shows in the range.
    pub vs_embree_best_rounds: Option<Spread>,
    /// Every round's trace ms (summed over bands; `trace_ms` sums the bands' best rounds).
    pub ms_trace_rounds: Vec<f64>,
    /// Fraction of rays whose closest primitive (or miss) equals parallax's single-ray answer.
    pub same_prim: f64,
    /// Fraction of rays with the same primitive, or a hit at the same distance (within 1e-5
    /// relative: another triangle at the same point, e.g. a shared edge or a coplanar copy).
    pub same_t: f64,
    /// Fraction of rays that hit geometry.
    pub hit_rate: f64,
    pub threads: usize,
}

/// The outcome of [`run`]: the rows, and why Embree is missing when it is.
#[derive(Clone, Debug)]
pub struct RaysReport {
    pub rows: Vec<RaysRow>,
    /// `None` when Embree ran; else the reason (e.g. [`parallax_embree::ENABLE_HINT`]).
    pub embree_missing: Option<String>,
}

/// A method's answer for one ray: (primitive, t), `None` for a miss.
type Answer = Option<(u32, f32)>;

/// The traced methods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    BvhSingle,
    BvhPacket16,
    /// 64-ray packets (8x8 pixels as four 16-ray groups, `Bvh::closest_hit_packet64`).
    BvhPacket64,
    /// The 4-wide tree's single rays and packets (the predecessors, for reference).
    BvhSingle4,
    BvhPacket4,
    EmbreeIntersect1,
    EmbreeIntersect8,
    EmbreeIntersect16,
    EmbreeStream,
}

impl Method {
    pub const ALL: [Method; 9] = [
        Method::BvhSingle,
        Method::BvhPacket16,
        Method::BvhPacket64,
        Method::BvhSingle4,
        Method::BvhPacket4,
        Method::EmbreeIntersect1,
        Method::EmbreeIntersect8,
        Method::EmbreeIntersect16,
        Method::EmbreeStream,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Method::BvhSingle => "bvh single",
            Method::BvhPacket16 => "bvh packet16",
            Method::BvhPacket64 => "bvh packet64",
            Method::BvhSingle4 => "bvh4 single",
            Method::BvhPacket4 => "bvh4 packet16",
            Method::EmbreeIntersect1 => "embree rtcIntersect1",
            Method::EmbreeIntersect8 => "embree rtcIntersect8",
            Method::EmbreeIntersect16 => "embree rtcIntersect16",
            Method::EmbreeStream => "embree rtcIntersect1M",
        }
    }

    /// The short name of `--methods` (`single`, `packet16`, `packet64`, `single4`, `packet4`,
    /// `embree1`, `embree8`, `embree16`, `embree1m`).
    pub fn short_name(self) -> &'static str {
        match self {
            Method::BvhSingle => "single",
            Method::BvhPacket16 => "packet16",
            Method::BvhPacket64 => "packet64",
            Method::BvhSingle4 => "single4",
            Method::BvhPacket4 => "packet4",
            Method::EmbreeIntersect1 => "embree1",
            Method::EmbreeIntersect8 => "embree8",
            Method::EmbreeIntersect16 => "embree16",
            Method::EmbreeStream => "embree1m",
        }
    }

    /// The method of a [`Self::short_name`] or [`Self::name`].
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.short_name() == s || m.name() == s)
    }

    pub fn is_embree(self) -> bool {
        !matches!(
            self,
            Method::BvhSingle
                | Method::BvhPacket16
                | Method::BvhPacket64
                | Method::BvhSingle4
                | Method::BvhPacket4
        )
    }

    /// Traces `rays` (one chunk) into `out`; `coherent` picks Embree's stream context flag.
    fn trace(
        self,
        bvh: &Bvh,
        emb: Option<&EmbreeScene>,
        rays: &[Ray],
        coherent: bool,
        out: &mut [Answer],
    ) {
        let ph = |h: Option<parallax_bvh::Hit>| h.map(|h| (h.prim, h.t));
        match self {
            Method::BvhSingle => {
                for (r, o) in rays.iter().zip(out) {
                    *o = ph(bvh.closest_hit(r));
                }
            }
            Method::BvhSingle4 => {
                for (r, o) in rays.iter().zip(out) {
                    *o = ph(bvh.closest_hit4(r));
                }
            }
            Method::BvhPacket64 => {
                let mut tmp = [None; PACKET64_SIZE];
                for (p, o) in rays
                    .chunks(PACKET64_SIZE)
                    .zip(out.chunks_mut(PACKET64_SIZE))
                {
                    bvh.closest_hit_packet64(p, &mut tmp);
                    for (o, h) in o.iter_mut().zip(tmp) {
                        *o = ph(h);
                    }
                }
            }
            Method::BvhPacket16 | Method::BvhPacket4 => {
                let mut tmp = [None; PACKET_SIZE];
                for (p, o) in rays.chunks(PACKET_SIZE).zip(out.chunks_mut(PACKET_SIZE)) {
                    if self == Method::BvhPacket16 {
                        bvh.closest_hit_packet(p, &mut tmp);
                    } else {
                        bvh.closest_hit_packet4(p, &mut tmp);
                    }
                    for (o, h) in o.iter_mut().zip(tmp) {
                        *o = ph(h);
                    }
                }
            }
            _ => {
                let emb = emb.expect("Embree method without an Embree scene");
                let mut tmp = [None::<EmbreeHit>; CHUNK];
                let tmp = &mut tmp[..rays.len()];
                match self {
                    Method::EmbreeIntersect1 => emb.closest_hits(rays, tmp),
                    Method::EmbreeIntersect8 => emb.closest_hit_packets(rays, 8, tmp),
                    Method::EmbreeIntersect16 => emb.closest_hit_packets(rays, 16, tmp),
                    _ => emb.closest_hit_stream(rays, coherent, tmp),
                }
                for (o, h) in out.iter_mut().zip(tmp.iter()) {
                    *o = h.map(|h| (h.prim, h.t));
                }
            }
        }
    }
}

/// Primary rays through pixel centres in 8x8 tiles of four 4x4 tiles (module docs); pixels
/// without a ray (outside a fisheye's circle, past the image's edge) are skipped, which
/// shortens their tile's packet.
pub fn primary_tiled(camera: &Camera) -> Vec<Ray> {
    let (w, h) = (camera.width(), camera.height());
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(8))
        .flat_map(|ty| (0..w.div_ceil(8)).map(move |tx| (8 * tx, 8 * ty)))
        .flat_map(|(x, y)| [(x, y), (x + 4, y), (x, y + 4), (x + 4, y + 4)])
        .filter(|&(x, y)| x < w && y < h)
        .collect();
    tiles
        .par_iter()
        .flat_map_iter(|&(x0, y0)| {
            (y0..(y0 + 4).min(h)).flat_map(move |y| {
                (x0..(x0 + 4).min(w)).filter_map(move |x| {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    camera
                        .generate_ray(film, Vec2::splat(0.5), 1)
                        .map(|r| r.ray)
                })
            })
        })
        .collect()
}

/// The `msaa16` rays of rows `y0..y1`: each pixel's 16 subsample rays, consecutive.
pub fn msaa_band(camera: &Camera, y0: u32, y1: u32) -> Vec<Ray> {
    let offsets: Vec<Vec2> = (0..MSAA_SPP)
        .map(|k| sobol_2d(k, 0x9e37_79b9) - Vec2::splat(0.5))
        .collect();
    let w = camera.width();
    (y0..y1)
        .into_par_iter()
        .flat_map_iter(|y| {
            let offsets = &offsets;
            (0..w).flat_map(move |x| {
                offsets.iter().filter_map(move |o| {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + *o;
                    camera
                        .generate_ray(film, Vec2::splat(0.5), 1)
                        .map(|r| r.ray)
                })
            })
        })
        .collect()
}

/// Cosine-distributed bounce rays from the closest hits of `primary` (misses give no ray),
/// seeded per ray index.
pub fn bounce_rays(bvh: &Bvh, scene: &Scene, primary: &[Ray]) -> Vec<Ray> {
    primary
        .par_iter()
        .enumerate()
        .filter_map(|(i, r)| {
            let hit = bvh.closest_hit(r)?;
            let p = r.at(hit.t);
            let mut n = scene.mesh.geometric_normal(hit.prim as usize);
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let mut rng = Rng::for_pixel(7, i as u32, 0, 0);
            let dir = Frame::from_normal(n).to_world(warp::cosine_hemisphere(rng.next_vec2()));
            let scale = 1e-4 * p.abs().max_element().max(1.0);
            Some(Ray::new(p + n * scale, dir))
        })
        .collect()
}

/// Per-method results accumulated over the bands of one mode.
#[derive(Clone, Default)]
struct Acc {
    ms: f64,
    /// Wall ms per round, summed over bands.
    rounds: Vec<f64>,
    cpu_ms: f64,
    same: u64,
    same_t: u64,
    hits: u64,
}

/// Times every method on one band of rays (interleaved rounds, best round) and counts its
/// agreement with parallax's single rays.
fn time_band(
    methods: &[Method],
    bvh: &Bvh,
    emb: Option<&EmbreeScene>,
    rays: &[Ray],
    coherent: bool,
    repeats: u32,
    acc: &mut [Acc],
) {
    let mut outs: Vec<Vec<Answer>> = methods.iter().map(|_| vec![None; rays.len()]).collect();
    let mut best = vec![(f64::INFINITY, f64::INFINITY); methods.len()];
    let rounds = repeats.max(1) as usize;
    for a in acc.iter_mut() {
        a.rounds.resize(rounds, 0.0);
    }
    for round in 0..rounds {
        let it = methods
            .iter()
            .zip(&mut outs)
            .zip(&mut best)
            .zip(acc.iter_mut());
        for (((m, out), b), a) in it {
            let (c0, t0) = (process_cpu_ns(), Instant::now());
            rays.par_chunks(CHUNK)
                .zip(out.par_chunks_mut(CHUNK))
                .for_each(|(r, o)| m.trace(bvh, emb, r, coherent, o));
            let wall = t0.elapsed().as_secs_f64() * 1e3;
            let cpu = ms_between(c0, process_cpu_ns());
            a.rounds[round] += wall;
            if wall < b.0 {
                *b = (wall, cpu);
            }
        }
    }
    // Method 0 is parallax's single rays, the reference.
    let reference = &outs[0];
    for ((out, b), a) in outs.iter().zip(&best).zip(acc) {
        a.ms += b.0;
        a.cpu_ms += b.1;
        a.same += out
            .par_iter()
            .zip(reference)
            .filter(|(x, y)| x.map(|h| h.0) == y.map(|h| h.0))
            .count() as u64;
        a.same_t += out
            .par_iter()
            .zip(reference)
            .filter(|(x, y)| match (x, y) {
                (None, None) => true,
                (Some(a), Some(b)) => {
                    a.0 == b.0 || (a.1 - b.1).abs() <= 1e-5 * a.1.abs().max(b.1.abs())
                }
                _ => false,
            })
            .count() as u64;
        a.hits += out.par_iter().filter(|x| x.is_some()).count() as u64;
    }
}

/// Builds the BVH (and Embree's scenes when available), then measures every mode.
pub fn run(scene: &Scene, camera: &Camera, opts: &RaysOptions) -> Result<RaysReport, BvhError> {
    let threads = rayon::current_num_threads();
    let mut rows = Vec::new();
    let row = |mode: &str, method: &str, build_ms: f64| RaysRow {
        mode: mode.into(),
        method: method.into(),
        scene: scene.name.clone(),
        rays: 0,
        build_ms,
        trace_ms: 0.0,
        trace_cpu_ms: 0.0,
        mrays_per_s: 0.0,
        vs_embree_best: None,
        vs_embree_best_rounds: None,
        ms_trace_rounds: Vec::new(),
        same_prim: 1.0,
        same_t: 1.0,
        hit_rate: 0.0,
        threads,
    };
    // Builds: the fastest of a few counts (the first Embree device also starts its threads).
    // Each build's memory is freed before the next, ours as Embree's (an Embree scene not kept
    // is dropped at once), so later builds run on the heap the first one grew, for both; ours
    // three times (the last one kept), as Embree's quality levels build six scenes before the
    // high-quality one is timed.
    let mut bvh_ms = f64::INFINITY;
    let mut bvh = None;
    for _ in 0..3 {
        drop(bvh.take());
        let t = Instant::now();
        bvh = Some(Bvh::try_build_with(&scene.mesh, &opts.bvh)?);
        bvh_ms = bvh_ms.min(t.elapsed().as_secs_f64() * 1e3);
    }
    let bvh = bvh.expect("built");
    rows.push(row("build", "bvh", bvh_ms));
    let mut embree = None;
    let mut embree_missing = None;
    let mut embree_ms = 0.0;
    for q in [Quality::Low, Quality::Medium, Quality::High] {
        let mut best = f64::INFINITY;
        for _ in 0..2 {
            let t = Instant::now();
            match EmbreeScene::new(
                &scene.mesh,
                Options {
                    quality: q,
                    robust: false,
                },
            ) {
                Ok(s) => {
                    best = best.min(t.elapsed().as_secs_f64() * 1e3);
                    if q == opts.embree_quality {
                        embree = Some(s);
                    }
                }
                Err(e) => {
                    embree_missing = Some(e.to_string());
                    break;
                }
            }
        }
        if embree_missing.is_some() {
            break;
        }
        if q == opts.embree_quality {
            embree_ms = best;
        }
        rows.push(row("build", &format!("embree {}", q.name()), best));
    }
    let methods: Vec<Method> = Method::ALL
        .into_iter()
        .filter(|m| embree.is_some() || !m.is_embree())
        .filter(|m| *m == Method::BvhSingle || opts.methods.is_empty() || opts.methods.contains(m))
        .collect();

    let primary = primary_tiled(camera);
    let random = bounce_rays(&bvh, scene, &primary);
    let mut modes: Vec<(&str, bool)> = vec![("primary", true)];
    if opts.msaa {
        modes.push(("msaa16", true));
    }
    modes.push(("random", false));
    for (mode, coherent) in modes {
        let mut acc = vec![Acc::default(); methods.len()];
        let mut n = 0u64;
        let band = |rays: &[Ray], acc: &mut [Acc]| {
            time_band(
                &methods,
                &bvh,
                embree.as_ref(),
                rays,
                coherent,
                opts.repeats,
                acc,
            );
            rays.len() as u64
        };
        match mode {
            "primary" => n += band(&primary, &mut acc),
            "random" => n += band(&random, &mut acc),
            _ => {
                for y0 in (0..camera.height()).step_by(MSAA_BAND_ROWS as usize) {
                    let y1 = (y0 + MSAA_BAND_ROWS).min(camera.height());
                    n += band(&msaa_band(camera, y0, y1), &mut acc);
                }
            }
        }
        let mrays = |a: &Acc| n as f64 / (a.ms * 1e3);
        // The Embree method of the highest throughput (best rounds) and its per-round times.
        let best_embree = methods
            .iter()
            .zip(&acc)
            .filter(|(m, _)| m.is_embree())
            .max_by(|(_, a), (_, b)| mrays(a).total_cmp(&mrays(b)))
            .map(|(_, a)| (mrays(a), &a.rounds));
        for (m, a) in methods.iter().zip(&acc) {
            let mut r = row(
                mode,
                m.name(),
                if m.is_embree() { embree_ms } else { bvh_ms },
            );
            r.rays = n;
            r.trace_ms = a.ms;
            r.trace_cpu_ms = a.cpu_ms;
            r.mrays_per_s = mrays(a);
            r.vs_embree_best = best_embree.map(|(b, _)| mrays(a) / b);
            r.vs_embree_best_rounds = best_embree.map(|(_, e)| {
                let ratios: Vec<f64> = e.iter().zip(&a.rounds).map(|(e, o)| e / o).collect();
                Spread::of(&ratios)
            });
            r.ms_trace_rounds = a.rounds.clone();
            r.same_prim = a.same as f64 / n.max(1) as f64;
            r.same_t = a.same_t as f64 / n.max(1) as f64;
            r.hit_rate = a.hits as f64 / n.max(1) as f64;
            rows.push(r);
        }
    }
    Ok(RaysReport {
        rows,
        embree_missing,
    })
}
