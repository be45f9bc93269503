//! The brute-force per-pixel-plane tracer against the BVH ground truth on a captured layer.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_raster::{LayerCapture, View, capture_gbuffer};
use parallax_scene::{Scene, camera::Pinhole};
use parallax_screen::{BruteForcePlanes, NormalSource, ScreenTracer, TraceResult, TraceStats};

const W: u32 = 48;
const H: u32 = 36;

fn setup() -> (Scene, Pinhole, LayerCapture, Bvh) {
    let scene = Scene::load("cornell").unwrap();
    let cam = Pinhole::new(&scene.camera(None).unwrap(), W, H).unwrap();
    let cap = capture_gbuffer(&scene, &View::from_pinhole(&cam).unwrap()).unwrap();
    let bvh = Bvh::build(&scene.mesh);
    (scene, cam, cap, bvh)
}

fn pixel_dir(cam: &Pinhole, x: u32, y: u32) -> Vec3 {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    cam.frame.dir_to_world(cam.camera_dir(film)).normalize()
}

#[test]
fn pixel_centre_rays_hit_own_plane_at_bvh_distance() {
    let (_, cam, cap, bvh) = setup();
    for source in [
        NormalSource::GBuffer,
        NormalSource::Depth {
            max_rel_error: 0.01,
        },
    ] {
        let tracer = BruteForcePlanes::from_capture(&cap, &cam, source).unwrap();
        let mut stats = TraceStats::default();
        let (mut checked, mut worst) = (0, 0.0f32);
        for y in 0..H {
            for x in 0..W {
                let ray = Ray::new(cam.frame.position, pixel_dir(&cam, x, y));
                let truth = bvh.closest_hit(&ray);
                match (tracer.trace(&ray, &mut stats), truth) {
                    (
                        TraceResult::Hit {
                            layer,
                            pixel,
                            t,
                            position,
                        },
                        Some(h),
                    ) => {
                        assert_eq!((layer, pixel.x, pixel.y), (0, x, y), "{source:?}");
                        let rel = (t - h.t).abs() / h.t;
                        worst = worst.max(rel);
                        assert!(
                            rel < 1e-3,
                            "{source:?} pixel ({x},{y}): t {t} vs bvh {}",
                            h.t
                        );
                        assert!((position - ray.at(h.t)).length() < 1e-3 * h.t);
                        checked += 1;
                    }
                    (TraceResult::Miss, None) => {}
                    (r, h) => panic!("{source:?} pixel ({x},{y}): {r:?} vs bvh {h:?}"),
                }
            }
        }
        assert!(checked > (W * H / 2) as usize, "{checked}");
        assert_eq!(stats.rays, (W * H) as u64);
        assert_eq!(stats.hits, checked as u64);
        assert!(stats.plane_tests >= stats.hits);
        eprintln!("{source:?}: worst relative t error {worst:e}, {stats:?}");
    }
}

/// Rays from an eye moved by `shift`: (agree within one pixel footprint, disoccluded, wrong,
/// total BVH hits).
fn shifted(shift_len: f32) -> (u32, u32, u32, u32) {
    let (_, cam, cap, bvh) = setup();
    let tracer = BruteForcePlanes::from_capture(&cap, &cam, NormalSource::GBuffer).unwrap();
    let shift = cam.frame.right() * shift_len;
    let mut stats = TraceStats::default();
    let (mut agree, mut disoccluded, mut wrong, mut total) = (0u32, 0u32, 0u32, 0u32);
    for y in 0..H {
        for x in 0..W {
            let ray = Ray::new(cam.frame.position + shift, pixel_dir(&cam, x, y));
            let Some(h) = bvh.closest_hit(&ray) else {
                continue;
            };
            total += 1;
            let truth = ray.at(h.t);
            let depth = -cam.frame.to_camera(truth).z;
            let footprint = 2.0 * cam.tan_half_y * depth / H as f32;
            let r = tracer.trace_detailed(&ray, &mut stats);
            let occluded_first = r
                .occlusion
                .is_some_and(|o| r.hit.is_none_or(|hh| o.t < hh.t));
            match r.hit {
                Some(hh) if (ray.at(hh.t) - truth).length() <= footprint => agree += 1,
                _ if occluded_first => disoccluded += 1,
                _ => wrong += 1,
            }
        }
    }
    eprintln!("shift {shift}: {agree} agree, {disoccluded} disoccluded, {wrong} wrong of {total}");
    (agree, disoccluded, wrong, total)
}

#[test]
fn shifted_eye_hits_within_a_pixel_footprint() {
    let (agree, disoccluded, _, total) = shifted(0.018);
    let frac = agree as f64 / (total - disoccluded) as f64;
    assert!(frac >= 0.95, "{frac}");
    assert!(disoccluded < total / 10, "{disoccluded} of {total}");
}

#[test]
fn degenerate_rays_miss_without_panicking() {
    let (_, cam, cap, bvh) = setup();
    let tracer = BruteForcePlanes::from_capture(&cap, &cam, NormalSource::GBuffer).unwrap();
    let dyn_tracer: &dyn ScreenTracer = &tracer;
    let mut stats = TraceStats::default();
    let eye = cam.frame.position;
    let fwd = cam.frame.forward();
    let misses = [
        Ray::new(eye, cam.frame.right()), // in the eye plane: parallel to the image
        Ray::new(eye + cam.frame.up() * 0.3, cam.frame.right()), // parallel, in front of near
        Ray::new(eye, -fwd),              // leaves the frustum backwards
        Ray::new(eye - fwd, -fwd),        // starts behind the eye, going away
        Ray::new(eye + fwd * 0.01, cam.frame.right() + fwd * 1e-3), // leaves through the side
        Ray::new(Vec3::NAN, fwd),
        Ray::new(eye, Vec3::ZERO),
        Ray::segment(eye, fwd, 5.0, 1.0),
    ];
    for r in misses {
        assert_eq!(dyn_tracer.trace(&r, &mut stats), TraceResult::Miss, "{r:?}");
    }
    // Starting behind the near plane (behind the eye) and looking in: clipped, same hit.
    let d = pixel_dir(&cam, W / 2, H / 2);
    let back = Ray::new(eye - d * 0.5, d);
    let h = bvh.closest_hit(&back).unwrap();
    let t = dyn_tracer.trace(&back, &mut stats).hit_t().unwrap();
    assert!((t - h.t).abs() < 1e-3 * h.t, "{t} vs {}", h.t);
}

#[test]
fn large_shift_reports_disocclusions() {
    // A 30 cm baseline sees around the boxes: rays pass behind their captured faces.
    let (agree, disoccluded, wrong, total) = shifted(0.3);
    assert!(disoccluded > 0, "{disoccluded}");
    assert!(
        agree as f64 / (total - disoccluded) as f64 >= 0.9,
        "{agree} {wrong} {total}"
    );
}
