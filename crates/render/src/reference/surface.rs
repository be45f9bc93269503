//! What a hit means: position, normals, texture coordinates and material at the hit point.

use glam::{Vec2, Vec3};
use parallax_bvh::Hit;
use parallax_core::Ray;
use parallax_scene::{Material, Scene};

/// The surface seen by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint<'a> {
    pub position: Vec3,
    /// Geometric normal, flipped to face the incoming ray.
    pub geometric_normal: Vec3,
    /// Interpolated shading normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    pub uv: Vec2,
    pub albedo: Vec3,
    pub material: &'a Material,
    pub material_id: u32,
    /// True when the ray hit the side the triangle's winding calls the front.
    pub front_face: bool,
}

impl<'a> SurfacePoint<'a> {
    pub fn new(scene: &'a Scene, ray: &Ray, hit: &Hit) -> Self {
        let prim = hit.prim as usize;
        let mesh = &scene.mesh;
        let position = ray.at(hit.t);
        let ng = mesh.geometric_normal(prim);
        let front_face = ng.dot(ray.dir) < 0.0;
        let flip = if front_face { 1.0 } else { -1.0 };
        let mut ns = mesh.shading_normal(prim, hit.u, hit.v) * flip;
        // Keep the shading normal in the hemisphere of the geometric one (no black facets).
        if ns.dot(ng * flip) <= 0.0 {
            ns = ng * flip;
        }
        let uv = mesh.uv(prim, hit.u, hit.v);
        let material_id = mesh.material_ids[prim];
        let material = &scene.materials[material_id as usize];
        let mut albedo = material.base_color;
        if let Some(t) = material.base_color_texture {
            albedo *= scene.textures[t as usize].sample(uv);
        }
        Self {
            position,
            geometric_normal: ng * flip,
            shading_normal: ns,
            uv,
            albedo,
            material,
            material_id,
            front_face,
        }
    }

    /// An origin for a ray leaving the surface towards `dir`: offset along the geometric
    /// normal by an amount that scales with the magnitude of the position (float spacing),
    /// so secondary rays do not re-hit the surface they start on.
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        let scale = 1e-4 * self.position.abs().max_element().max(1.0);
        let side = if dir.dot(self.geometric_normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        self.position + self.geometric_normal * (scale * side)
    }
}
