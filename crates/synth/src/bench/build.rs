//! `parallax bench quadtree-build`: the quad-tree build (Widmer et al. 2015, §3.2-3.3; the
//! paper's `T_ref` holds it) against the time to stream the layer it reads through memory
//! once, in one process, interleaved rounds, best round of each.
//!
//! **Stream** = one pass over the layer's view depths and normals (the inputs of the leaves,
//! 16 bytes per pixel), read as 32-bit words and folded with XOR over rayon chunks (the
//! build's thread pool): a memory-bound pass with one vector XOR per load, the floor any build
//! of the layer has. **Build** = [`QuadTreeTracer::build`] over 1 layer (one tree) and over 2 layers, whose
//! layer-0 tree is the cascade's pruning fixed point (`crate` quad-tree docs, "cascade";
//! layer 1's time includes its effective planes, which layer 0 needs). The ratios are
//! `build / stream` of the same layer.
//!
//! **Warm inputs**: every timed stream and every timed build is preceded by untimed streams
//! of the layers it reads, so both read them from the same (warm) caches. Timing the stream
//! straight after the previous round's builds measured it on cold caches at 2-4x its warm
//! time, while the build that followed it read warm data: a ratio flattered by a slow
//! denominator.
//!
//! Rows reuse `bench warp`'s field names (`method`, `layers`, `ms_*`).

use std::time::Instant;

use parallax_bvh::Bvh;
use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_core::image::GBuffer;
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;
use parallax_screen::QuadTreeTracer;
use rayon::prelude::*;
use serde::Serialize;

use crate::SynthError;
use crate::layers::capture_reference;
use crate::method::{MethodOptions, quadtree_options};
use parallax_render::score::Shading;

/// One tree of one build setting.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRow {
    pub method: String,
    /// Layers of the build (1, or 2 for the cascade).
    pub layers: usize,
    /// The tree's layer (0 = nearest).
    pub tree: usize,
    pub width: u32,
    pub height: u32,
    /// Best-round build milliseconds of this tree.
    pub ms_build: f64,
    /// Best-round milliseconds of streaming this layer's depth + normals once.
    pub ms_stream: f64,
    /// `ms_build / ms_stream` (best rounds, possibly of different rounds).
    pub ratio: f64,
    /// Every round's build ms of this tree, in round order.
    pub ms_build_rounds: Vec<f64>,
    /// Every round's stream ms of this layer, in round order.
    pub ms_stream_rounds: Vec<f64>,
    /// Per-round `build / stream` (the same round's two times): median, min, max.
    pub ratio_rounds: Spread,
    /// Per-round process-CPU `build / stream` of the same round: median, min, max (the
    /// 1-layer row only; NaN elsewhere, as the 2-layer build's CPU time is not split by
    /// layer).
    pub cpu_ratio_rounds: Spread,
    /// Per-round `build / the same round's 1-layer build`: median, min, max (1 for the
    /// 1-layer row; layer 0 of 2 is the fixed point's ratio).
    pub over_one_layer_rounds: Spread,
    /// The same in process CPU time (`QuadTreeTracer::build_cpu_ms` of both builds).
    pub cpu_over_one_layer_rounds: Spread,
    pub nodes: usize,
    pub plane_nodes: usize,
    pub threads: usize,
    /// Best-round ms of the tree's effective planes (top-down levels, one decode per node
    /// and row) and of their definition (a climb and a decode per pixel): layer 0 of the
    /// 2-layer build only (`NaN` elsewhere).
    pub ms_effective_planes: f64,
    pub ms_effective_planes_climb: f64,
}

pub use parallax_core::spread::Spread;

/// XOR of every bit of the layer's depths and normals (module docs, "Stream"): both arrays read
/// as plain 32-bit words (`bytemuck`), so the fold is a vector XOR per load and the pass runs
/// at the speed the memory (or the cache holding the layer) delivers.
pub fn stream_layer(g: &GBuffer) -> u32 {
    fn fold(words: &[u32]) -> u32 {
        words
            .par_chunks(STREAM_CHUNK_WORDS)
            .map(|c| c.iter().fold(0u32, |a, &x| a ^ x))
            .reduce(|| 0, |a, b| a ^ b)
    }
    let depth: &[u32] = bytemuck::cast_slice(&g.depth);
    let normal: &[u32] = bytemuck::cast_slice(&g.normal);
    fold(depth) ^ fold(normal)
}

/// Untimed passes over `layers` before a timed stream or build, so both start on the same
/// warm caches (module docs, "Warm inputs").
fn warm(layers: &[GBuffer]) {
    for _ in 0..WARM_PASSES {
        for g in layers {
            std::hint::black_box(stream_layer(g));
        }
    }
}

/// Untimed streams before each timed stream or build: with fewer, the timed stream stays well
/// above the time a stand-alone read of the same bytes takes on 2-thread hosts (measured in
/// `docs/notes/quadtree.md`).
const WARM_PASSES: usize = 6;

/// Words per rayon task of [`stream_layer`] (256 KiB: large enough that scheduling is noise,
/// small enough that both threads get many tasks).
const STREAM_CHUNK_WORDS: usize = 1 << 16;

/// Captures two layers of `camera`'s view and times the builds (module docs); `progress`
/// gets the stage names.
pub fn run(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    opts: &MethodOptions,
    repeats: u32,
    progress: &dyn Fn(&str),
) -> Result<Vec<BuildRow>, SynthError> {
    progress("capture");
    let reference = capture_reference(scene, bvh, camera, 2, Shading::Fixed, 0)?;
    let mut reference = reference;
    reference.fit_cube(opts.cube_near)?;
    let layers = &reference.layers;
    let q = quadtree_options(opts);
    let q = parallax_screen::QuadTreeOptions {
        gamma_dist: q.gamma_dist * crate::method::gamma_dist_scale(&reference.cube, layers)?,
        ..q
    };
    // Per round: the streams of layers 0 and 1, the 1-layer build, the 2-layer build's
    // layer 0 and layer 1 (module docs, "One round").
    let rounds = repeats.max(1) as usize;
    let mut stream: [Vec<f64>; 2] = [Vec::with_capacity(rounds), Vec::with_capacity(rounds)];
    let mut build1 = Vec::with_capacity(rounds);
    let (mut cpu_stream, mut cpu_build1) = (Vec::with_capacity(rounds), Vec::with_capacity(rounds));
    let mut build2: [Vec<f64>; 2] = [Vec::with_capacity(rounds), Vec::with_capacity(rounds)];
    let mut cpu_tree1 = Vec::with_capacity(rounds);
    let mut cpu_tree2: [Vec<f64>; 2] = [Vec::with_capacity(rounds), Vec::with_capacity(rounds)];
    let mut trees: (Option<QuadTreeTracer>, Option<QuadTreeTracer>) = (None, None);
    for round in 0..rounds {
        progress(&format!("round {}", round + 1));
        for (k, s) in stream.iter_mut().enumerate() {
            warm(&layers[k..=k]);
            let c = process_cpu_ns();
            let t = Instant::now();
            std::hint::black_box(stream_layer(&layers[k]));
            s.push(t.elapsed().as_secs_f64() * 1e3);
            if k == 0 {
                cpu_stream.push(ms_between(c, process_cpu_ns()));
            }
        }
        warm(&layers[..1]);
        let c = process_cpu_ns();
        let one = QuadTreeTracer::build(&reference.cube, &layers[..1], &q)?;
        cpu_build1.push(ms_between(c, process_cpu_ns()));
        build1.push(one.build_ms()[0]);
        cpu_tree1.push(one.build_cpu_ms()[0]);
        warm(&layers[..2]);
        let two = QuadTreeTracer::build(&reference.cube, &layers[..2], &q)?;
        for (b, m) in build2.iter_mut().zip(two.build_ms()) {
            b.push(m);
        }
        for (b, m) in cpu_tree2.iter_mut().zip(two.build_cpu_ms()) {
            b.push(m);
        }
        trees = (Some(one), Some(two));
    }
    let best = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
    let (one, two) = (trees.0.expect("a round"), trees.1.expect("a round"));
    // The fixed point's inner step, fast path against its definition (interleaved).
    progress("effective planes");
    let (mut fast, mut climb) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        std::hint::black_box(two.trees[0].effective_planes());
        fast = fast.min(t.elapsed().as_secs_f64() * 1e3);
        let t = Instant::now();
        std::hint::black_box(two.trees[0].effective_planes_by_climbing());
        climb = climb.min(t.elapsed().as_secs_f64() * 1e3);
    }
    let row = |layers: usize, tree: usize, ms: &[f64], cpu: &[f64], t: &QuadTreeTracer| BuildRow {
        method: "quadtree".into(),
        layers,
        tree,
        width: camera.width,
        height: camera.height,
        ms_build: best(ms),
        ms_stream: best(&stream[tree]),
        ratio: best(ms) / best(&stream[tree]),
        ms_build_rounds: ms.to_vec(),
        ms_stream_rounds: stream[tree].clone(),
        ratio_rounds: Spread::of(&per_round(ms, &stream[tree])),
        cpu_ratio_rounds: Spread::of(&if layers == 1 {
            per_round(&cpu_build1, &cpu_stream)
        } else {
            Vec::new()
        }),
        over_one_layer_rounds: Spread::of(&per_round(ms, &build1)),
        cpu_over_one_layer_rounds: Spread::of(&per_round(cpu, &cpu_tree1)),
        nodes: t.trees[tree].node_count(),
        plane_nodes: t.trees[tree].plane_node_count(),
        threads: rayon::current_num_threads(),
        ms_effective_planes: if (layers, tree) == (2, 0) {
            fast
        } else {
            f64::NAN
        },
        ms_effective_planes_climb: if (layers, tree) == (2, 0) {
            climb
        } else {
            f64::NAN
        },
    };
    Ok(vec![
        row(1, 0, &build1, &cpu_tree1, &one),
        row(2, 0, &build2[0], &cpu_tree2[0], &two),
        row(2, 1, &build2[1], &cpu_tree2[1], &two),
    ])
}

/// `a[r] / b[r]` per round.
fn per_round(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x / y).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_is_median_and_range() {
        let s = Spread::of(&[3.0, 1.0, 2.0]);
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        let s = Spread::of(&[4.0, f64::NAN, 1.0, 2.0, 3.0]);
        assert_eq!((s.median, s.min, s.max), (2.5, 1.0, 4.0));
        assert!(Spread::of(&[f64::NAN]).median.is_nan());
        assert_eq!(per_round(&[6.0, 8.0], &[2.0, 4.0]), vec![3.0, 2.0]);
    }
}
