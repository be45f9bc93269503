//! The two-level LDC tracer (Bürger et al. 2007, §1.3-1.4) against the BVH: it answers like
//! the BVH on axis-aligned and random rays (measured agreement), its coarse levels are exact
//! filters (every block size and interval count, down to one block over the whole image — a
//! plain fine DDA — gives the same answers), occlusion agrees with closest hits, and every
//! traversal terminates without truncation, degenerate rays included.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::sampling::{Rng, warp};
use parallax_core::{Aabb, HitSurface, Ray, WorldHit, WorldStats, WorldTracer};
use parallax_raster::ldc::{LayeredDepthCube, LdcOptions};
use parallax_scene::Scene;
use parallax_screen::ldc::{LdcTraceOptions, LdcTracer, SampleTest};
use proptest::prelude::*;

fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn tracer(scene: &Scene, res: u32, block: u32, opts: LdcTraceOptions) -> LdcTracer {
    let build = LdcOptions {
        block,
        ..LdcOptions::default()
    };
    LdcTracer::new(LayeredDepthCube::build(scene, res, &build).unwrap(), opts).unwrap()
}

/// `n` rays with origins uniform in `b`: along `±x, ±y, ±z` (`axis`) or uniform directions.
fn rays(b: &Aabb, n: usize, axis: bool, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed, axis as u64);
    (0..n)
        .map(|_| {
            let o = b.min + b.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let d = if axis {
                let k = rng.next_bounded(6) as usize;
                let mut d = Vec3::ZERO;
                d[k % 3] = if k < 3 { 1.0 } else { -1.0 };
                d
            } else {
                warp::uniform_sphere(rng.next_vec2())
            };
            Ray::new(o, d)
        })
        .collect()
}

fn agrees(a: Option<WorldHit>, b: Option<WorldHit>, tol: f32) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => a.prim == b.prim || a.position.distance(b.position) < tol,
        _ => false,
    }
}

/// Fraction of `rays` on which `ldc` and `bvh` agree (same primitive or within `tol`).
fn agreement(ldc: &LdcTracer, bvh: &Bvh, rays: &[Ray], tol: f32) -> f64 {
    let (mut s, mut t) = (WorldStats::default(), WorldStats::default());
    let n = rays
        .iter()
        .filter(|r| {
            let want = WorldTracer::closest_hit(bvh, r, &mut t);
            agrees(ldc.closest_hit(r, &mut s), want, tol)
        })
        .count();
    assert_eq!(s.truncated, 0);
    n as f64 / rays.len() as f64
}

#[test]
fn answers_like_the_bvh_on_axis_and_random_rays() {
    let mut cases = vec![("cornell", Scene::load("cornell").unwrap(), 256, 0.985)];
    let bunny = shared("stanford_bunny/bun_zipper.ply");
    if std::path::Path::new(&bunny).exists() {
        cases.push(("bunny", Scene::load(&bunny).unwrap(), 256, 0.985));
    } else {
        eprintln!("skipping missing {bunny}");
    }
    for (name, scene, res, min) in cases {
        let bvh = Bvh::build(&scene.mesh);
        let ldc = tracer(&scene, res, 8, LdcTraceOptions::default());
        let b = scene.mesh.bounds();
        for axis in [true, false] {
            let r = rays(&b, 4000, axis, 3);
            let a = agreement(&ldc, &bvh, &r, LdcTraceOptions::default().eps);
            eprintln!(
                "{name} at {res}^2, {} rays: agreement {a:.4}",
                if axis { "axis" } else { "random" }
            );
            assert!(a >= min, "{name} axis={axis}: {a}");
        }
    }
}

#[test]
fn coarse_levels_are_exact_filters() {
    let scene = Scene::load("cornell").unwrap();
    let b = scene.mesh.bounds();
    let mut all = rays(&b, 1500, false, 5);
    all.extend(rays(&b, 500, true, 6));
    for test in [SampleTest::Plane, SampleTest::Depth] {
        let opts = |intervals| LdcTraceOptions {
            test,
            intervals,
            ..LdcTraceOptions::default()
        };
        // One block over the whole image: the coarse test passes for any ray near the box's
        // depth range, so the fine DDA walks every pixel the ray crosses.
        let brute = tracer(&scene, 96, 1 << 10, opts(1));
        let mut sb = WorldStats::default();
        let want: Vec<_> = all.iter().map(|r| brute.closest_hit(r, &mut sb)).collect();
        for (block, intervals) in [(8, 1), (8, 4), (16, 8), (4, 2), (1, 3)] {
            let t = tracer(&scene, 96, block, opts(intervals));
            let mut s = WorldStats::default();
            for (r, w) in all.iter().zip(&want) {
                let got = t.closest_hit(r, &mut s);
                // The same sample; `t` may differ in the last bits (a pixel's interval comes
                // from its block's DDA, so its ends round differently per block size).
                let same = match (&got, w) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        a.prim == b.prim
                            && a.surface == b.surface
                            && (a.t - b.t).abs() <= 1e-5 * (1.0 + b.t)
                    }
                    _ => false,
                };
                assert!(
                    same,
                    "{test:?} block {block} x{intervals}: {r:?}\n{got:?}\n{w:?}"
                );
            }
            assert!(
                s.steps < sb.steps,
                "block {block}: the coarse level skips pixels"
            );
            assert_eq!(s.truncated, 0);
        }
    }
}

#[test]
fn occlusion_is_a_closest_hit_and_hits_are_samples() {
    let scene = Scene::load("cornell").unwrap();
    let ldc = tracer(&scene, 128, 8, LdcTraceOptions::default());
    let mut s = WorldStats::default();
    let b = scene.mesh.bounds();
    let mut hits = 0;
    for (i, r) in rays(&b, 2000, false, 9).into_iter().enumerate() {
        // Half the rays as segments.
        let r = if i % 2 == 0 {
            Ray::segment(r.origin, r.dir, 0.0, 0.5)
        } else {
            r
        };
        let h = ldc.closest_hit(&r, &mut s);
        assert_eq!(ldc.occluded(&r, &mut s), h.is_some(), "{r:?}");
        if let Some(h) = h {
            hits += 1;
            assert!(h.t > r.t_min && h.t < r.t_max);
            assert!((h.position - r.at(h.t)).length() < 1e-5);
            assert!((h.prim as usize) < scene.mesh.triangle_count());
            let HitSurface::Sampled(sample) = h.surface else {
                panic!("LDC hits are sampled");
            };
            assert!((sample.normal.length() - 1.0).abs() < 1e-4);
        }
    }
    assert!(hits > 500, "{hits}");
    assert_eq!(s.rays, 4000);
    assert!(!ldc.is_exact());
}

#[test]
fn invalid_options_are_errors() {
    let scene = Scene::load("cornell").unwrap();
    let cube = LayeredDepthCube::build(&scene, 32, &LdcOptions::default()).unwrap();
    let d = LdcTraceOptions::default();
    for bad in [
        LdcTraceOptions { eps: 0.0, ..d },
        LdcTraceOptions { eps: -1e-3, ..d },
        LdcTraceOptions { eps: f32::NAN, ..d },
        LdcTraceOptions {
            eps: f32::INFINITY,
            ..d
        },
        LdcTraceOptions { intervals: 0, ..d },
        LdcTraceOptions {
            intervals: 1000,
            ..d
        },
        LdcTraceOptions { skip: -1.0, ..d },
        LdcTraceOptions { overlap: -0.1, ..d },
        LdcTraceOptions { overlap: 2.0, ..d },
        LdcTraceOptions {
            overlap: f32::NAN,
            ..d
        },
        LdcTraceOptions {
            skip: f32::NAN,
            ..d
        },
    ] {
        assert!(LdcTracer::new(cube.clone(), bad).is_err(), "{bad:?}");
    }
    assert!(SampleTest::parse("plane").is_ok() && SampleTest::parse("box").is_err());
}

/// Degenerate components: zero, tiny, huge, or ordinary.
fn component() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(1.0f32),
        Just(-1.0f32),
        Just(1e-30f32),
        Just(-1e-30f32),
        Just(1e30f32),
        -1.0f32..1.0,
    ]
}

/// Origins inside, on the faces, edges and corners of, or far outside the box [-1.05, 1.05] x
/// [-0.05, 2.05] x [-1.05, 1.0] (the Cornell box's bounds).
fn origin() -> impl Strategy<Value = Vec3> {
    let coord =
        |lo: f32, hi: f32| prop_oneof![Just(lo), Just(hi), lo..hi, Just(1e6f32), Just(-1e6f32)];
    (coord(-1.05, 1.05), coord(-0.05, 2.05), coord(-1.05, 1.0))
        .prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn every_traversal_terminates(
        o in origin(),
        d in (component(), component(), component()),
        t in prop_oneof![Just((0.0f32, f32::INFINITY)), (0.0f32..3.0, 0.0f32..3.0), Just((f32::NAN, 1.0))],
        nan in 0u8..8,
    ) {
        static LDC: std::sync::LazyLock<LdcTracer> = std::sync::LazyLock::new(|| {
            let scene = Scene::load("cornell").unwrap();
            tracer(&scene, 64, 8, LdcTraceOptions::default())
        });
        let mut dir = Vec3::new(d.0, d.1, d.2);
        let mut origin = o;
        if nan == 0 { dir.x = f32::NAN; }
        if nan == 1 { origin.y = f32::NAN; }
        let ray = Ray::segment(origin, dir, t.0, t.1);
        let mut s = WorldStats::default();
        let h = LDC.closest_hit(&ray, &mut s);
        let occ = LDC.occluded(&ray, &mut s);
        prop_assert_eq!(s.truncated, 0);
        prop_assert_eq!(occ, h.is_some());
        if !ray.is_valid() || !(ray.t_min < ray.t_max) {
            prop_assert!(h.is_none());
        }
        if let Some(h) = h {
            prop_assert!(h.t > ray.t_min && h.t < ray.t_max && h.t.is_finite());
        }
    }
}
