//! The cube maps of one reflection set-up ([`CubeMaps`]): the paper's one cube map at the
//! camera ([`super::cube`]) or, as an option that is not the paper's method, one per
//! reflective object ([`super::objects`]); the reflectors built on them and the matching BVH
//! truth ([`super::truth`]), so `reflect` and `bench reflect` build either the same way.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_scene::{CameraDesc, Scene};

use super::Reflector;
use super::cube::{CubeReflector, CubeTimes, ReflectionCube};
use super::objects::{CubeAt, CubeCentres, ObjectCubeReflector, ObjectCubes};
use super::truth::{BvhReflector, TruthColour};
use crate::SynthError;
use crate::method::{Method, MethodOptions};

/// The captured cube maps of a [`CubeAt`] placement.
#[derive(Clone, Debug)]
pub enum CubeMaps {
    Camera(ReflectionCube),
    Objects(ObjectCubes),
}

impl CubeMaps {
    /// Captures the cube map(s) of `at`: at `eye` (world-aligned faces) or at each reflective
    /// object of `scene` (an error when it has none).
    pub fn capture(
        scene: &Scene,
        bvh: &Bvh,
        at: CubeAt,
        eye: Vec3,
        face: u32,
        layers: usize,
        seed: u64,
    ) -> Result<Self, SynthError> {
        Ok(match at {
            CubeAt::Camera => {
                let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0);
                Self::Camera(ReflectionCube::capture(
                    scene, bvh, &desc, face, layers, seed,
                )?)
            }
            CubeAt::Objects => Self::Objects(ObjectCubes::capture(scene, bvh, face, layers, seed)?),
        })
    }

    /// The placement.
    pub fn at(&self) -> CubeAt {
        match self {
            Self::Camera(_) => CubeAt::Camera,
            Self::Objects(_) => CubeAt::Objects,
        }
    }

    /// The per-object centres (`None` for the camera's cube map).
    pub fn centres(&self) -> Option<&CubeCentres> {
        match self {
            Self::Camera(_) => None,
            Self::Objects(o) => Some(&o.centres),
        }
    }

    /// Number of cube maps.
    pub fn count(&self) -> usize {
        match self {
            Self::Camera(_) => 1,
            Self::Objects(o) => o.cubes.len(),
        }
    }

    /// `method`'s reflector on these cube maps (surfaces `thickness` thick, as
    /// [`parallax_screen::CubeMapTracer::thickness`]) and its `T_cm`.
    pub fn reflector<'a>(
        &'a self,
        scene: &'a Scene,
        method: Method,
        opts: &MethodOptions,
        thickness: Option<f32>,
    ) -> Result<(Box<dyn Reflector + 'a>, CubeTimes), SynthError> {
        Ok(match self {
            Self::Camera(c) => {
                let mut r = CubeReflector::build(scene, c, method, opts)?;
                r.tracer.thickness = thickness;
                let t = r.times;
                (Box::new(r), t)
            }
            Self::Objects(o) => {
                let mut r = ObjectCubeReflector::build(scene, o, method, opts)?;
                r.set_thickness(thickness);
                let t = r.times;
                (Box::new(r), t)
            }
        })
    }

    /// The BVH truth of these cube maps' reflections with colouring `c` ([`super::truth`]):
    /// towards the camera's `eye`, or towards the centre of the object cube a ray is traced
    /// in.
    pub fn truth<'a>(
        &'a self,
        scene: &'a Scene,
        bvh: &'a Bvh,
        eye: Vec3,
        seed: u64,
        c: TruthColour,
    ) -> BvhReflector<'a> {
        let t = BvhReflector::new(scene, bvh, eye, seed).coloured(c);
        match self.centres() {
            Some(centres) => t.with_centres(centres),
            None => t,
        }
    }
}
