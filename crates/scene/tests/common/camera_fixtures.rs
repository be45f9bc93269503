//! The camera the camera tests share (a fixed pose, 48-pixel-wide films) and their helpers:
//! film sampling, projection back to film, coverage (`#[path]`-included).
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use parallax_scene::CameraDesc;
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind};

pub const W: u32 = 48;
pub const H: u32 = 32;
pub const LENS_CENTRE: Vec2 = Vec2::splat(0.5);

pub fn desc() -> CameraDesc {
    CameraDesc::new(
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(-0.5, 1.0, -2.0),
        Vec3::Y,
        55.0,
    )
}

pub fn build(kind: ModelKind, desc: &CameraDesc, opts: &CameraOptions) -> Camera {
    // Composite models take the size of one view; keep every film 48 px wide.
    let (w, h) = match kind {
        ModelKind::Stereo => (W / 2, H),
        ModelKind::Cube => (W / 6, H),
        _ => (W, H),
    };
    Camera::new(kind, desc, w, h, opts).unwrap()
}

/// splitmix64: a tiny deterministic generator for test positions.
pub struct Rng(pub u64);
impl Rng {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn unit_vector(&mut self) -> Vec3 {
        let z = 2.0 * self.next_f32() - 1.0;
        let phi = std::f32::consts::TAU * self.next_f32();
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// Pixel centres and random positions over the whole film.
pub fn film_positions(cam: &Camera, seed: u64) -> Vec<Vec2> {
    let (w, h) = (cam.width(), cam.height());
    let mut v = Vec::new();
    for y in 0..h {
        for x in 0..w {
            v.push(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        }
    }
    let mut rng = Rng(seed);
    for _ in 0..400 {
        v.push(Vec2::new(
            rng.next_f32() * w as f32,
            rng.next_f32() * h as f32,
        ));
    }
    v
}

/// The channel `project` must use for film position `film` and ray channel `c`.
pub fn project_channel(cam: &Camera, film: Vec2, c: usize) -> usize {
    match cam {
        Camera::Stereo(_) => usize::from(film.x >= (cam.width() / 2) as f32),
        _ => c,
    }
}

/// Film distance, modulo the width for a full-circle equirect.
pub fn film_distance(cam: &Camera, a: Vec2, b: Vec2) -> f32 {
    let mut d = (a - b).abs();
    if let Camera::Equirect(e) = cam
        && (e.fov.x - std::f32::consts::TAU).abs() < 1e-6
    {
        d.x = d.x.min(cam.width() as f32 - d.x);
    }
    d.length()
}

/// Longitude is undefined at the poles of a full equirect: positions within 0.25 px of them
/// are skipped (a 1e-7 direction error moves x by more than 1e-3 px there).
pub fn near_pole(cam: &Camera, film: Vec2) -> bool {
    matches!(cam, Camera::Equirect(e) if (e.fov.y - std::f32::consts::PI).abs() < 1e-6)
        && (film.y < 0.25 || film.y > cam.height() as f32 - 0.25)
}

pub fn is_covered(cam: &Camera, film: Vec2) -> bool {
    match cam {
        Camera::Fisheye(f) => f.normalized(film).length_squared() <= 1.0,
        _ => true,
    }
}
