//! `QuadTreeTracer::trace_batch` answers every ray exactly as `ScreenTracer::trace` does (same
//! results bit for bit, same work counters), for batch lengths around the phase size, on
//! synthetic height fields and captures, 1 and 2 layers, cascade and inpainting.

mod quadtree_util;

use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;
use parallax_screen::quadtree::LayerMode;
use parallax_screen::{
    CubeNear, QuadTreeOptions, QuadTreeTracer, ScreenTracer, TraceResult, TraceStats, UnitCube,
};
use quadtree_util::{camera, height_field, rays};

fn check(qt: &QuadTreeTracer, rays: &[parallax_core::Ray], what: &str) {
    let mut s1 = TraceStats::default();
    let one: Vec<TraceResult> = rays.iter().map(|r| qt.trace(r, &mut s1)).collect();
    for len in [1, 3, 8, 13, rays.len()] {
        let mut s2 = TraceStats::default();
        let mut out = vec![TraceResult::Miss; rays.len()];
        for (r, o) in rays.chunks(len).zip(out.chunks_mut(len)) {
            qt.trace_batch(r, o, &mut s2);
        }
        assert_eq!(s1, s2, "{what}, batches of {len}: counters");
        for (i, (a, b)) in one.iter().zip(&out).enumerate() {
            // `==` on the floats, and their bits (a NaN or a signed zero would slip past `==`).
            assert_eq!(a, b, "{what}, batches of {len}, ray {i}");
            if let (TraceResult::Hit { t: ta, .. }, TraceResult::Hit { t: tb, .. }) = (a, b) {
                assert_eq!(ta.to_bits(), tb.to_bits(), "{what}, ray {i}");
            }
        }
    }
    assert!(s1.hits > s1.rays / 4, "{what}: {s1:?}");
}

fn tracers(cam: &Pinhole, layers: &[parallax_core::GBuffer]) -> Vec<(String, QuadTreeTracer)> {
    let mut out = Vec::new();
    for near in [CubeNear::Fitted, CubeNear::Camera(0.1)] {
        let depths: Vec<&[f32]> = layers.iter().map(|g| &g.depth[..]).collect();
        let cube = UnitCube::fit(cam, depths, near).unwrap();
        for n in 1..=layers.len() {
            for mode in [LayerMode::Cascade, LayerMode::Inpaint] {
                let opts = QuadTreeOptions {
                    mode,
                    ..QuadTreeOptions::default()
                };
                let qt = QuadTreeTracer::build(&cube, &layers[..n], &opts).unwrap();
                out.push((format!("{near:?}, {n} layer(s), {mode:?}"), qt));
            }
        }
    }
    out
}

#[test]
fn batches_equal_single_rays_on_height_fields() {
    for (w, h, seed) in [(64, 48, 1), (97, 33, 2)] {
        let cam = camera(w, h);
        let layers = vec![
            height_field(&cam, seed, 0.05),
            height_field(&cam, seed + 9, 0.3),
        ];
        let rays = rays(&cam, &layers[0], 600, 0.3, seed);
        for (what, qt) in tracers(&cam, &layers) {
            check(&qt, &rays, &format!("{w}x{h}, {what}"));
        }
    }
}

#[test]
fn batches_equal_single_rays_on_captures() {
    for (name, w, h) in [
        ("atrium", 160, 90),
        ("cornell", 96, 72),
        ("foliage", 120, 80),
    ] {
        let scene = Scene::load(name).unwrap();
        let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
        let cap = capture_layers(
            &scene,
            &View::from_pinhole(&cam).unwrap(),
            &RasterOptions::layers(2),
        )
        .unwrap();
        let layers = cap.layers.layers.clone();
        let rays = rays(&cam, &layers[0], 800, 0.1, 5);
        for (what, qt) in tracers(&cam, &layers) {
            check(&qt, &rays, &format!("{name}, {what}"));
        }
    }
}
