//! The ground truth of the reflection renderer: the same reflection rays traced exactly with
//! the BVH ([`BvhReflector`]).
//!
//! A hit is the exact triangle hit with the scene's shading normal, material and texture. Its
//! **colour** is what a cube-map sample of that point holds: the reference shader's radiance
//! along the ray from the cube map's eye to the point, with the same fixed random stream
//! ([`super::cube::ReflectionCube`]), so the score measures where the rays land, not that a
//! cube map stores one view-independent colour per surface point. Extra samples are traced
//! as full paths (every direction of the lobe exactly: what the cube map's plane lookups
//! approximate).

use glam::Vec3;
use parallax_bvh::{Bvh, Hit};
use parallax_core::{Ray, WorldStats};
use parallax_render::reference::shade::Shader;
use parallax_render::reference::surface::SurfacePoint;
use parallax_render::score::Shading;
use parallax_scene::Scene;

use super::{Reflector, SurfaceHit};

/// Reflection rays traced exactly (module docs).
pub struct BvhReflector<'a> {
    pub shader: Shader<'a>,
    /// The cube map's eye: colours are the radiance towards it.
    pub eye: Vec3,
    pub seed: u64,
}

impl<'a> BvhReflector<'a> {
    pub fn new(scene: &'a Scene, bvh: &'a Bvh, eye: Vec3, seed: u64) -> Self {
        Self {
            shader: Shader::new(scene, bvh),
            eye,
            seed,
        }
    }
}

impl Reflector for BvhReflector<'_> {
    fn name(&self) -> String {
        "bvh".into()
    }

    fn scene(&self) -> &Scene {
        self.shader.scene
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        stats.rays += 1;
        let hit = self.shader.bvh.closest_hit(ray)?;
        let s = SurfacePoint::new(self.shader.scene, ray, &hit);
        Some(SurfaceHit {
            t: hit.t,
            position: s.position,
            normal: s.shading_normal,
            material_id: s.material_id,
            albedo: s.albedo,
            prim: hit.prim,
            barycentrics: glam::Vec2::new(hit.u, hit.v),
            sample: None,
            occlusion: false,
        })
    }

    fn colour(&self, _: &Ray, hit: &SurfaceHit) -> Vec3 {
        let to = hit.position - self.eye;
        let dist = to.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return self.shader.scene.environment;
        }
        let ray = Ray::new(self.eye, to / dist);
        let h = Hit {
            prim: hit.prim,
            t: dist,
            u: hit.barycentrics.x,
            v: hit.barycentrics.y,
        };
        let mut rng = Shading::Fixed.rng(self.seed, 0, 0, 0);
        let mut rays = 0;
        self.shader.radiance_from_hit(ray, h, &mut rng, &mut rays)
    }

    fn traces_extras(&self) -> bool {
        true
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, _: f32) -> (Vec3, f32) {
        (self.colour(ray, hit), 1.0)
    }
}
