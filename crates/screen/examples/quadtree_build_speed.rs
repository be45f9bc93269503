//! Quad-tree build speed (Widmer et al. 2015, §3) on atrium at 1600x900, 2 captured layers:
//! per round, in one process and interleaved, the stream of the layer (its depths and
//! normals once, XOR of their bits), the 1-layer build and the 2-layer build (layer 0 is the
//! cascade's pruning fixed point); best round of each, as wall time and as process CPU time
//! (all threads; less sensitive to other jobs on the machine than wall time). The fixed
//! point's CPU time is the 2-layer build's minus that of layer 1 alone (its 1-layer build
//! and its effective planes, which layer 0's cascade needs), against the 1-layer build of
//! layer 0.
//!
//! `cd crates/screen && cargo run --release --example quadtree_build_speed -- [ROUNDS]`
//! (default 7). Under `perf record` this profiles the build (the capture is a small share).

use std::time::Instant;

use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_core::image::GBuffer;
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{CubeNear, QuadTreeOptions, QuadTreeTracer, UnitCube};
use rayon::prelude::*;

fn stream(g: &GBuffer) -> u32 {
    let w = g.width() as usize;
    let d: u32 = g
        .depth
        .par_chunks(w * 8)
        .map(|c| c.iter().fold(0u32, |a, x| a ^ x.to_bits()))
        .reduce(|| 0, |a, b| a ^ b);
    let n: u32 = g
        .normal
        .par_chunks(w * 8)
        .map(|c| {
            c.iter().fold(0u32, |a, v| {
                a ^ v.x.to_bits() ^ v.y.to_bits() ^ v.z.to_bits()
            })
        })
        .reduce(|| 0, |a, b| a ^ b);
    d ^ n
}

/// (wall ms, CPU ms) of `f`.
fn time<T>(f: impl FnOnce() -> T) -> (f64, f64) {
    let (t, c) = (Instant::now(), process_cpu_ns());
    std::hint::black_box(f());
    (
        t.elapsed().as_secs_f64() * 1e3,
        ms_between(c, process_cpu_ns()),
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: u32 = std::env::args().nth(1).map_or(Ok(7), |a| a.parse())?;
    let (w, h) = (1600, 900);
    let scene = Scene::load("atrium")?;
    let cam = Pinhole::new(&scene.camera(None)?, w, h)?;
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam)?,
        &RasterOptions::layers(2),
    )?;
    let layers = cap.layers.layers.clone();
    let cube = UnitCube::fit(&cam, layers.iter().map(|g| &g.depth[..]), CubeNear::Fitted)?;
    let opts = QuadTreeOptions::default();
    let mut best = [(f64::INFINITY, f64::INFINITY); 4];
    for _ in 0..rounds {
        let r = [
            time(|| stream(&layers[0])),
            time(|| QuadTreeTracer::build(&cube, &layers[..1], &opts).unwrap()),
            time(|| QuadTreeTracer::build(&cube, &layers[..2], &opts).unwrap()),
            time(|| {
                let t = QuadTreeTracer::build(&cube, &layers[1..2], &opts).unwrap();
                t.trees[0].effective_planes()
            }),
        ];
        for (b, r) in best.iter_mut().zip(r) {
            *b = (b.0.min(r.0), b.1.min(r.1));
        }
    }
    let [s, one, two, deep] = best;
    println!(
        "atrium {w}x{h}, {} threads, best of {rounds}: stream {:.2} ms (CPU {:.2}); 1 layer {:.2} ms ({:.1}x, CPU {:.2}); 2 layers {:.2} ms (CPU {:.2}); layer 1 + its effective planes CPU {:.2}; fixed point CPU {:.2} = {:.2}x the 1-layer build's",
        rayon::current_num_threads(),
        s.0,
        s.1,
        one.0,
        one.0 / s.0,
        one.1,
        two.0,
        two.1,
        deep.1,
        two.1 - deep.1,
        (two.1 - deep.1) / one.1
    );
    Ok(())
}
