//! Synthetic ray sets for comparing tracers beyond one view's secondary rays, each generated
//! from seeded streams (the same rays on every run and thread count):
//!
//! | set | origins | directions |
//! |---|---|---|
//! | `axis` | uniform in a box | one of `±x, ±y, ±z` |
//! | `random` | uniform in a box | uniform on the sphere |
//! | `surface` | uniform on the scene's triangles (by area), a hair off the surface on a random side | cosine-distributed around that side's normal |

use glam::Vec3;
use parallax_core::sampling::{Rng, warp};
use parallax_core::{Aabb, Ray};
use parallax_scene::Scene;

/// A synthetic ray set (module table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RaySet {
    Axis,
    Random,
    Surface,
}

impl RaySet {
    pub const ALL: [RaySet; 3] = [RaySet::Axis, RaySet::Random, RaySet::Surface];

    pub fn name(self) -> &'static str {
        match self {
            RaySet::Axis => "axis",
            RaySet::Random => "random",
            RaySet::Surface => "surface",
        }
    }
}

/// `n` rays of `set` (origins in `bounds` or on `scene`'s triangles), from stream `seed`.
pub fn ray_set(set: RaySet, scene: &Scene, bounds: &Aabb, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed, set as u64);
    let in_box = |rng: &mut Rng| {
        bounds.min + bounds.extent() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
    };
    match set {
        RaySet::Axis => (0..n)
            .map(|_| {
                let o = in_box(&mut rng);
                let k = rng.next_bounded(6) as usize;
                let mut d = Vec3::ZERO;
                d[k % 3] = if k < 3 { 1.0 } else { -1.0 };
                Ray::new(o, d)
            })
            .collect(),
        RaySet::Random => (0..n)
            .map(|_| {
                let o = in_box(&mut rng);
                Ray::new(o, warp::uniform_sphere(rng.next_vec2()))
            })
            .collect(),
        RaySet::Surface => surface_rays(scene, n, &mut rng),
    }
}

/// Rays leaving uniformly chosen points of the scene's surfaces (module table).
fn surface_rays(scene: &Scene, n: usize, rng: &mut Rng) -> Vec<Ray> {
    let mesh = &scene.mesh;
    // Area CDF over triangles.
    let mut cdf = Vec::with_capacity(mesh.indices.len());
    let mut total = 0f64;
    for p in 0..mesh.indices.len() {
        let [a, b, c] = mesh.triangle(p);
        total += 0.5 * (b - a).cross(c - a).length() as f64;
        cdf.push(total);
    }
    if !(total > 0.0) {
        return Vec::new();
    }
    (0..n)
        .map(|_| {
            let u = rng.next_f32() as f64 * total;
            let p = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
            let [a, b, c] = mesh.triangle(p);
            let side = if rng.next_f32() < 0.5 { 1.0 } else { -1.0 };
            let ng = mesh.geometric_normal(p) * side;
            let w = warp::uniform_triangle(rng.next_vec2());
            let q = a * w.x + b * w.y + c * w.z;
            let d = warp::cosine_hemisphere_around(ng, rng.next_vec2());
            // The same offset as the renderer's spawn points.
            let off = 1e-4 * q.abs().max_element().max(1.0);
            Ray::new(q + ng * off, d)
        })
        .collect()
}
