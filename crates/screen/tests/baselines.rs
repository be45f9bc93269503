//! The baseline tracers (DDA, min-max mipmaps, Hi-Z) on synthetic height fields with known
//! answers, on degenerate rays, and against the BVH ground truth on small captures.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::{GBuffer, Ray};
use parallax_raster::{LayerCapture, RasterOptions, View, capture_layers};
use parallax_scene::{CameraDesc, Scene, camera::Pinhole};
use parallax_screen::{
    BruteForcePlanes, DdaOptions, DdaTracer, HiZOptions, HiZTracer, MinMaxOptions, MinMaxTracer,
    NormalSource, ScreenTracer, TraceResult, TraceStats, UnitCube,
};

type Tracer = Box<dyn ScreenTracer>;

fn pixel_dir(cam: &Pinhole, x: u32, y: u32) -> Vec3 {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    cam.frame.dir_to_world(cam.camera_dir(film)).normalize()
}

/// All baselines over `layers` with thickness `thick` (1 and 2 layer DDA).
fn tracers(
    cube: &UnitCube,
    layers: &[GBuffer],
    thick: f32,
) -> Vec<(&'static str, Box<dyn ScreenTracer>)> {
    let dda = |n| DdaOptions {
        layers: n,
        z_thickness: thick,
        ..Default::default()
    };
    let mm = MinMaxOptions {
        z_thickness: thick,
        ..Default::default()
    };
    let hz = HiZOptions {
        z_thickness: thick,
        ..Default::default()
    };
    let mut v: Vec<(&'static str, Box<dyn ScreenTracer>)> = vec![
        (
            "dda1",
            Box::new(DdaTracer::new(cube, layers, &dda(1)).unwrap()),
        ),
        (
            "minmax",
            Box::new(MinMaxTracer::new(cube, layers, &mm).unwrap()),
        ),
        (
            "minmax-flat",
            Box::new(
                MinMaxTracer::new(
                    cube,
                    layers,
                    &MinMaxOptions {
                        bilinear: false,
                        ..mm
                    },
                )
                .unwrap(),
            ),
        ),
        ("hiz", Box::new(HiZTracer::new(cube, layers, &hz).unwrap())),
    ];
    if layers.len() > 1 {
        v.insert(
            1,
            (
                "dda2",
                Box::new(DdaTracer::new(cube, layers, &dda(2)).unwrap()),
            ),
        );
    }
    v
}

// ---------------------------------------------------------------- synthetic height fields

const SW: u32 = 64;
const SH: u32 = 48;

fn synth_camera() -> Pinhole {
    let desc = CameraDesc::new(
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        50.0,
    );
    Pinhole::new(&desc, SW, SH).unwrap()
}

/// A layer whose view depth is `f(x, y)` at pixel `(x, y)`.
fn synth_layer(f: impl Fn(u32, u32) -> f32) -> GBuffer {
    let mut g = GBuffer::new(SW, SH).unwrap();
    for y in 0..SH {
        for x in 0..SW {
            g.depth[(y * SW + x) as usize] = f(x, y);
        }
    }
    g
}

/// World `t` at which `ray` reaches view depth `d` (camera at the origin looking down -z).
fn t_at_depth(ray: &Ray, d: f32) -> f32 {
    (-d - ray.origin.z) / ray.dir.z
}

#[test]
fn fronto_parallel_plane_is_hit_exactly() {
    let cam = synth_camera();
    let layer = synth_layer(|_, _| 5.0);
    let cube = UnitCube::new(&cam, 1.0, 20.0).unwrap();
    for (name, tr) in tracers(&cube, std::slice::from_ref(&layer), 0.05) {
        let mut stats = TraceStats::default();
        let mut worst = 0.0f32;
        for shift in [0.0, 0.1, -0.25] {
            let eye = Vec3::new(shift, 0.03, 0.0);
            for y in (0..SH).step_by(3) {
                for x in (0..SW).step_by(3) {
                    let ray = Ray::new(eye, pixel_dir(&cam, x, y));
                    let truth = t_at_depth(&ray, 5.0);
                    let inside = cube.to_cube(ray.at(truth)).unwrap();
                    let inside =
                        inside.x > 0.0 && inside.x < 1.0 && inside.y > 0.0 && inside.y < 1.0;
                    match tr.trace(&ray, &mut stats) {
                        TraceResult::Hit {
                            t, position, layer, ..
                        } => {
                            assert!(inside, "{name}: hit outside the view");
                            assert_eq!(layer, 0);
                            worst = worst.max((t - truth).abs() / truth);
                            assert!((position - ray.at(truth)).length() < 1e-3, "{name}");
                        }
                        r => assert!(!inside, "{name} ({x},{y}) shift {shift}: {r:?}"),
                    }
                }
            }
        }
        eprintln!("{name}: worst rel t error {worst:e}; {stats:?}");
        assert!(worst < 1e-4, "{name}: {worst}");
    }
}

#[test]
fn slanted_plane_hits_within_a_footprint() {
    // A plane tilted about the horizontal axis: depth varies from 3 (top) to ~9 (bottom).
    let cam = synth_camera();
    let n = Vec3::new(0.0, 0.6, 0.8).normalize();
    let p0 = Vec3::new(0.0, 0.0, -5.0);
    let plane_t = |ray: &Ray| (p0 - ray.origin).dot(n) / ray.dir.dot(n);
    let layer = synth_layer(|x, y| {
        let r = Ray::new(
            Vec3::ZERO,
            cam.camera_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5)),
        );
        -r.at(plane_t(&r)).z
    });
    let cube = UnitCube::fit_depths(&cam, [&layer.depth[..]]).unwrap();
    for (name, tr) in tracers(&cube, std::slice::from_ref(&layer), 0.1) {
        let mut stats = TraceStats::default();
        let (mut agree, mut total) = (0, 0);
        let eye = Vec3::new(0.0325, 0.0, 0.0);
        for y in 0..SH {
            for x in 0..SW {
                let ray = Ray::new(eye, pixel_dir(&cam, x, y));
                let truth = ray.at(plane_t(&ray));
                let c = cube.to_cube(truth).unwrap();
                if !(c.x > 0.02 && c.x < 0.98 && c.y > 0.02 && c.y < 0.98) {
                    continue;
                }
                total += 1;
                let fp = 2.0 * cam.tan_half_y * -truth.z / SH as f32;
                if let TraceResult::Hit { position, .. } = tr.trace(&ray, &mut stats) {
                    // The plane is seen at a slant: allow a footprint along the view ray.
                    if (position - truth).length() <= 2.0 * fp {
                        agree += 1;
                    }
                }
            }
        }
        let frac = agree as f64 / total as f64;
        eprintln!("{name}: slanted plane {agree}/{total} = {frac:.4}; {stats:?}");
        assert!(frac >= 0.97, "{name}: {frac}");
    }
}

#[test]
fn depth_step_hits_or_reports_the_occlusion_volume() {
    // Left half at depth 3, right half at depth 6; eyes shifted right see behind the step.
    let cam = synth_camera();
    let layer = synth_layer(|x, _| if x < SW / 2 { 3.0 } else { 6.0 });
    let cube = UnitCube::new(&cam, 1.0, 12.0).unwrap();
    for (name, tr) in tracers(&cube, std::slice::from_ref(&layer), 0.01) {
        let mut stats = TraceStats::default();
        let (mut agree, mut total, mut occluded) = (0, 0, 0);
        let eye = Vec3::new(1.0, 0.0, 0.0);
        for y in (0..SH).step_by(4) {
            for x in 0..SW {
                let ray = Ray::new(eye, pixel_dir(&cam, x, y));
                let (t3, t6) = (t_at_depth(&ray, 3.0), t_at_depth(&ray, 6.0));
                let (c3, c6) = (
                    cube.to_cube(ray.at(t3)).unwrap(),
                    cube.to_cube(ray.at(t6)).unwrap(),
                );
                let expect = if (0.0..0.5).contains(&c3.x) {
                    Some(t3)
                } else if (0.5..1.0).contains(&c6.x) {
                    Some(t6)
                } else if c3.x >= 0.5 && c6.x < 0.5 && c6.x >= 0.0 {
                    None // passes behind the near half: occlusion volume
                } else {
                    continue; // leaves the view
                };
                // Skip rays within a pixel of the step edge.
                if (c3.x - 0.5).abs() < 1.0 / SW as f32 || (c6.x - 0.5).abs() < 1.0 / SW as f32 {
                    continue;
                }
                total += 1;
                let r = tr.trace(&ray, &mut stats);
                let ok = match (expect, r) {
                    (Some(te), TraceResult::Hit { t, .. }) => (t - te).abs() < 1e-3 * te,
                    (None, TraceResult::OcclusionVolume { layer: 0, .. }) => {
                        occluded += 1;
                        true
                    }
                    _ => false,
                };
                if !ok {
                    eprintln!("{name} ({x},{y}): expected {expect:?}, got {r:?}");
                }
                agree += ok as u32;
            }
        }
        eprintln!("{name}: step {agree}/{total}, {occluded} occluded; {stats:?}");
        assert!(occluded > 10, "{name}: {occluded}");
        assert_eq!(agree, total, "{name}");
    }
}

#[test]
fn empty_pixels_have_no_height() {
    let cam = synth_camera();
    let layer = synth_layer(|x, _| if x < SW / 2 { f32::INFINITY } else { 4.0 });
    let cube = UnitCube::new(&cam, 1.0, 12.0).unwrap();
    for (name, tr) in tracers(&cube, std::slice::from_ref(&layer), 0.1) {
        let mut stats = TraceStats::default();
        for y in (0..SH).step_by(5) {
            for x in (0..SW).step_by(5) {
                let ray = Ray::new(Vec3::ZERO, pixel_dir(&cam, x, y));
                let r = tr.trace(&ray, &mut stats);
                if x < SW / 2 {
                    assert_eq!(r, TraceResult::Miss, "{name} ({x},{y})");
                } else {
                    let t = r
                        .hit_t()
                        .unwrap_or_else(|| panic!("{name} ({x},{y}): {r:?}"));
                    assert!((t - t_at_depth(&ray, 4.0)).abs() < 1e-3, "{name}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------- termination

#[test]
fn degenerate_and_random_rays_terminate() {
    let cam = synth_camera();
    let l0 = synth_layer(|x, y| {
        if (x + y) % 7 == 0 {
            f32::INFINITY
        } else {
            2.0 + (x % 5) as f32
        }
    });
    let l1 = synth_layer(|x, _| if x % 3 == 0 { 9.0 } else { f32::INFINITY });
    let layers = [l0, l1];
    let cube = UnitCube::fit_depths(&cam, layers.iter().map(|g| &g.depth[..])).unwrap();
    let eye = cam.frame.position;
    let fwd = cam.frame.forward();
    let right = cam.frame.right();
    let misses = [
        Ray::new(eye, right),
        Ray::new(eye + cam.frame.up() * 0.3, right),
        Ray::new(eye, -fwd),
        Ray::new(eye - fwd, -fwd),
        Ray::new(eye + fwd * 0.01, right + fwd * 1e-3),
        Ray::new(Vec3::NAN, fwd),
        Ray::new(eye, Vec3::new(f32::NAN, 0.0, -1.0)),
        Ray::new(eye, Vec3::ZERO),
        Ray::new(eye, Vec3::INFINITY),
        Ray::segment(eye, fwd, 5.0, 1.0),
        Ray::segment(eye, fwd, f32::NAN, 1.0),
    ];
    for (name, tr) in tracers(&cube, &layers, 0.1) {
        let mut stats = TraceStats::default();
        for r in &misses {
            assert_eq!(tr.trace(r, &mut stats), TraceResult::Miss, "{name}: {r:?}");
        }
        // Starting behind the eye and looking in: clipped to the near plane, same hit.
        let d = pixel_dir(&cam, SW / 2 + 1, SH / 2);
        let front = tr.trace(&Ray::new(eye, d), &mut stats).hit_t().unwrap();
        let back = tr
            .trace(&Ray::new(eye - d * 0.5, d), &mut stats)
            .hit_t()
            .unwrap();
        assert!((back - 0.5 - front).abs() < 1e-3, "{name}: {front} {back}");
        // Random rays from inside and outside the frustum, any direction (incl. towards the
        // eye, parallel to the image plane and grazing): a result, never a hang.
        let mut seed = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        let mut stats = TraceStats::default();
        let n = 3000u64;
        for i in 0..n {
            let o = Vec3::new(rnd() * 3.0, rnd() * 3.0, rnd() * 10.0 - 4.0);
            let mut dir = Vec3::new(rnd(), rnd(), rnd());
            if i % 5 == 0 {
                dir.z = 0.0;
            }
            let _ = tr.trace(&Ray::new(o, dir), &mut stats);
        }
        assert_eq!(stats.rays, n);
        // Every baseline bounds its loop: at most max_steps per layer per ray.
        assert!(stats.steps <= n * 2 * 2000, "{name}: {stats:?}");
        eprintln!("{name}: random rays {stats:?}");
    }
}

#[test]
fn bad_options_and_sizes_error() {
    let cam = synth_camera();
    let l = synth_layer(|_, _| 3.0);
    let cube = UnitCube::new(&cam, 1.0, 10.0).unwrap();
    let small = GBuffer::new(8, 8).unwrap();
    assert!(DdaTracer::new(&cube, std::slice::from_ref(&small), &DdaOptions::default()).is_err());
    assert!(
        MinMaxTracer::new(
            &cube,
            std::slice::from_ref(&small),
            &MinMaxOptions::default()
        )
        .is_err()
    );
    assert!(HiZTracer::new(&cube, std::slice::from_ref(&small), &HiZOptions::default()).is_err());
    assert!(DdaTracer::new(&cube, &[], &DdaOptions::default()).is_err());
    for bad in [
        DdaOptions {
            layers: 3,
            ..Default::default()
        },
        DdaOptions {
            stride: 0.5,
            ..Default::default()
        },
        DdaOptions {
            jitter: 2.0,
            ..Default::default()
        },
        DdaOptions {
            z_thickness: f32::NAN,
            ..Default::default()
        },
    ] {
        assert!(
            DdaTracer::new(&cube, std::slice::from_ref(&l), &bad).is_err(),
            "{bad:?}"
        );
    }
    // Asking for 2 layers of a 1-layer capture uses the one there is.
    let t = DdaTracer::new(&cube, std::slice::from_ref(&l), &DdaOptions::default()).unwrap();
    assert_eq!(t.bytes(), (SW * SH) as usize * 4);
}

// ---------------------------------------------------------------- captures vs the BVH

const W: u32 = 96;
const H: u32 = 64;

struct Case {
    cam: Pinhole,
    cap: LayerCapture,
    cube: UnitCube,
    bvh: Bvh,
}

fn case(name: &str) -> Case {
    let scene = Scene::load(name).unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), W, H).unwrap();
    let cap = capture_layers(
        &scene,
        &View::from_pinhole(&cam).unwrap(),
        &RasterOptions::layers(2),
    )
    .unwrap();
    let cube = UnitCube::fit_depths(&cam, cap.layers.layers.iter().map(|g| &g.depth[..])).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    Case {
        cam,
        cap,
        cube,
        bvh,
    }
}

/// Fraction of the BVH hits of an eye moved `shift` m along the reference's right axis (one
/// ray per pixel centre) that `tr` hits within `tol` pixel footprints (at the true hit's
/// depth) of the true hit, and the stats.
fn agreement(c: &Case, tr: &dyn ScreenTracer, shift: f32, tol: f32) -> (f64, TraceStats) {
    let eye = c.cam.frame.position + c.cam.frame.right() * shift;
    let (mut agree, mut total) = (0u32, 0u32);
    let mut stats = TraceStats::default();
    for y in 0..H {
        for x in 0..W {
            let ray = Ray::new(eye, pixel_dir(&c.cam, x, y));
            let r = tr.trace(&ray, &mut stats);
            let Some(h) = c.bvh.closest_hit(&ray) else {
                continue;
            };
            total += 1;
            let truth = ray.at(h.t);
            let depth = -c.cam.frame.to_camera(truth).z;
            let fp = 2.0 * c.cam.tan_half_y * depth / H as f32;
            if let TraceResult::Hit { position, .. } = r
                && (position - truth).length() <= tol * fp
            {
                agree += 1;
            }
        }
    }
    (agree as f64 / total as f64, stats)
}

/// Per tracer name: minimum agreement for the stereo eye (0.0325 m) and for a 0.3 m shift,
/// both within one footprint.
fn quality(name: &str, min_frac: &[(&str, f64, f64)]) {
    let c = case(name);
    let brute = BruteForcePlanes::new(c.cube.clone(), &c.cap, NormalSource::GBuffer).unwrap();
    let (fb, _) = agreement(&c, &brute, 0.0325, 1.0);
    let (fb3, _) = agreement(&c, &brute, 0.3, 1.0);
    eprintln!("{name} brute: {fb:.4} / {fb3:.4}");
    for (tname, tr) in tracers(&c.cube, &c.cap.layers.layers, 0.1) {
        let (f, stats) = agreement(&c, tr.as_ref(), 0.0325, 1.0);
        let (f3, stats3) = agreement(&c, tr.as_ref(), 0.3, 1.0);
        eprintln!(
            "{name} {tname}: stereo {f:.4} (brute {fb:.4}), 0.3 m {f3:.4} (brute {fb3:.4}); steps/ray {:.1} / {:.1}; occl {} / {}",
            stats.steps as f64 / stats.rays as f64,
            stats3.steps as f64 / stats3.rays as f64,
            stats.occlusion_volumes,
            stats3.occlusion_volumes,
        );
        let &(_, want, want3) = min_frac.iter().find(|(n, _, _)| *n == tname).unwrap();
        assert!(f >= want, "{name} {tname}: {f} < {want}");
        assert!(f3 >= want3, "{name} {tname} 0.3 m: {f3} < {want3}");
    }
}

#[test]
fn cornell_stereo_eye_agrees_with_bvh() {
    quality(
        "cornell",
        // Measured (96x64): dda 0.879 / 0.844, minmax 0.910 / 0.905, flat and hiz 0.879 /
        // 0.854; brute-force planes 0.990 / 0.978 (flat heights on the obliquely seen walls
        // are off by more than a footprint along the ray).
        &[
            ("dda1", 0.86, 0.82),
            ("dda2", 0.86, 0.82),
            ("minmax", 0.89, 0.88),
            ("minmax-flat", 0.86, 0.83),
            ("hiz", 0.86, 0.83),
        ],
    );
}

#[test]
fn atrium_stereo_eye_agrees_with_bvh() {
    quality(
        "atrium",
        // Measured (96x64): dda 0.953 / 0.730, minmax 0.949 / 0.848, flat and hiz 0.953 /
        // 0.835; brute-force planes 0.955 / 0.860.
        &[
            ("dda1", 0.93, 0.71),
            ("dda2", 0.93, 0.71),
            ("minmax", 0.93, 0.83),
            ("minmax-flat", 0.93, 0.81),
            ("hiz", 0.93, 0.81),
        ],
    );
}

#[test]
fn second_layer_resolves_disocclusions() {
    // A 0.3 m shift sees behind the boxes / columns: the cascade into layer 1 must find
    // surfaces one layer cannot.
    for name in ["cornell", "atrium"] {
        let c = case(name);
        let layers = &c.cap.layers.layers;
        let mm = |n| {
            MinMaxTracer::new(
                &c.cube,
                layers,
                &MinMaxOptions {
                    layers: n,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let hz = |n| {
            HiZTracer::new(
                &c.cube,
                layers,
                &HiZOptions {
                    layers: n,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let dd = |n| {
            DdaTracer::new(
                &c.cube,
                layers,
                &DdaOptions {
                    layers: n,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let pairs: [(&str, Tracer, Tracer); 3] = [
            ("minmax", Box::new(mm(1)), Box::new(mm(2))),
            ("hiz", Box::new(hz(1)), Box::new(hz(2))),
            ("dda", Box::new(dd(1)), Box::new(dd(2))),
        ];
        for (tname, one, two) in pairs {
            let (f1, s1) = agreement(&c, one.as_ref(), 0.3, 1.0);
            let (f2, s2) = agreement(&c, two.as_ref(), 0.3, 1.0);
            eprintln!(
                "{name} {tname}: 1 layer {f1:.4} ({} occl), 2 layers {f2:.4} ({} occl)",
                s1.occlusion_volumes, s2.occlusion_volumes
            );
            assert!(f2 >= f1, "{name} {tname}");
            assert!(
                s2.occlusion_volumes <= s1.occlusion_volumes,
                "{name} {tname}"
            );
        }
    }
}

#[test]
fn minmax_flat_and_hiz_find_the_same_hits() {
    // Both trace flat per-pixel heights with the same leaf test; they differ only in how they
    // skip (min-max bounds vs min only). Any lost or extra hit is a traversal bug.
    for name in ["cornell", "atrium"] {
        let c = case(name);
        let layers = &c.cap.layers.layers;
        let mm = MinMaxTracer::new(
            &c.cube,
            layers,
            &MinMaxOptions {
                bilinear: false,
                ..Default::default()
            },
        )
        .unwrap();
        let hz = HiZTracer::new(&c.cube, layers, &HiZOptions::default()).unwrap();
        let (mut sm, mut sh) = (TraceStats::default(), TraceStats::default());
        let mut compared = 0;
        for shift in [0.0325, 0.3, -0.5] {
            let eye = c.cam.frame.position + c.cam.frame.right() * shift + c.cam.frame.up() * 0.1;
            for y in 0..H {
                for x in 0..W {
                    let ray = Ray::new(eye, pixel_dir(&c.cam, x, y));
                    let (a, b) = (mm.trace(&ray, &mut sm), hz.trace(&ray, &mut sh));
                    match (a.hit_t(), b.hit_t()) {
                        (Some(ta), Some(tb)) => {
                            assert!(
                                (ta - tb).abs() <= 1e-4 * ta,
                                "{name} ({x},{y}): {a:?} {b:?}"
                            )
                        }
                        (None, None) => {}
                        _ => panic!("{name} ({x},{y}) shift {shift}: {a:?} vs {b:?}"),
                    }
                    compared += 1;
                }
            }
        }
        eprintln!(
            "{name}: {compared} rays; minmax steps/ray {:.2}, hiz {:.2}",
            sm.steps as f64 / sm.rays as f64,
            sh.steps as f64 / sh.rays as f64
        );
        assert_eq!(sm.hits, sh.hits);
    }
}
