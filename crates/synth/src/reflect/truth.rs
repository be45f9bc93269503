//! The ground truth of the reflection renderer: the same reflection rays traced exactly with
//! the BVH ([`BvhReflector`]).
//!
//! A hit is the exact triangle hit with the scene's shading normal, material and texture. Its
//! **colour** ([`TruthColour`]) is by default what a cube-map sample of that point holds: the
//! reference shader's radiance along the ray from the cube map's eye to the point, with the
//! same fixed random stream ([`super::cube::ReflectionCube`]), so the score measures where
//! the rays land, not that a cube map stores one view-independent colour per surface point.
//! With one cube map per reflective object ([`super::CubeAt::Objects`], not the paper's
//! set-up) "the cube map's eye" is the centre of the cube the ray was traced in: that of
//! the object the ray leaves ([`CubeCentres`]). [`TruthColour::AlongTheRay`] colours every
//! hit by the radiance it sends back along the reflection ray instead — the physical
//! reflection, the same image whatever cube map the reflector uses (for a side of a box
//! facing away from the cube's centre the default rule gives that side's shading seen from
//! the centre, not a physical value). Extra samples are traced as full paths (every direction
//! of the lobe exactly: what the cube map's plane lookups approximate).

use glam::Vec3;
use parallax_bvh::{Bvh, Hit};
use parallax_core::{Ray, WorldStats};
use parallax_render::reference::shade::Shader;
use parallax_render::reference::surface::SurfacePoint;
use parallax_render::score::Shading;
use parallax_scene::Scene;
use serde::Serialize;

use super::objects::CubeCentres;
use super::{Reflector, SurfaceHit};

/// How the truth colours a hit (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum TruthColour {
    /// The radiance the hit sends towards the centre of the cube map the ray was traced in
    /// (what a cube-map sample of it holds): the bench's `PSNR refl.`.
    #[default]
    TowardsCube,
    /// The radiance the hit sends back along the reflection ray (physical): the bench's
    /// `PSNR refl. phys.` (`--physical-truth`).
    AlongTheRay,
}

/// Reflection rays traced exactly (module docs).
pub struct BvhReflector<'a> {
    pub shader: Shader<'a>,
    /// The cube map's eye: colours are the radiance towards it.
    pub eye: Vec3,
    pub seed: u64,
    pub colouring: TruthColour,
    /// One cube map per reflective object (`None`: the one at `eye`): which cube a ray leaving
    /// a triangle is traced in and where its centre is.
    pub centres: Option<&'a CubeCentres>,
}

impl<'a> BvhReflector<'a> {
    pub fn new(scene: &'a Scene, bvh: &'a Bvh, eye: Vec3, seed: u64) -> Self {
        Self {
            shader: Shader::new(scene, bvh),
            eye,
            seed,
            colouring: TruthColour::TowardsCube,
            centres: None,
        }
    }

    /// This truth with colouring `c`.
    pub fn coloured(self, c: TruthColour) -> Self {
        Self {
            colouring: c,
            ..self
        }
    }

    /// This truth for the per-object cube maps of `centres` (module docs).
    pub fn with_centres(self, centres: &'a CubeCentres) -> Self {
        Self {
            centres: Some(centres),
            ..self
        }
    }

    /// The radiance of `hit` seen along `ray` (from `ray.origin`).
    fn radiance_along(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        let h = Hit {
            prim: hit.prim,
            t: hit.t,
            u: hit.barycentrics.x,
            v: hit.barycentrics.y,
        };
        let mut rng = Shading::Fixed.rng(self.seed, 0, 0, 0);
        let mut rays = 0;
        self.shader.radiance_from_hit(*ray, h, &mut rng, &mut rays)
    }
}

impl Reflector for BvhReflector<'_> {
    fn name(&self) -> String {
        "bvh".into()
    }

    fn scene(&self) -> &Scene {
        self.shader.scene
    }

    fn trace_from(&self, ray: &Ray, from: u32, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let hit = self.trace(ray, stats)?;
        let cube = self.centres.map_or(0, |c| c.cube_for(from, ray.origin));
        Some(SurfaceHit { cube, ..hit })
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
            cube: 0,
        })
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        if self.colouring == TruthColour::AlongTheRay {
            return self.radiance_along(ray, hit);
        }
        let eye = self
            .centres
            .map_or(self.eye, |c| c.centres[hit.cube as usize]);
        let to = hit.position - eye;
        let dist = to.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return self.shader.scene.environment;
        }
        let ray = Ray::new(eye, to / dist);
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
