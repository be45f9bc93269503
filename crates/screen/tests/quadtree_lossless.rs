//! Lossless settings: the quad-tree (Widmer et al. 2015) returns exactly the hits of brute
//! force over the same (quantised) per-pixel planes, on random height fields (proptest,
//! non-power-of-two sizes, empty pixels) and on captured layers.

mod quadtree_util;

use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{QuadTreeOptions, QuadTreeTracer};
use proptest::prelude::*;
use quadtree_util::*;

const REL: f32 = 1e-4;

fn check_height_field(w: u32, h: u32, seed: u64, empty: f32, max_levels: u32) {
    let cam = camera(w, h);
    let g = height_field(&cam, seed, empty);
    let cube = cube(&cam, std::slice::from_ref(&g));
    let opts = exact(QuadTreeOptions {
        max_levels,
        ..QuadTreeOptions::lossless()
    });
    let qt = QuadTreeTracer::build(&cube, std::slice::from_ref(&g), &opts).unwrap();
    assert_eq!(
        qt.trees[0].plane_node_count(),
        qt.trees[0]
            .effective_planes()
            .normal
            .iter()
            .filter(|n| **n != glam::Vec3::ZERO)
            .count()
    );
    let bf = twin(&qt);
    let rays = rays(&cam, &g, 300, 0.3, seed ^ 0x55);
    let (t, first, _) = run(&qt, &bf, &rays, REL);
    assert_eq!(t.differ, 0, "{w}x{h} seed {seed}: {t:?} first: {first:?}");
    assert!(t.edge * 50 <= t.total(), "{t:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn lossless_equals_brute_force_on_height_fields(
        w in 9u32..90, h in 7u32..60, seed in any::<u64>(), empty in 0.0f32..0.2, lv in 1u32..10,
    ) {
        check_height_field(w, h, seed, empty, lv);
    }
}

/// A case proptest found: a ray almost parallel to a pixel row boundary, whose
/// occlusion-volume entry `t` the two tracers round differently (see `Verdict::or_same_entry`).
#[test]
fn lossless_equals_brute_force_regression_68x41() {
    check_height_field(68, 41, 174269643855716870, 0.19304094, 1);
}

#[test]
fn lossless_equals_brute_force_fixed_sizes() {
    for (w, h) in [(64, 48), (1, 1), (2, 17), (33, 1), (128, 64)] {
        check_height_field(w, h, 42, 0.05, 9);
    }
}

fn captured(name: &str, w: u32, h: u32, layers: usize) -> (Pinhole, Vec<parallax_core::GBuffer>) {
    let scene = Scene::load(name).unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam).unwrap(),
        &RasterOptions::layers(layers),
    )
    .unwrap();
    (cam, cap.layers.layers.clone())
}

#[test]
fn lossless_equals_brute_force_on_captures() {
    for (name, w, h) in [("cornell", 96, 72), ("atrium", 160, 90)] {
        let (cam, layers) = captured(name, w, h, 1);
        let cube = cube(&cam, &layers);
        let qt =
            QuadTreeTracer::build(&cube, &layers, &exact(QuadTreeOptions::lossless())).unwrap();
        let bf = twin(&qt);
        let rays = rays(&cam, &layers[0], 1500, 0.2, 9);
        let (t, first, stats) = run(&qt, &bf, &rays, REL);
        eprintln!(
            "{name}: {t:?}, nodes/ray {:.1}",
            stats.nodes_visited as f64 / stats.rays as f64
        );
        assert_eq!(t.differ, 0, "{name}: {t:?} first: {first:?}");
        assert!(t.edge * 100 <= t.total(), "{t:?}");
        assert!(t.hits > t.total() / 3, "{t:?}");
    }
}

/// A case proptest found: a ray crosses the plane of pixel (36, 18) 9.3e-7 px
/// (f64) before leaving its footprint through `x = 37`; brute force's f32 bound `37/88`
/// ends the footprint just before the crossing (no hit there, a later hit at (37, 19)), the
/// traversal's exit lies past it (a hit). See `Verdict::or_boundary_crossing`.
#[test]
fn lossless_equals_brute_force_regression_88x26() {
    check_height_field(88, 26, 10959061550737753857, 0.14931929, 1);
}

/// A case proptest found: a ray leaves the cube through the image's right edge
/// and crosses the plane of pixel (71, 14) 6.4e-8 px before it (f64); brute force's `f` at
/// the segment end is exactly 0 (a hit), the traversal's footprint exit is one ulp earlier
/// (a miss). See `Verdict::or_boundary_crossing`.
#[test]
fn lossless_equals_brute_force_regression_72x17() {
    check_height_field(72, 17, 18425509305348070330, 0.050340116, 1);
}
