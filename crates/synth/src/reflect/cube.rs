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
//! and albedo. Its colour (asked only where a path ends) is the stereo warp's colour of that
//! answer in that face ([`crate::warp::RayWarp::colour`]: depth-aware bilinear resampling at
//! the hit, nearest-background fill of an occlusion volume).
//!
//! **Extra samples** ([`Reflector::plane_sample`]): a ray of the same lobe is intersected with
//! the tangent plane of its traced twin's hit sample only (the hit pixel's plane stands in for
//! the quad-tree leaf's: a leaf merges pixel planes within the tolerances `γ`), the
//! intersection is looked up in the cube map (the face of its direction, the hit's layer,
//! coloured as a hit there) and weighted by `exp(-((d - d_s) / d_s)² / σ²)` — `d` its view
//! depth in that face, `d_s` the sample's depth there — as depth of field weighs its
//! secondary samples ([`crate::dof::secondary`]).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `face` | u32 | (caller) | face size in pixels, `1..=`[`MAX_FACE`] |
//! | `layers` | usize | (caller) | colour + depth layers per face, `1..=8` |
//! | `method` | [`Method`] | (caller) | `quadtree` or `dda` per face, options as for view synthesis |

use std::time::Instant;

use glam::{UVec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::image::GBuffer;
use parallax_core::{Ray, Rgb, WorldStats, WorldTracer};
use parallax_raster::raster::TriangleFilter;
use parallax_render::score::Shading;
use parallax_scene::camera::{CameraModel, CubeMap};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::{CubeMapTracer, TraceStats};
use serde::Serialize;

use super::{Reflector, SurfaceHit};
use crate::SynthError;
use crate::layers::{HiddenLayers, MAX_LAYERS, Reference, ReferenceTimes, shaded_layers};
use crate::method::{Method, MethodOptions, build_tracer};
use crate::warp::{RayWarp, WarpOptions};
use parallax_screen::{CubeNear, TraceResult, UnitCube};

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
    /// Face `i` as a view-synthesis reference: its pinhole, layers, colours and unit cube (the
    /// depth range shared by all six faces, [`CubeMapTracer::depth_range`]).
    pub faces: Vec<Reference>,
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
        Self::capture_only(scene, bvh, eye, face, layers, seed, None)
    }

    /// [`Self::capture`] of the triangles `only` accepts (`None`: all; every layer, layer 0
    /// included): a reflective object's own cube map leaves the object's far side out
    /// ([`super::objects`]).
    pub fn capture_only(
        scene: &Scene,
        bvh: &Bvh,
        eye: &CameraDesc,
        face: u32,
        layers: usize,
        seed: u64,
        only: Option<TriangleFilter>,
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
        let mut shaded = Vec::with_capacity(6);
        for i in 0..6 {
            let camera = cube.face_camera(i);
            let (g, c, capture_ms, shade_ms) = shaded_layers(
                scene,
                bvh,
                &camera,
                layers,
                HiddenLayers::FrontFacing,
                only,
                Shading::Fixed,
                seed,
            )?;
            times.capture_ms += capture_ms;
            times.shade_ms += shade_ms;
            shaded.push((camera, g, c));
        }
        let depths: Vec<Vec<GBuffer>> = shaded.iter().map(|f| f.1.clone()).collect();
        let (near, far) = CubeMapTracer::depth_range(&depths)?;
        let faces = shaded
            .into_iter()
            .map(|(camera, layers, colors)| {
                Ok(Reference {
                    cube: UnitCube::new(&camera, near, far)?,
                    camera,
                    layers,
                    colors,
                    cube_near: CubeNear::Fitted,
                    background: scene.environment,
                    environment: None,
                    times: ReferenceTimes::default(),
                })
            })
            .collect::<Result<Vec<_>, SynthError>>()?;
        Ok(Self {
            cube,
            faces,
            background: scene.environment,
            times,
        })
    }

    /// Bytes of the layers and colours.
    pub fn bytes(&self) -> usize {
        self.faces
            .iter()
            .map(|f| {
                let g: usize = f.layers.iter().map(GBuffer::bytes).sum();
                g + f
                    .colors
                    .iter()
                    .map(|c| c.len() * std::mem::size_of::<Rgb>())
                    .sum::<usize>()
            })
            .sum()
    }
}

/// Reflection rays through the cube map's per-face structures (module docs).
pub struct CubeReflector<'a> {
    pub cube: &'a ReflectionCube,
    /// The colour lookup of each face (the stereo warp's: depth-aware bilinear resampling,
    /// nearest-background fill of occlusion volumes; no layer-0 guard).
    warps: Vec<RayWarp<'a>>,
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
            cube.faces.iter().map(|f| f.layers.clone()).collect(),
            &name,
            |unit_cube, layers| build_tracer(method, unit_cube, layers, opts),
        )?;
        let times = CubeTimes {
            build_ms: t.elapsed().as_secs_f64() * 1e3,
            ..cube.times
        };
        let colour_only = WarpOptions {
            side_entry_guard: false,
            dda_recheck: false,
            silhouette_check: false,
            nearer_neighbour_check: false,
            ..opts.warp
        };
        let warps = cube
            .faces
            .iter()
            .map(|f| RayWarp::new(f, &colour_only))
            .collect();
        Ok(Self {
            cube,
            warps,
            scene,
            tracer,
            method,
            times,
        })
    }

    /// The surface hit of `ray`'s answer `r` in face `face`: the answering layer sample's
    /// attributes at the traced position.
    fn sample_hit(&self, ray: &Ray, face: usize, r: TraceResult) -> Option<SurfaceHit> {
        let (layer, pixel, t, occlusion) = match r {
            TraceResult::Hit {
                layer, pixel, t, ..
            } => (layer, pixel, t, false),
            TraceResult::OcclusionVolume { layer, pixel, t } => (layer, pixel, t, true),
            TraceResult::Miss => return None,
        };
        if !(t > ray.t_min && t < ray.t_max) {
            return None;
        }
        let g = self.cube.faces[face].layers.get(layer as usize)?;
        let i = g.index(pixel.x, pixel.y);
        let n = g.normal[i];
        let n = if n.dot(ray.dir) > 0.0 { -n } else { n };
        Some(SurfaceHit {
            t,
            position: ray.at(t),
            normal: n,
            material_id: g.material_id[i],
            albedo: g.albedo[i],
            prim: g.primitive_id[i],
            barycentrics: g.barycentrics[i],
            sample: Some((face as u8, layer as u8, pixel)),
            occlusion,
            cube: 0,
        })
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
        CubeMapTracer::count(stats, &s, &trace);
        self.sample_hit(ray, trace.face, trace.result)
    }

    fn colour(&self, ray: &Ray, hit: &SurfaceHit) -> Vec3 {
        let Some((face, layer, pixel)) = hit.sample else {
            return self.cube.background;
        };
        let (layer, t) = (layer as u32, hit.t);
        let r = if hit.occlusion {
            TraceResult::OcclusionVolume { layer, pixel, t }
        } else {
            TraceResult::Hit {
                layer,
                pixel,
                position: hit.position,
                t,
            }
        };
        self.warps[face as usize].colour(ray, r).0
    }

    fn plane_sample(&self, hit: &SurfaceHit, ray: &Ray, sigma: f32) -> (Vec3, f32) {
        let Some((face, layer, pixel)) = hit.sample else {
            return (Vec3::ZERO, 0.0);
        };
        let g = &self.cube.faces[face as usize].layers[layer as usize];
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
        let gq = &self.cube.faces[f].layers[layer as usize];
        let j = gq.index(q.x, q.y);
        let d_s = gq.depth[j];
        if !(d_s.is_finite() && d_s > 0.0) {
            return (Vec3::ZERO, 0.0);
        }
        let rel = (self.face_depth(f, x) - d_s) / d_s;
        let w = (-(rel * rel) / (sigma * sigma)).exp();
        let at = TraceResult::Hit {
            layer: layer as u32,
            pixel: q,
            position: x,
            t,
        };
        (self.warps[f].colour(ray, at).0, w)
    }
}
