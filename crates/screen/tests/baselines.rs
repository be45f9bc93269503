//! The baseline tracers (DDA, min-max mipmaps, Hi-Z) on synthetic height fields with known
//! answers and on degenerate rays (captures vs the BVH: `baselines_scenes.rs`).

use glam::{Vec2, Vec3};
use parallax_core::{GBuffer, Ray};
use parallax_scene::{CameraDesc, camera::Pinhole};
use parallax_screen::{
    DdaOptions, DdaTracer, HiZOptions, HiZTracer, MinMaxOptions, MinMaxTracer, ScreenTracer,
    TraceResult, TraceStats, UnitCube,
};

mod baselines_util;
use baselines_util::{pixel_dir, tracers};

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
        // Segments inside a small image are shorter than any default step bound.
        assert_eq!(stats.truncated, 0, "{name}: {stats:?}");
        eprintln!("{name}: random rays {stats:?}");
    }
}

/// A DDA whose `max_steps` cannot reach the surface reports the rays it gave up on
/// ([`TraceStats::truncated`]): a cap too small for the view is visible, not a silent miss.
#[test]
fn dda_counts_rays_that_run_out_of_steps() {
    let cam = synth_camera();
    let layers = [synth_layer(|_, _| 3.0)];
    let cube = UnitCube::new(&cam, 0.5, 10.0).unwrap();
    let eye = cam.frame.position + cam.frame.right() * 0.2;
    for (steps, want) in [(1u32, true), (10_000, false)] {
        let o = DdaOptions {
            max_steps: steps,
            layers: 1,
            ..Default::default()
        };
        let dda = DdaTracer::new(&cube, &layers, &o).unwrap();
        let mut stats = TraceStats::default();
        let mut hits = 0;
        for y in 0..SH {
            for x in 0..SW {
                let r = Ray::new(eye, pixel_dir(&cam, x, y));
                hits += dda.trace(&r, &mut stats).hit_t().is_some() as u64;
            }
        }
        let n = (SW * SH) as u64;
        if want {
            // Most rays give up early (a hit is never a truncation; a few short segments at
            // the image border end within the one step).
            assert!(stats.truncated + hits <= n, "{stats:?}");
            assert!(stats.truncated > n / 2, "{stats:?}");
        } else {
            // Converged: no ray gives up, nearly all hit the plane (the rest enter through
            // the image border behind it or leave the reference frustum: the eye is off
            // the reference camera).
            assert_eq!(stats.truncated, 0, "{stats:?}");
            assert!(hits > n * 9 / 10, "{stats:?}");
        }
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
