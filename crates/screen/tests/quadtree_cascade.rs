//! Multi-layer cascade (Widmer et al. 2015, §4.1): tracing layer `k + 1` only for rays that
//! entered layer `k`'s trigger region gives exactly brute force over all layers; inpaint mode
//! stops at the first (dilated) occlusion-volume entry.

mod quadtree_util;

use parallax_core::{GBuffer, Ray};
use parallax_raster::{RasterOptions, View, capture_layers};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{
    BruteForcePlanes, LayerMode, QuadTreeOptions, QuadTreeTracer, ScreenTracer, TraceResult,
    TraceStats,
};
use proptest::prelude::*;
use quadtree_util::*;

const REL: f32 = 1e-4;

/// Counts rays per number of layers traversed.
fn reach(qt: &QuadTreeTracer, rays: &[parallax_core::Ray]) -> Vec<usize> {
    let mut n = vec![0; qt.trees.len() + 1];
    let mut s = TraceStats::default();
    for r in rays {
        n[qt.trace_layers(r, &mut s).1] += 1;
    }
    n
}

/// The synthetic three-layer case `(w, h, seed)`: the quad-tree (lossy or lossless merging,
/// exact otherwise), its brute-force twin, and the 300 test rays.
fn synthetic(
    w: u32,
    h: u32,
    seed: u64,
    mode_lossy: bool,
) -> (QuadTreeTracer, BruteForcePlanes, Vec<Ray>) {
    let cam = camera(w, h);
    let g0 = height_field(&cam, seed, 0.05);
    let g1 = behind(&g0, seed + 1);
    let g2 = behind(&g1, seed + 2);
    let layers = vec![g0, g1, g2];
    let cube = cube(&cam, &layers);
    let opts = exact(if mode_lossy {
        QuadTreeOptions {
            gamma_dist: 1e-3,
            gamma_norm: 20f32.to_radians().cos(),
            ..Default::default()
        }
    } else {
        QuadTreeOptions::lossless()
    });
    let qt = QuadTreeTracer::build(&cube, &layers, &opts).unwrap();
    let bf = twin(&qt);
    let rays = rays(&cam, &layers[0], 300, 0.5, seed ^ 3);
    (qt, bf, rays)
}

fn check_synthetic(w: u32, h: u32, seed: u64, mode_lossy: bool) {
    let (qt, bf, rays) = synthetic(w, h, seed, mode_lossy);
    let (t, first, _) = run(&qt, &bf, &rays, REL);
    assert_eq!(t.differ, 0, "{w}x{h} seed {seed}: {t:?} first: {first:?}");
    assert!(t.edge * 50 <= t.total(), "{t:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    #[test]
    fn cascade_equals_brute_force_on_three_synthetic_layers(
        w in 9u32..70, h in 7u32..50, seed in any::<u64>(), lossy in any::<bool>(),
    ) {
        check_synthetic(w, h, seed, lossy);
    }
}

fn capture(name: &str, w: u32, h: u32) -> (Pinhole, Vec<GBuffer>) {
    let scene = Scene::load(name).unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam).unwrap(),
        &RasterOptions::layers(2),
    )
    .unwrap();
    (cam, cap.layers.layers.clone())
}

#[test]
fn cascade_equals_brute_force_on_two_layer_captures() {
    for (name, w, h) in [("atrium", 160, 90), ("cornell", 96, 72)] {
        let (cam, layers) = capture(name, w, h);
        let cube = cube(&cam, &layers);
        let qt =
            QuadTreeTracer::build(&cube, &layers, &exact(QuadTreeOptions::lossless())).unwrap();
        let bf = twin(&qt);
        for (spread, seed) in [(0.0325, 1u64), (0.5, 2)] {
            let rays = rays(&cam, &layers[0], 1500, spread, seed);
            let (t, first, _) = run(&qt, &bf, &rays, REL);
            let n = reach(&qt, &rays);
            eprintln!(
                "{name} spread {spread}: {t:?}; rays by layers traversed {n:?} ({:.2}% reach layer 2); unsafe px {:?}",
                100.0 * n[2] as f64 / rays.len() as f64,
                qt.unsafe_pixels()
            );
            assert_eq!(t.differ, 0, "{name}: {t:?} first: {first:?}");
            assert!(t.edge * 100 <= t.total(), "{t:?}");
        }
        let srays = stereo_rays(&cam, 0.0325);
        let (t, first, _) = run(&qt, &bf, &srays, REL);
        let n = reach(&qt, &srays);
        eprintln!("{name} stereo eye: {t:?}; layers traversed {n:?}");
        assert_eq!(t.differ, 0, "{name}: {t:?} first: {first:?}");
        assert!(
            n[2] * 5 < srays.len(),
            "most stereo rays settle in layer 0: {n:?}"
        );
        // Layer 2 matters: brute force over layer 0 alone differs on some rays.
        let single = BruteForcePlanes {
            cube: bf.cube.clone(),
            layers: vec![bf.layers[0].clone()],
        };
        let rays2 = rays(&cam, &layers[0], 1500, 0.5, 2);
        let (t, _, _) = run(&qt, &single, &rays2, REL);
        eprintln!("{name}: 2-layer cascade vs layer-0-only brute force {t:?}");
    }
}

#[test]
fn inpaint_stops_at_first_event() {
    let (cam, layers) = capture("atrium", 160, 90);
    let layers = vec![layers[0].clone()];
    let cube = cube(&cam, &layers);
    let opts = exact(QuadTreeOptions {
        mode: LayerMode::Inpaint,
        ..QuadTreeOptions::lossless()
    });
    let qt = QuadTreeTracer::build(&cube, &layers, &opts).unwrap();
    let bf = twin(&qt);
    let rays = rays(&cam, &layers[0], 1500, 0.5, 5);
    let mut s = TraceStats::default();
    let (mut ov, mut hit) = (0, 0);
    for r in &rays {
        let a = qt.trace_ray(r, &mut s);
        let b = bf.trace_detailed(r, &mut s);
        let first_is_hit = match (b.hit, b.occlusion) {
            (Some(h), Some(o)) => h.t <= o.t,
            (h, _) => h.is_some(),
        };
        match a {
            TraceResult::Hit { pixel, t, .. } => {
                assert!(first_is_hit, "{r:?}: {a:?} vs {b:?}");
                let h = b.hit.unwrap();
                assert!(
                    (t - h.t).abs() <= REL * t
                        && pixel.as_ivec2().distance_squared(h.pixel.as_ivec2()) <= 2
                );
                hit += 1;
            }
            TraceResult::OcclusionVolume { pixel, t, .. } => {
                let o = b.occlusion.expect("an occlusion entry");
                assert!(
                    !first_is_hit || b.hit.unwrap().t > o.t * (1.0 - REL),
                    "{r:?}"
                );
                // Dilated: at most the entry, and within ~one pixel of travel before it.
                assert!(t <= o.t * (1.0 + REL), "{t} vs {}", o.t);
                let d = pixel.as_ivec2() - o.pixel.as_ivec2();
                assert!(d.x.abs() <= 2 && d.y.abs() <= 2, "{pixel} vs {}", o.pixel);
                ov += 1;
            }
            TraceResult::Miss => assert!(b.hit.is_none() && b.occlusion.is_none()),
        }
    }
    eprintln!(
        "inpaint: {hit} hits, {ov} occlusion entries of {}",
        rays.len()
    );
    assert!(ov > 0 && hit > 0);
}

/// A case proptest found.
#[test]
fn cascade_regression_47x28() {
    check_synthetic(47, 28, 3129365413543782575, false);
}

/// A case proptest found (lossy settings): ray 76 crosses layer 0's plane at pixel
/// (23, 26) 1.0e-6 px before (f64) entering its footprint; brute force's f32 boundary
/// `27/45` puts the crossing inside (a hit at the entry), the traversal's grid-unit entry
/// puts it outside (an occlusion entry). Both answers are the same point within 1e-5 px:
/// an edge tie ([`Verdict::or_boundary_crossing`]). The rule is narrow: the same answers
/// with the hit moved 0.01 px along the ray, or given a non-adjacent pixel or another layer,
/// still differ.
#[test]
fn cascade_regression_24x45_hit_vs_entry() {
    let (w, h, seed) = (24u32, 45u32, 6201883681859096247u64);
    check_synthetic(w, h, seed, true);
    let (qt, bf, rays) = synthetic(w, h, seed, true);
    let r = rays[76];
    let mut s = TraceStats::default();
    let a = qt.trace(&r, &mut s);
    let b = bf.trace(&r, &mut s);
    let (TraceResult::OcclusionVolume { layer, pixel, t }, TraceResult::Hit { t: th, .. }) = (a, b)
    else {
        panic!("the case changed: {a:?} vs {b:?}");
    };
    assert_eq!((layer, pixel), (0, glam::UVec2::new(23, 26)));
    assert_eq!(compare(&a, &b, REL), Verdict::Differ);
    assert_eq!(a_vs_b(&a, &b, &r, &bf), Verdict::EdgeTie);
    assert_eq!(a_vs_b(&b, &a, &r, &bf), Verdict::EdgeTie);
    // Narrowness: 0.01 px of travel further (segment: ~3.5 px over ~14 m), another pixel,
    // another layer.
    let moved = |dt: f32| match b {
        TraceResult::Hit { layer, pixel, .. } => TraceResult::Hit {
            layer,
            pixel,
            position: r.at(th + dt),
            t: th + dt,
        },
        _ => unreachable!(),
    };
    assert_eq!(a_vs_b(&a, &moved(0.04), &r, &bf), Verdict::Differ);
    assert_eq!(a_vs_b(&a, &moved(-0.04), &r, &bf), Verdict::Differ);
    let other_pixel = TraceResult::OcclusionVolume {
        layer,
        pixel: glam::UVec2::new(21, 26),
        t,
    };
    assert_eq!(a_vs_b(&other_pixel, &b, &r, &bf), Verdict::Differ);
    let other_layer = TraceResult::OcclusionVolume { layer: 1, pixel, t };
    assert_eq!(a_vs_b(&other_layer, &b, &r, &bf), Verdict::Differ);
}

fn a_vs_b(
    a: &TraceResult,
    b: &TraceResult,
    r: &parallax_core::Ray,
    bf: &BruteForcePlanes,
) -> Verdict {
    compare(a, b, REL)
        .or_same_entry(a, b, r, &bf.cube)
        .or_boundary_crossing(a, b, r, bf, REL)
}

/// A case proptest found (lossy settings): layer 1's plane at pixel (5, 18) lies behind
/// layer 0's *pixel* plane (pixel safe, merged) but in front of the merged level-1 proxy
/// plane the traversal tests (up to `gamma_dist` away), so the cascade never traced layer 1
/// and returned layer 0's hit 0.0056 m behind brute force's layer-1 hit. Fixed in the build:
/// pixels unsafe against their effective plane are kept from merging (quadtree/build.rs).
#[test]
fn cascade_regression_56x32_proxy_plane() {
    check_synthetic(56, 32, 2410601268783673479, true);
}

/// A case proptest found (lossy settings): ray 260 crosses layer 1's plane at pixel
/// (7, 11) 3.7e-7 px (f64) before entering its footprint. The traversal's entry (reciprocal
/// of the direction) is one ulp earlier and finds the crossing inside: a layer-1 hit at the
/// entry, closer than layer 0's hit; brute force enters behind the plane (an occlusion
/// entry) and returns layer 0's hit 0.8 m further. An edge tie of the hidden layer
/// ([`Verdict::or_boundary_crossing`], the quad-tree's answer being brute force's with that
/// one crossing counted as a hit).
#[test]
fn cascade_regression_53x41_hidden_boundary_crossing() {
    let (w, h, seed) = (53u32, 41u32, 12274103234209209180u64);
    check_synthetic(w, h, seed, true);
    let (qt, bf, rays) = synthetic(w, h, seed, true);
    let r = rays[260];
    let mut s = TraceStats::default();
    let (a, b) = (qt.trace(&r, &mut s), bf.trace(&r, &mut s));
    let (
        TraceResult::Hit {
            layer: 1, pixel, ..
        },
        TraceResult::Hit { layer: 0, .. },
    ) = (a, b)
    else {
        panic!("the case changed: {a:?} vs {b:?}");
    };
    assert_eq!(pixel, glam::UVec2::new(7, 11));
    assert_eq!(
        compare(&a, &b, REL).or_same_entry(&a, &b, &r, &bf.cube),
        Verdict::Differ
    );
    assert_eq!(a_vs_b(&a, &b, &r, &bf), Verdict::EdgeTie);
    // Symmetric (brute force's answer is the quad-tree's without the crossing).
    assert_eq!(a_vs_b(&b, &a, &r, &bf), Verdict::EdgeTie);
    // Not for the neighbour pixel, nor 0.04 m further along the ray.
    let TraceResult::Hit { position, t, .. } = a else {
        unreachable!()
    };
    let shifted = TraceResult::Hit {
        layer: 1,
        pixel: glam::UVec2::new(7, 12),
        position,
        t,
    };
    assert_eq!(a_vs_b(&shifted, &b, &r, &bf), Verdict::Differ);
    let moved = TraceResult::Hit {
        layer: 1,
        pixel,
        position: r.at(t + 0.04),
        t: t + 0.04,
    };
    assert_eq!(a_vs_b(&moved, &b, &r, &bf), Verdict::Differ);
    assert_eq!(a_vs_b(&shifted, &b, &r, &bf), Verdict::Differ);
}
