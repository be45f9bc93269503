//! The cube map of the reflection renderer (Widmer et al. 2015, §5.4: "we generate a cube map
//! at the camera location, and create our adaptive data structure for each face of the cube
//! map ... we simply render the scene six times, once to each cube map face"): six 90° faces
//! of `N` colour + depth layers around the camera eye, and the [`Reflector`] that traces
//! reflection rays through one screen-space structure per face
//! ([`parallax_screen::CubeMapTracer`]: the quad-tree, or the DDA baseline).
//!
//! Each face is captured and shaded as a view-synthesis reference
//! ([`crate::layers`]: hidden layers of front faces only, every sample shaded by the reference
//! shader along the face's pixel ray with one fixed random stream), so a sample's colour is
//! the radiance its surface point sends towards the eye.
//!
//! **Answers.** A hit (or the inpainted occlusion-volume answer, [`parallax_screen::cubemap`])
//! is the layer sample of its face pixel: position on the ray, the sample's normal, material
//! and albedo, and its colour read at that pixel (nearest; no resampling between pixels).
//! **Extra samples** ([`Reflector::plane_sample`]): a ray of the same lobe is intersected with
//! the tangent plane of its traced twin's hit sample only (the hit pixel's plane stands in for
//! the quad-tree leaf's: a leaf merges pixel planes within the tolerances `γ`), the
//! intersection is looked up in the cube map (the face of its direction, the hit's layer) and
//! weighted by `exp(-((d - d_s) / d_s)² / σ²)` — `d` its view depth in that face, `d_s` the
//! sample's depth there — as depth of field weighs its secondary samples
//! ([`crate::dof::secondary`]).

use std::time::Instant;

use glam::{UVec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::image::GBuffer;
use parallax_core::{Image, Ray, Rgb, WorldStats, WorldTracer};
use parallax_render::score::Shading;
use parallax_scene::camera::{CameraModel, CubeMap};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{CubeMapTracer, TraceStats};
use serde::Serialize;

use super::{Reflector, SurfaceHit};
use crate::SynthError;
use crate::layers::{HiddenLayers, MAX_LAYERS, shaded_layers};
use crate::method::{Method, MethodOptions, build_tracer};

/// Largest cube face accepted (pixels on a side).
pub const MAX_FACE: u32 = 4096;

/// Milliseconds of building a cube map and its structure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct CubeTimes {
    /// Rasterizing the six faces' layers.
    pub capture_ms: f64,
    /// Shading their samples.
    pub shade_ms: f64,
    /// Building the six face structures (set by [`CubeReflector::build`]).
    pub build_ms: f64,
}

impl CubeTimes {
    /// `T_cm`: capture + shade + build.
    pub fn total_ms(&self) -> f64 {
        self.capture_ms + self.shade_ms + self.build_ms
    }
}

/// Six faces of colour + depth layers around one eye.
#[derive(Clone, Debug)]
pub struct ReflectionCube {
    pub cube: CubeMap,
    /// `layers[face][k]`.
    pub layers: Vec<Vec<GBuffer>>,
    /// `colours[face][k]`: linear colour of every sample (environment where uncovered).
    pub colours: Vec<Vec<Image<Rgb>>>,
    pub background: Rgb,
    pub times: CubeTimes,
}

impl ReflectionCube {
    /// Captures and shades `layers` layers of the six `face x face` faces around `eye.eye`
    /// (orientation of `eye` unused: faces are world-axis aligned).
    pub fn capture(
        scene: &Scene,
        bvh: &Bvh,
        eye: &CameraDesc,
        face: u32,
        layers: usize,
        seed: u64,
    ) -> Result<Self, SynthError> {
        if !(1..=MAX_FACE).contains(&face) {
            return Err(SynthError::Invalid(format!(
                "cube face size must be in 1..={MAX_FACE} pixels, got {face}"
            )));
        }
        if !(1..=MAX_LAYERS).contains(&layers) {
            return Err(SynthError::Invalid(format!(
                "cube map layers must be in 1..={MAX_LAYERS}, got {layers}"
            )));
        }
        let cube = CubeMap::new(eye, face)?;
        let mut times = CubeTimes::default();
        let (mut all_layers, mut colours) = (Vec::with_capacity(6), Vec::with_capacity(6));
        for i in 0..6 {
            let camera = cube.face_camera(i);
            let (g, c, capture_ms, shade_ms) = shaded_layers(
                scene,
                bvh,
                &camera,
                layers,
                HiddenLayers::FrontFacing,
                Shading::Fixed,
                seed,
            )?;
            times.capture_ms += capture_ms;
            times.shade_ms += shade_ms;
            all_layers.push(g);
            colours.push(c);
        }
        Ok(Self {
            cube,
            layers: all_layers,
            colours,
            background: scene.environment,
            times,
        })
    }

    /// Bytes of the layers and colours.
    pub fn bytes(&self) -> usize {
        let g: usize = self.layers.iter().flatten().map(GBuffer::bytes).sum();
        let c: usize = self
            .colours
            .iter()
            .flatten()
            .map(|i| i.len() * std::mem::size_of::<Rgb>())
            .sum();
        g + c
    }
}

/// Reflection rays through the cube map's per-face structures (module docs).
pub struct CubeReflector<'a> {
    pub cube: &'a ReflectionCube,
    pub scene: &'a Scene,
    pub tracer: CubeMapTracer,
    pub method: Method,
    /// `T_cm` of this structure: the cube's capture and shading plus its build.
    pub times: CubeTimes,
}

impl<'a> CubeReflector<'a> {
    /// Builds `method`'s structure (`quadtree` or `dda`, with `opts` as for view synthesis)
    /// on every face of `cube`.
    pub fn build(
        scene: &'a Scene,
        cube: &'a ReflectionCube,
        method: Method,
        opts: &MethodOptions,
    ) -> Result<Self, SynthError> {
        if !matches!(method, Method::QuadTree | Method::Dda) {
            return Err(SynthError::Invalid(format!(
                "reflections trace the cube map with quadtree or dda, not {method}"
            )));
        }
        let t = Instant::now();
        let name = format!("cubemap-{method}");
        let tracer = CubeMapTracer::from_faces(
            &cube.cube,
            cube.layers.clone(),
            &name,
            |unit_cube, layers| build_tracer(method, unit_cube, layers, opts),
        )?;
        let times = CubeTimes {
            build_ms: t.elapsed().as_secs_f64() * 1e3,
            ..cube.times
        };
        Ok(Self {
            cube,
            scene,
            tracer,
            method,
            times,
        })
    }

    /// The layer sample at `pixel` of layer `layer` of face `face`, as a surface hit of
    /// `ray` at `t`.
    fn sample_hit(&self, ray: &Ray, face: usize, layer: usize, pixel: UVec2, t: f32) -> SurfaceHit {
        let g = &self.cube.layers[face][layer];
        let i = g.index(pixel.x, pixel.y);
        let n = g.normal[i];
        let n = if n.dot(ray.dir) > 0.0 { -n } else { n };
        SurfaceHit {
            t,
            position: ray.at(t),
            normal: n,
            material_id: g.material_id[i],
            albedo: g.albedo[i],
            prim: g.primitive_id[i],
            barycentrics: g.barycentrics[i],
            sample: Some((face as u8, layer as u8, pixel)),
        }
    }

    /// The view depth of `p` in face `face` (distance along the face's axis).
    fn face_depth(&self, face: usize, p: Vec3) -> f32 {
        let axis = parallax_scene::camera::cube::FACE_AXES[face];
        (p - self.cube.cube.eye).dot(axis)
    }
}

impl Reflector for CubeReflector<'_> {
    fn name(&self) -> String {
        self.tracer.name().to_string()
    }

    fn scene(&self) -> &Scene {
        self.scene
    }

    fn trace(&self, ray: &Ray, stats: &mut WorldStats) -> Option<SurfaceHit> {
        let mut s = TraceStats::default();
        let trace = self.tracer.trace(ray, &mut s);
        stats.rays += 1;
        stats.nodes += s.nodes_visited + if s.nodes_visited == 0 { s.steps } else { 0 };
        stats.tests += s.box_tests + s.plane_tests;
        stats.steps += trace.visits as u64;
        stats.truncated += (s.truncated > 0 || trace.truncated) as u64;
        let (layer, pixel, t) = trace.sample()?;
        if !(t > ray.t_min && t < ray.t_max) {
            return None;
        }
        Some(self.sample_hit(ray, trace.face, layer as usize, pixel, t))
    }

    fn colour(&self, hit: &SurfaceHit) -> Vec3 {
        match hit.sample {
            Some((f, l, p)) => {
                let c = &self.cube.colours[f as usize][l as usize];
                *c.get(p.x, p.y)
            }
            None => self.cube.background,
        }
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, sigma: f32) -> (Vec3, f32) {
        let Some((face, layer, pixel)) = hit.sample else {
            return (Vec3::ZERO, 0.0);
        };
        let g = &self.cube.layers[face as usize][layer as usize];
        let i = g.index(pixel.x, pixel.y);
        // The hit sample's tangent plane n . (x - p_s) = 0.
        let (p_s, n) = (g.position[i], g.normal[i]);
        let denom = n.dot(ray.dir);
        let t = n.dot(p_s - ray.origin) / denom;
        if !(t.is_finite() && t > ray.t_min && t < ray.t_max) {
            return (Vec3::ZERO, 0.0);
        }
        let x = ray.at(t);
        let dir = x - self.cube.cube.eye;
        let f = CubeMap::face_of(dir);
        let camera = &self.tracer.faces[f].camera;
        let Some(film) = camera.project(x, 0) else {
            return (Vec3::ZERO, 0.0);
        };
        let s = self.cube.cube.face_size();
        let q = UVec2::new(
            (film.x.max(0.0) as u32).min(s - 1),
            (film.y.max(0.0) as u32).min(s - 1),
        );
        let gq = &self.cube.layers[f][layer as usize];
        let j = gq.index(q.x, q.y);
        let d_s = gq.depth[j];
        if !(d_s.is_finite() && d_s > 0.0) {
            return (Vec3::ZERO, 0.0);
        }
        let rel = (self.face_depth(f, x) - d_s) / d_s;
        let w = (-(rel * rel) / (sigma * sigma)).exp();
        (*self.cube.colours[f][layer as usize].get(q.x, q.y), w)
    }
}
