//! HVVR's Table 3 (Hunt et al. 2018, §6.2): procedural (just-in-time) subsample rays against the
//! naive variant that stores every subsample ray in a high-resolution ray buffer
//! ([`crate::RayBuffer`], `cast/stored.rs`), on the `normal` scheme's both eyes: the same
//! caster, the same rays (the stored rays are [`crate::SampleSet::subsample_ray`]'s,
//! bit-identical to the generated ones), the same buffer (checked every run: `same_image`).
//!
//! Timing: rounds, in each the procedural cast of both eyes, then the stored one (interleaved),
//! best round each; the buffers are made outside the timed region. `ms_intersect` is the
//! caster's sample-test stage (thread CPU time summed over threads, `CastStats::sample_test`),
//! `ms_trace` the whole cast (wall). `ray_mb` is what the caster reads to make its rays: the
//! sample set (samples and offset tables) or the stored rays (24 bytes each).
//!
//! | option | type | default (CLI) | meaning |
//! |---|---|---|---|
//! | `width`, `height` | u32 | 2160, 1200 | both eyes' film |
//! | `spp` | u32 | 16 (`--table3-spp`) | subsamples per pixel (the paper: 16) |
//! | `repeats` | u32 | `--repeats` | timed rounds (the best counts) |

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_scene::{CameraDesc, Scene};
use serde::Serialize;

use super::scheme_sets;
use crate::frame::VrError;
use crate::{CastOptions, Hierarchy, RayBuffer, Sample, VisibilityBuffer, cast_opts, cast_stored};

/// One ray mode of the table.
#[derive(Clone, Debug, Serialize)]
pub struct Table3Row {
    pub scene: String,
    /// `procedural` or `stored`.
    pub method: String,
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    pub rays: u64,
    /// Best round: the sample-test stage (CPU ms summed over threads).
    pub ms_intersect: f64,
    /// Best round: the whole cast of both eyes (wall ms).
    pub ms_trace: f64,
    pub mrays_per_s: f64,
    /// What the caster reads to make its rays (MB).
    pub ray_mb: f64,
    /// The buffer equals the procedural one (always true for `procedural`).
    pub same_image: bool,
    pub threads: usize,
}

/// Runs the table (module docs).
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    head: &CameraDesc,
    width: u32,
    height: u32,
    spp: u32,
    repeats: u32,
) -> Result<Vec<Table3Row>, VrError> {
    let sets = scheme_sets("normal", head, width, height, spp)?;
    let hier = [Hierarchy::build(&sets[0])?, Hierarchy::build(&sets[1])?];
    let stored = [RayBuffer::new(&sets[0]), RayBuffer::new(&sets[1])];
    let mut proc_out = [
        VisibilityBuffer::new(&sets[0]),
        VisibilityBuffer::new(&sets[1]),
    ];
    let mut stored_out = proc_out.clone();
    let opts = CastOptions::default();
    let rays: u64 = sets.iter().map(|s| s.ray_count() as u64).sum();
    // (best wall ms, best intersect ms) per mode.
    let mut best = [(f64::INFINITY, f64::INFINITY); 2];
    let mut same = true;
    for _ in 0..repeats.max(1) {
        for (mode, b) in best.iter_mut().enumerate() {
            let t0 = Instant::now();
            let mut intersect = 0.0;
            for e in 0..2 {
                let st = if mode == 0 {
                    cast_opts(bvh, &sets[e], &hier[e], &mut proc_out[e], opts)
                } else {
                    cast_stored(
                        bvh,
                        &sets[e],
                        &stored[e],
                        &hier[e],
                        &mut stored_out[e],
                        opts,
                    )
                };
                intersect += st.sample_test.as_secs_f64() * 1e3;
            }
            b.0 = b.0.min(t0.elapsed().as_secs_f64() * 1e3);
            b.1 = b.1.min(intersect);
        }
        same &= proc_out == stored_out;
    }
    let set_bytes: usize = sets
        .iter()
        .map(|s| {
            s.samples.len() * std::mem::size_of::<Sample>()
                + (s.offsets.len() + s.lens.len()) * std::mem::size_of::<glam::Vec2>()
        })
        .sum();
    let stored_bytes: usize = stored.iter().map(RayBuffer::bytes).sum();
    let row = |method: &str, (ms, isect): (f64, f64), bytes: usize, same_image: bool| Table3Row {
        scene: scene.name.clone(),
        method: method.into(),
        width,
        height,
        samples_per_pixel: spp,
        rays,
        ms_intersect: isect,
        ms_trace: ms,
        mrays_per_s: rays as f64 / (ms * 1e3),
        ray_mb: bytes as f64 / 1e6,
        same_image,
        threads: rayon::current_num_threads(),
    };
    Ok(vec![
        row("procedural", best[0], set_bytes, true),
        row("stored", best[1], stored_bytes, same),
    ])
}

/// The rows as a Markdown table.
pub fn markdown(rows: &[Table3Row]) -> String {
    let mut s = String::from(
        "| spp | ray mode | rays | intersect ms (CPU) | cast ms (wall) | Mrays/s | ray memory MB | same image |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.2} | {:.1} | {} |\n",
            r.samples_per_pixel,
            r.method,
            r.rays,
            r.ms_intersect,
            r.ms_trace,
            r.mrays_per_s,
            r.ray_mb,
            if r.same_image { "yes" } else { "NO" },
        );
    }
    s
}
