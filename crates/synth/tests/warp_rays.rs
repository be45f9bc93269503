//! The warp's pixel rays (`synth::warp::PixelRays`, shared with `bench`'s trace-only pass)
//! are bit-identical to the pinhole's `generate_ray` at every pixel centre.

use glam::{Vec2, Vec3};
use parallax_scene::CameraDesc;
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_synth::warp::PixelRays;

#[test]
fn pixel_rays_equal_generate_ray_bits() {
    let descs = [
        CameraDesc::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 1.5, -2.0),
            Vec3::Y,
            50.0,
        ),
        CameraDesc::new(
            Vec3::new(-9.0, 3.5, 0.0),
            Vec3::new(8.0, 5.0, 0.0),
            Vec3::Y,
            60.0,
        ),
        CameraDesc::new(
            Vec3::new(0.3, -7.0, 0.1),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::Z,
            100.0,
        ),
    ];
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let mut n = 0;
    for (k, d) in descs.iter().enumerate() {
        for (w, h) in [(160u32, 120u32), (97, 31), (1, 1)] {
            let mut cam = Pinhole::new(d, w, h).unwrap();
            if k == 1 {
                cam = cam.with_shift(Vec2::new(0.031, -0.2));
            }
            let rays = PixelRays::new(&cam);
            for y in 0..h {
                let row = rays.row(y);
                for x in 0..w {
                    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let want = cam.generate_ray(film, Vec2::splat(0.5), 1).unwrap().ray;
                    let got = row.ray(x);
                    assert_eq!(bits(got.origin), bits(want.origin));
                    assert_eq!(bits(got.dir), bits(want.dir), "{k} {w}x{h} ({x}, {y})");
                    assert_eq!(got.t_min.to_bits(), want.t_min.to_bits());
                    assert_eq!(got.t_max.to_bits(), want.t_max.to_bits());
                    n += 1;
                }
            }
        }
    }
    assert_eq!(n, 3 * (160 * 120 + 97 * 31 + 1));
}
