//! One cube map per reflective object — **not the paper's method** (Widmer et al. 2015, §5.4,
//! place one cube map at the camera: [`super::cube`], the default). This is the set-up of
//! Umenhoffer et al. 2007, which §5.4 builds on ("create a cube map at the center of a
//! reflective object"), and which the paper's Fig. 12 compares with; here every cube face
//! still gets the paper's screen-space structure (quad-tree or DDA), so the rays are
//! reprojected through each object's own cube map. Option `reflect --cube-at objects`.
//!
//! **Why.** Reflection rays start on the reflector's surface, so a cube map at the reflector
//! sees nearly everything its rays reach, including the sides of boxes, pillars and balls
//! that face away from the camera (no camera cube map can hold them: its layers keep the
//! sides facing its centre, `docs/notes/synth.md`) and the ground hidden from the camera
//! behind them.
//!
//! **Objects.** A reflective object is a mesh object ([`parallax_scene::mesh::ObjectRange`])
//! with a triangle whose material has a reflection lobe ([`Lobe::of`]: mirrors, glossy
//! metals). Its cube map's centre is the centre of the object's bounding box.
//!
//! **Contents.** Each cube map holds the whole scene (the other reflective objects included:
//! a multi-bounce ray that reaches another object continues in that object's cube map)
//! except the object's own triangles that face away from its centre. A convex object around
//! its centre (a mirror ball) thereby leaves itself out entirely — a ray leaving a convex
//! surface cannot meet it again (Fig. 11's "no self-reflections") — while a concave one (the
//! cylindrical mirror) keeps its reflecting inner side and so its self-reflections. Hidden
//! layers hold front faces as in the camera cube map ([`crate::layers::HiddenLayers`]).
//!
//! **Tracing.** A ray leaving a triangle of object `M` ([`Reflector::trace_from`]) is traced
//! in `M`'s cube map ([`CubeReflector`]); a ray leaving a triangle of no reflective object
//! (the renderer makes none) takes the cube map whose centre is nearest its origin. The hit
//! carries the cube's index ([`SurfaceHit::cube`]) for its colour lookup, the extra samples'
//! plane lookups and the truth's colouring ([`super::truth`]). Reflection rays start where
//! they start for the camera cube map (offsets measured from the camera, so every reflector
//! and truth sees the same rays).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `face` | u32 | (caller) | face size of every object's cube map, as [`ReflectionCube::capture`] |
//! | `layers` | usize | (caller) | layers per face, as [`ReflectionCube::capture`] |
//! | [`CubeAt`] | enum | `camera` | `camera` (the paper) or `objects` (this module) |
//!
//! **Cost.** `T_cm` is one cube map per reflective object (three on `mirrors-open`: three
//! times the capture, shading and build of the camera's).

use std::fmt;
use std::str::FromStr;

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::{Ray, WorldStats};
use parallax_scene::{CameraDesc, Scene};
use serde::Serialize;

use super::cube::{CubeReflector, CubeTimes, ReflectionCube};
use super::lobe::Lobe;
use super::{Reflector, SurfaceHit};
use crate::SynthError;
use crate::method::{Method, MethodOptions};

/// Where the reflection renderer's cube maps are (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum CubeAt {
    /// One cube map at the camera's eye (Widmer et al. 2015, §5.4).
    #[default]
    Camera,
    /// One cube map at the centre of each reflective object (Umenhoffer et al. 2007; not the
    /// paper's method).
    Objects,
}

impl fmt::Display for CubeAt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CubeAt::Camera => "camera",
            CubeAt::Objects => "objects",
        })
    }
}

impl FromStr for CubeAt {
    type Err = SynthError;

    fn from_str(s: &str) -> Result<Self, SynthError> {
        match s {
            "camera" => Ok(CubeAt::Camera),
            "objects" => Ok(CubeAt::Objects),
            _ => Err(SynthError::Invalid(format!(
                "cube map placement must be camera or objects, got {s:?}"
            ))),
        }
    }
}

/// No reflective object owns the triangle.
const NONE: u16 = u16::MAX;

/// The reflective objects of a scene: their names, cube-map centres, and which object owns
/// each triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeCentres {
    pub names: Vec<String>,
    pub centres: Vec<Vec3>,
    /// Per scene triangle: the index of its reflective object, `u16::MAX` for none.
    of_prim: Vec<u16>,
}

impl CubeCentres {
    /// The reflective objects of `scene` (module docs); an error when it has none.
    pub fn of_scene(scene: &Scene) -> Result<Self, SynthError> {
        let mesh = &scene.mesh;
        let reflects = |t: usize| {
            let m = mesh.material_ids.get(t).copied().unwrap_or(u32::MAX);
            scene
                .materials
                .get(m as usize)
                .is_some_and(|m| Lobe::of(m, Vec3::ONE).is_some())
        };
        let mut out = Self {
            names: Vec::new(),
            centres: Vec::new(),
            of_prim: vec![NONE; mesh.triangle_count()],
        };
        for o in &mesh.objects {
            let tris = o.first_triangle as usize..(o.first_triangle + o.triangle_count) as usize;
            if !tris.clone().any(reflects) {
                continue;
            }
            let k = out.centres.len();
            if k >= NONE as usize {
                return Err(SynthError::Invalid(format!(
                    "at most {} reflective objects get a cube map each",
                    NONE
                )));
            }
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for t in tris.clone() {
                for p in mesh.triangle(t) {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                out.of_prim[t] = k as u16;
            }
            out.names.push(o.name.clone());
            out.centres.push(0.5 * (lo + hi));
        }
        if out.centres.is_empty() {
            return Err(SynthError::Invalid(format!(
                "cube maps at the reflective objects: scene {:?} has no reflective object (a mesh object with a mirror or glossy metal material)",
                scene.name
            )));
        }
        Ok(out)
    }

    /// The object owning triangle `prim`, if reflective.
    pub fn object_of(&self, prim: u32) -> Option<usize> {
        match self.of_prim.get(prim as usize) {
            Some(&k) if k != NONE => Some(k as usize),
            _ => None,
        }
    }

    /// The cube a ray leaving triangle `from` at `origin` is traced in (module docs).
    pub fn cube_for(&self, from: u32, origin: Vec3) -> u16 {
        if let Some(k) = self.object_of(from) {
            return k as u16;
        }
        let d = |c: &Vec3| (*c - origin).length_squared();
        (0..self.centres.len())
            .min_by(|&a, &b| d(&self.centres[a]).total_cmp(&d(&self.centres[b])))
            .unwrap_or(0) as u16
    }
}

/// The cube maps of every reflective object of a scene (module docs).
#[derive(Clone, Debug)]
pub struct ObjectCubes {
    pub centres: CubeCentres,
    /// `cubes[k]`: object `k`'s cube map.
    pub cubes: Vec<ReflectionCube>,
}

impl ObjectCubes {
    /// Captures and shades `layers` layers of six `face x face` faces at the centre of every
    /// reflective object of `scene` (module docs: contents).
    pub fn capture(
        scene: &Scene,
        bvh: &Bvh,
        face: u32,
        layers: usize,
        seed: u64,
    ) -> Result<Self, SynthError> {
        Self::capture_at(
            scene,
            bvh,
            CubeCentres::of_scene(scene)?,
            face,
            layers,
            seed,
        )
    }

    /// [`Self::capture`] with the cube maps at `centres` (e.g. moved by the caller).
    pub fn capture_at(
        scene: &Scene,
        bvh: &Bvh,
        centres: CubeCentres,
        face: u32,
        layers: usize,
        seed: u64,
    ) -> Result<Self, SynthError> {
        let mesh = &scene.mesh;
        let mut cubes = Vec::with_capacity(centres.centres.len());
        for (k, &c) in centres.centres.iter().enumerate() {
            let keep = |prim: u32| {
                if centres.object_of(prim) != Some(k) {
                    return true;
                }
                let [p0, _, _] = mesh.triangle(prim as usize);
                mesh.geometric_normal(prim as usize).dot(c - p0) > 0.0
            };
            let desc = CameraDesc::new(c, c - Vec3::Z, Vec3::Y, 90.0);
            cubes.push(ReflectionCube::capture_only(
                scene,
                bvh,
                &desc,
                face,
                layers,
                seed,
                Some(&keep),
            )?);
        }
        Ok(Self { centres, cubes })
    }

    /// Bytes of every cube's layers and colours.
    pub fn bytes(&self) -> usize {
        self.cubes.iter().map(ReflectionCube::bytes).sum()
    }
}

/// Reflection rays through each reflective object's own cube map (module docs).
pub struct ObjectCubeReflector<'a> {
    pub cubes: &'a ObjectCubes,
    /// `reflectors[k]`: object `k`'s cube map and its per-face structures.
    pub reflectors: Vec<CubeReflector<'a>>,
    /// `T_cm` of all the cube maps.
    pub times: CubeTimes,
}

impl<'a> ObjectCubeReflector<'a> {
    /// [`CubeReflector::build`] on every object's cube map.
    pub fn build(
        scene: &'a Scene,
        cubes: &'a ObjectCubes,
        method: Method,
        opts: &MethodOptions,
    ) -> Result<Self, SynthError> {
        let reflectors = cubes
            .cubes
            .iter()
            .map(|c| CubeReflector::build(scene, c, method, opts))
            .collect::<Result<Vec<_>, _>>()?;
        let times = reflectors
            .iter()
            .fold(CubeTimes::default(), |a, r| CubeTimes {
                capture_ms: a.capture_ms + r.times.capture_ms,
                shade_ms: a.shade_ms + r.times.shade_ms,
                build_ms: a.build_ms + r.times.build_ms,
            });
        Ok(Self {
            cubes,
            reflectors,
            times,
        })
    }

    /// Sets the relative thickness of every cube map's surfaces
    /// ([`parallax_screen::CubeMapTracer::thickness`]).
    pub fn set_thickness(&mut self, thickness: Option<f32>) {
        for r in &mut self.reflectors {
            r.tracer.thickness = thickness;
        }
    }
}

impl Reflector for ObjectCubeReflector<'_> {
    fn name(&self) -> String {
        format!("{}@objects", self.reflectors[0].name())
    }

    fn scene(&self) -> &Scene {
        self.reflectors[0].scene()
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        self.trace_from(ray, u32::MAX, stats)
    }

    fn trace_from(&self, ray: &Ray, from: u32, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let cube = self.cubes.centres.cube_for(from, ray.origin);
        let hit = self.reflectors[cube as usize].trace(ray, stats)?;
        Some(SurfaceHit { cube, ..hit })
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        self.reflectors[hit.cube as usize].colour(ray, hit)
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, sigma: f32) -> (Vec3, f32) {
        self.reflectors[hit.cube as usize].plane_sample(hit, ray, sigma)
    }
}
