//! Colour + depth input as users bring it: a textured plane in front of a sky whose pixels
//! have no depth (+inf, 0 or NaN), written as an sRGB PNG and a depth EXR and read back.
//! Sky pixels keep their colour after a warp (background at infinity, warped by direction),
//! and an identity warp returns the input PNG's bytes exactly (sRGB in, sRGB out).

use glam::{Vec2, Vec3};
use parallax_core::Image;
use parallax_core::image::png::{ToneMapping, srgb_eotf, to_srgb8, write_png};
use parallax_core::image::write_exr;
use parallax_scene::CameraDesc;
use parallax_scene::camera::Pinhole;
use parallax_synth::input::{
    Intrinsics, input_desc, read_color, read_depth, reference_from_images,
};
use parallax_synth::method::{Method, MethodOptions, Synthesizer};
use parallax_synth::warp::HitKind;

const W: u32 = 96;
const H: u32 = 64;
/// View depth of the plane (metres).
const PLANE_Z: f32 = 4.0;

/// The plane covers the lower 60% of the image and the middle 70% of its width.
fn on_plane(x: u32, y: u32) -> bool {
    y >= H * 2 / 5 && (W * 3 / 20..W * 17 / 20).contains(&x)
}

/// sRGB bytes of the input: a checkerboard with a colour ramp on the plane, a smooth
/// gradient with a sun-like spot in the sky.
fn input_bytes() -> Vec<u8> {
    let mut b = Vec::with_capacity((W * H * 3) as usize);
    for y in 0..H {
        for x in 0..W {
            let px = if on_plane(x, y) {
                let check = ((x / 4) + (y / 4)) % 2 == 0;
                let v = if check { 220 } else { 40 };
                [v, (x * 255 / W) as u8, (y * 3) as u8]
            } else {
                let sun = (x as i32 - 70).pow(2) + (y as i32 - 8).pow(2) < 25;
                if sun {
                    [255, 250, 210]
                } else {
                    [(60 + x) as u8, (120 + y) as u8, (200 + y / 2) as u8]
                }
            };
            b.extend_from_slice(&px);
        }
    }
    b
}

struct Input {
    reference: parallax_synth::Reference,
    desc: CameraDesc,
    bytes: Vec<u8>,
}

/// Writes the PNG + EXR pair and reads it back as a reference (identity pose, 60 degrees).
fn load(tag: &str) -> Input {
    let bytes = input_bytes();
    let dir = std::env::temp_dir().join(format!("parallax-input-sky-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (cpath, dpath) = (dir.join("color.png"), dir.join("depth.exr"));
    // Linear values whose sRGB encoding is `bytes`: a PNG writer without tone curve
    // reproduces them (checked below by reading the file back).
    let linear: Vec<Vec3> = bytes
        .chunks_exact(3)
        .map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32).map(|v| srgb_eotf(v / 255.0)))
        .collect();
    let img = Image::from_vec(W, H, linear).unwrap();
    write_png(&cpath, &img, &ToneMapping::default()).unwrap();
    let desc = input_desc(Intrinsics::FovYDeg(60.0), H, None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    // The plane z = -PLANE_Z in camera space: view depth PLANE_Z everywhere on it. The sky's
    // "no depth" comes in the three spellings tools write.
    let depth: Vec<f32> = (0..W * H)
        .map(|i| {
            let (x, y) = (i % W, i / W);
            if on_plane(x, y) {
                PLANE_Z
            } else {
                [f32::INFINITY, 0.0, f32::NAN][(i % 3) as usize]
            }
        })
        .collect();
    write_exr(&dpath, W, H, &[("Z", &depth)]).unwrap();
    let color = read_color(&cpath).unwrap();
    assert_eq!(
        to_srgb8(&color, &ToneMapping::default()),
        bytes,
        "PNG round trip"
    );
    let depth = read_depth(&dpath).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(cam.width, W);
    let reference = reference_from_images(color, &depth, &desc, Vec3::ZERO).unwrap();
    Input {
        reference,
        desc,
        bytes,
    }
}

fn synth(m: Method, r: &parallax_synth::Reference) -> Synthesizer {
    Synthesizer::build(m, r, &MethodOptions::default()).unwrap()
}

#[test]
fn identity_warp_returns_the_input_png_bytes() {
    let input = load("identity");
    let r = &input.reference;
    // The tracers only: the mesh warp (a baseline) loses the outermost half pixel of the
    // plane (its triangles join pixel centres; 105 pixels here).
    for m in [Method::QuadTree, Method::Dda, Method::Brute] {
        let v = synth(m, r).view(r, &r.camera).unwrap();
        let out = to_srgb8(&v.image, &ToneMapping::default());
        let differ = out
            .chunks_exact(3)
            .zip(input.bytes.chunks_exact(3))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(differ, 0, "{m}: {differ} pixels differ");
    }
}

#[test]
fn sky_pixels_keep_their_colour_after_a_warp() {
    let input = load("sky");
    let r = &input.reference;
    // The right eye of a 0.3 m baseline and a camera turned by 3 degrees.
    let eye = Vec3::new(0.3, 0.05, 0.0);
    let turn = glam::Quat::from_rotation_y(3f32.to_radians());
    let target_desc = CameraDesc::new(eye, eye + turn * Vec3::NEG_Z, Vec3::Y, 60.0);
    let target = Pinhole::new(&target_desc, W, H).unwrap();
    let reference_cam = Pinhole::new(&input.desc, W, H).unwrap();
    let linear = r.colors[0].data();
    for m in [Method::QuadTree, Method::Dda, Method::Mesh] {
        let v = synth(m, r).view(r, &target).unwrap();
        let (mut checked, mut black) = (0, 0);
        for y in 0..H {
            for x in 0..W {
                let i = (y * W + x) as usize;
                if v.kinds[i] != HitKind::Miss {
                    continue;
                }
                let c = v.image.data()[i];
                if c.max_element() < 1e-3 {
                    black += 1;
                }
                // The direction of this pixel seen from the reference: where the 2x2 pixel
                // centres around it are all sky, the colour is their bilinear blend.
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let dir = target.frame.dir_to_world(target.camera_dir(film));
                let cdir = reference_cam.frame.basis.transpose() * dir;
                let Some(f) = reference_cam.film_of_camera_point(cdir) else {
                    continue;
                };
                let p = f - Vec2::splat(0.5);
                let (fx, fy) = (p.x.floor(), p.y.floor());
                if fx < 0.0 || fy < 0.0 || fx + 1.0 >= W as f32 || fy + 1.0 >= H as f32 {
                    continue;
                }
                let (x0, y0) = (fx as u32, fy as u32);
                let corners = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
                if corners.iter().any(|&(cx, cy)| on_plane(cx, cy)) {
                    continue;
                }
                let (tx, ty) = (p.x - fx, p.y - fy);
                let at = |(cx, cy): (u32, u32)| linear[(cy * W + cx) as usize];
                let want = (at(corners[0]) * (1.0 - tx) + at(corners[1]) * tx) * (1.0 - ty)
                    + (at(corners[2]) * (1.0 - tx) + at(corners[3]) * tx) * ty;
                assert!(
                    (c - want).abs().max_element() < 1e-3,
                    "{m}: ({x},{y}) {c} vs sky at {f} {want}"
                );
                checked += 1;
            }
        }
        let misses = v.kinds.iter().filter(|k| **k == HitKind::Miss).count();
        assert_eq!(black, 0, "{m}: {black} black sky pixels of {misses}");
        // Half of the image is sky; a turn of 3 degrees keeps most of it in view.
        assert!(misses > (W * H / 4) as usize, "{m}: {misses} misses");
        assert!(
            checked > (W * H / 5) as usize,
            "{m}: only {checked} sky pixels checked"
        );
    }
}
