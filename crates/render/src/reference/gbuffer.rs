//! Primary visibility from BVH rays: the reference G-buffer.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_core::image::{GBuffer, GSample};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};

use super::surface::SurfacePoint;
use crate::tiles::for_each_pixel;

/// The G-buffer sample of the ray through the centre of pixel `(x, y)` and the lens centre.
pub(crate) fn gsample(scene: &Scene, bvh: &Bvh, camera: &Camera, x: u32, y: u32) -> GSample {
    let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
    let Some(cr) = camera.generate_ray(film, Vec2::splat(0.5), 1) else {
        return GSample::MISS;
    };
    let Some(hit) = bvh.closest_hit(&cr.ray) else {
        return GSample::MISS;
    };
    let s = SurfacePoint::new(scene, &cr.ray, &hit);
    GSample {
        depth: cr.view_depth(hit.t),
        position: s.position,
        normal: s.shading_normal,
        albedo: s.albedo,
        material_id: s.material_id,
        primitive_id: hit.prim,
        barycentrics: Vec2::new(hit.u, hit.v),
    }
}

/// Writes per-pixel samples into a planar G-buffer.
pub(crate) fn pack(width: u32, height: u32, samples: &[GSample]) -> GBuffer {
    let mut g = GBuffer::new(width, height).expect("size validated by the camera");
    for (i, s) in samples.iter().enumerate() {
        g.set_at(i, *s);
    }
    g
}

/// The reference G-buffer of `camera`: one BVH primary ray through every pixel centre (lens
/// centre for thin lenses, green channel for per-channel distortion).
pub fn render_gbuffer(scene: &Scene, bvh: &Bvh, camera: &Camera) -> GBuffer {
    let (w, h) = (camera.width(), camera.height());
    let mut samples = vec![GSample::MISS; w as usize * h as usize];
    for_each_pixel(
        w,
        h,
        &mut samples,
        |x, y, out| *out = gsample(scene, bvh, camera, x, y),
        &|_| {},
    );
    pack(w, h, &samples)
}
