//! Quad-tree build speed (Widmer et al. 2015, §3) on atrium at 1600x900, 2 captured layers:
//! per round, in one process and interleaved, the 1-layer build and the 2-layer build (layer 0
//! is the cascade's pruning fixed point), each also by [`QuadTreeTracer::build_reference`]
//! (the scalar definitions, the whole tree re-pruned per fixed-point iteration); best round of each, as wall time and as process CPU time
//! (all threads; less sensitive to other jobs on the machine than wall time). The fixed
//! point's CPU time is the 2-layer build's minus that of layer 1 alone (its 1-layer build
//! and its effective planes, which layer 0's cascade needs), against the 1-layer build of
//! layer 0. (The stream of the layer, the floor the build is measured against, is `parallax
//! bench quadtree-build`'s.)
//!
//! `--profile LAYERS`: instead, only [`QuadTreeTracer::build`] of `LAYERS` (1 or 2) layers,
//! `ROUNDS` times (for `perf record` and `valgrind --tool=callgrind`: no reference build, no
//! other layer count in the profile); `LAYERS` = `deep`: the 1-layer build of layer 1 and its
//! effective planes (the share of the 2-layer build that is not layer 0's).
//!
//! `--check`: instead, asserts that [`QuadTreeTracer::build`] equals
//! [`QuadTreeTracer::build_reference`] (the definitions) tree for tree, bit for bit, for 1
//! and 2 layers (the real-scene counterpart of `tests/quadtree_build.rs`).
//!
//! `cd crates/screen && cargo run --release --example quadtree_build_speed -- [ROUNDS]
//! [--check] [--sponza]` (default 7 rounds; `--sponza`: Sponza from
//! `../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb`, eye (-9, 3.5, 0), target
//! (8, 5, 0), 60°, instead of atrium). Under `perf record` this profiles the build (the
//! capture is a small share).

use std::time::Instant;

use glam::Vec3;
use parallax_core::cpu_time::{ms_between, process_cpu_ns};
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{CameraDesc, Scene, camera::Pinhole};
use parallax_screen::{CubeNear, QuadTreeOptions, QuadTreeTracer, UnitCube};

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
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |f: &str| args.iter().any(|a| a == f);
    let rounds: u32 = args
        .iter()
        .take_while(|a| *a != "--profile")
        .find(|a| !a.starts_with("--"))
        .map_or(Ok(7), |a| a.parse())?;
    let (w, h) = (1600, 900);
    let (scene, desc) = if flag("--sponza") {
        let scene = Scene::load("../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb")?;
        let desc = CameraDesc::new(
            Vec3::new(-9.0, 3.5, 0.0),
            Vec3::new(8.0, 5.0, 0.0),
            Vec3::Y,
            60.0,
        );
        (scene, desc)
    } else {
        let scene = Scene::load("atrium")?;
        let desc = scene.camera(None)?;
        (scene, desc)
    };
    let name = if flag("--sponza") { "sponza" } else { "atrium" };
    let cam = Pinhole::new(&desc, w, h)?;
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam)?,
        &RasterOptions::layers(2),
    )?;
    let layers = cap.layers.layers.clone();
    let cube = UnitCube::fit(&cam, layers.iter().map(|g| &g.depth[..]), CubeNear::Fitted)?;
    let opts = QuadTreeOptions::default();
    if flag("--check") {
        for n in 1..=2 {
            let fast = QuadTreeTracer::build(&cube, &layers[..n], &opts)?;
            let slow = QuadTreeTracer::build_reference(&cube, &layers[..n], &opts)?;
            for (k, (a, b)) in fast.trees.iter().zip(&slow.trees).enumerate() {
                assert!(a == b, "{name}: {n} layers, tree {k} differs");
                let (pa, pb) = (a.effective_planes(), b.effective_planes());
                assert!(
                    pa.offset
                        .iter()
                        .zip(&pb.offset)
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                );
            }
            println!(
                "{name} {w}x{h}, {n} layer(s): fast build == reference build ({} unsafe pixels in layer 0)",
                fast.unsafe_pixels()[0]
            );
        }
        return Ok(());
    }
    if let Some(i) = args.iter().position(|a| a == "--profile") {
        let what = args.get(i + 1).map_or("1", |a| a.as_str());
        for _ in 0..rounds {
            let (wall, cpu) = if what == "deep" {
                time(|| {
                    let t = QuadTreeTracer::build(&cube, &layers[1..2], &opts).unwrap();
                    t.trees[0].effective_planes()
                })
            } else {
                let n: usize = what.parse()?;
                time(|| QuadTreeTracer::build(&cube, &layers[..n], &opts).unwrap())
            };
            println!("{name} {what}: {wall:.2} ms (CPU {cpu:.2})");
        }
        return Ok(());
    }
    let mut best = [(f64::INFINITY, f64::INFINITY); 5];
    for _ in 0..rounds {
        let r = [
            time(|| QuadTreeTracer::build_reference(&cube, &layers[..1], &opts).unwrap()),
            time(|| QuadTreeTracer::build_reference(&cube, &layers[..2], &opts).unwrap()),
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
    let [ref1, ref2, one, two, deep] = best;
    println!(
        "reference build (scalar definitions, full fixed point): 1 layer {:.2} ms (CPU {:.2}), 2 layers {:.2} ms (CPU {:.2}); fast / reference CPU: 1 layer {:.2}, 2 layers {:.2}",
        ref1.0,
        ref1.1,
        ref2.0,
        ref2.1,
        one.1 / ref1.1,
        two.1 / ref2.1
    );
    println!(
        "{name} {w}x{h}, {} threads, best of {rounds}: 1 layer {:.2} ms (CPU {:.2}); 2 layers {:.2} ms (CPU {:.2}); layer 1 + its effective planes CPU {:.2}; fixed point CPU {:.2} = {:.2}x the 1-layer build's",
        rayon::current_num_threads(),
        one.0,
        one.1,
        two.0,
        two.1,
        deep.1,
        two.1 - deep.1,
        (two.1 - deep.1) / one.1
    );
    Ok(())
}
