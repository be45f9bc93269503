//! [`CubeMapTracer`]: a world-space tracer over a six-face cube map of captured layers, one
//! screen-space structure per face (Widmer et al. 2015, §5.4, Table 5, Figs. 11-13: "we
//! generate a cube map at the camera location, and create our adaptive data structure for
//! each face").
//!
//! A ray is traced in the face its origin lies in, then, while it finds nothing, in the
//! neighbour face across the frustum plane it leaves by, until a hit or the far plane
//! ([`faces`]). Every face keeps its own tracer (the quad-tree of §3-4 with its cascade or
//! inpainting through 1 or 2 layers, or the DDA baseline), built over the face's layers in the
//! face's unit cube; all six cubes share one near and one far plane, so the frusta tile the
//! space between the near cube and the far cube. A face tracer sees the whole ray and clips
//! it to its own frustum (each frustum is convex, so that is the ray's one interval there).
//!
//! **Back sides.** Every captured sample faces the eye (its normal is turned towards it, and
//! hidden layers hold front faces). A reflection ray that crosses a sample's plane from
//! behind (normal along the ray) has not met that surface: a ray leaving a convex surface
//! near its silhouette crosses the steep planes of the surface's own neighbouring pixels this
//! way, and the surface it would really meet from behind is not in the capture. Such a
//! crossing is passed over: the face is traced on from half a pixel footprint beyond it, at
//! most [`MAX_BACK_SKIPS`] + 1 times per face (then the walk goes on to the next face).
//!
//! **Thickness** (optional, [`CubeMapTracer::thickness`] = `τ`; off by default, the paper's
//! semantics): a face's occlusion-volume answer says the ray passed behind a captured surface
//! with nothing hit; a cube map's occluders are then infinitely thick, so every ray that
//! passes behind a pillar towards the sky answers with the pillar. With `τ` every sample at
//! depth `d` occludes only `[d, d (1 + τ)]` (the DDA's `z_thickness`, relative): from the
//! occlusion entry the ray is marched on in steps of half a face pixel footprint (at least
//! `τ d / 4`) — inside a sample's interval it is a hit on that sample; once in front of layer
//! 0 again (or over an empty pixel) the face tracer resumes there; leaving the face (or the
//! ray) goes on to the next face. At most [`MAX_BACK_SKIPS`] + 1 face traces per face count
//! both kinds of skips.
//!
//! **Answers** ([`CubeTrace`]): a hit in a face's layer; an occlusion-volume answer (the ray
//! passed behind the last layer's surface: with the quad-tree's inpainting mode on the last
//! layer, the background-side pixel before the silhouette) is reported as a hit on that pixel's
//! sample — the single-layer inpainting of §4.1, the only answer a cube map without the
//! hidden surface can give; a miss once the ray leaves through the far plane. As a
//! [`WorldTracer`] the hit is [`HitSurface::Sampled`] with the layer sample's normal, albedo
//! and material, and its primitive id (the capture keeps it).
//!
//! **Invariants** (those of [`WorldTracer`]): `t` in `(t_min, t_max)`, `position =
//! ray.at(t)`; `occluded` is `closest_hit(..).is_some()`; invalid rays miss; the face walk is
//! bounded ([`faces::MAX_FACE_VISITS`], cut walks count in `truncated`); answers do not
//! depend on the thread.

pub mod faces;

use std::time::Instant;

use glam::{UVec2, Vec2};
use parallax_core::Ray;
use parallax_core::image::GBuffer;
use parallax_core::world::{HitSurface, SampledSurface, WorldHit, WorldStats, WorldTracer};
use parallax_raster::CubeCapture;
use parallax_scene::camera::{CameraModel, CubeMap, Pinhole};

use crate::{
    DdaOptions, DdaTracer, QuadTreeOptions, QuadTreeTracer, ScreenError, ScreenTracer, TraceResult,
    TraceStats, UnitCube,
};
pub use faces::{Exit, FaceWalk, Faces};

/// Most back-side crossings passed over per face (module docs).
pub const MAX_BACK_SKIPS: u32 = 4;

/// Most march steps behind an occluder per face, in face sizes (module docs, "thickness").
const MARCH_FACES: u32 = 4;

/// Where the march behind an occluder ended.
enum Behind {
    /// In front of layer 0 (or over an empty pixel) at this ray parameter.
    Free(f32),
    /// Inside a sample's thickness interval: a hit on it.
    Inside(TraceResult),
    /// Out of the face or past the ray's end.
    Left,
}

/// One face: its pinhole, unit cube, layers and tracer.
pub struct CubeFace {
    pub camera: Pinhole,
    pub cube: UnitCube,
    pub layers: Vec<GBuffer>,
    pub tracer: Box<dyn ScreenTracer>,
}

/// The tracer of a face that captured no surface: every ray misses.
struct EmptyFace;

impl ScreenTracer for EmptyFace {
    fn trace(&self, _: &Ray, stats: &mut TraceStats) -> TraceResult {
        stats.rays += 1;
        TraceResult::Miss
    }
}

/// What [`CubeMapTracer::trace`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeTrace {
    /// The face that answered (the last face visited for a miss).
    pub face: usize,
    /// The face tracer's answer (`Miss` when no face found anything).
    pub result: TraceResult,
    /// Faces visited.
    pub visits: u32,
    /// The face walk was cut ([`faces::MAX_FACE_VISITS`]).
    pub truncated: bool,
    /// Back-side crossings passed over (module docs).
    pub back_skips: u32,
}

impl CubeTrace {
    /// Layer, pixel and ray parameter of a hit or occlusion-volume answer.
    pub fn sample(&self) -> Option<(u32, UVec2, f32)> {
        match self.result {
            TraceResult::Hit {
                layer, pixel, t, ..
            } => Some((layer, pixel, t)),
            TraceResult::OcclusionVolume { layer, pixel, t } => Some((layer, pixel, t)),
            TraceResult::Miss => None,
        }
    }
}

/// Six faces of captured layers and their tracers (module docs).
pub struct CubeMapTracer {
    name: String,
    pub faces: Vec<CubeFace>,
    pub walk: Faces,
    /// Milliseconds of building the six face tracers.
    pub build_ms: f64,
    /// Relative thickness of captured surfaces (module docs, "thickness"); `None`: occlusion
    /// volumes are final answers.
    pub thickness: Option<f32>,
}

impl CubeMapTracer {
    /// The shared depth range of a cube map's faces (`faces[i]` the layers of face `i`):
    /// `near` = half the nearest captured depth over all faces and layers, `far` = twice the
    /// farthest.
    pub fn depth_range(faces: &[Vec<GBuffer>]) -> Result<(f32, f32), ScreenError> {
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for g in faces.iter().flatten() {
            for &d in &g.depth {
                if d.is_finite() && d > 0.0 {
                    lo = lo.min(d);
                    hi = hi.max(d);
                }
            }
        }
        if !lo.is_finite() {
            return Err(ScreenError::InvalidSpace(
                "the cube map captured no surface".into(),
            ));
        }
        Ok((0.5 * lo, 2.0 * hi))
    }

    /// Builds one tracer per face of `capture` with `face(cube, layers)`, named `name`
    /// (e.g. `cubemap-quadtree`), all faces in the cube of [`Self::depth_range`].
    pub fn build<E: From<ScreenError>>(
        capture: &CubeCapture,
        name: &str,
        face: impl Fn(&UnitCube, &[GBuffer]) -> Result<Box<dyn ScreenTracer>, E>,
    ) -> Result<Self, E> {
        let layers: Vec<Vec<GBuffer>> = capture
            .faces
            .iter()
            .map(|f| f.layers.layers.clone())
            .collect();
        Self::from_faces(&capture.cube, layers, name, face)
    }

    /// [`Self::build`] over the layers of each face of `cube` (`faces[i]` of face `i`, every
    /// layer `cube.face_size()` square), however they were captured (e.g. hidden layers of
    /// front faces only).
    pub fn from_faces<E: From<ScreenError>>(
        cube: &CubeMap,
        faces: Vec<Vec<GBuffer>>,
        name: &str,
        face: impl Fn(&UnitCube, &[GBuffer]) -> Result<Box<dyn ScreenTracer>, E>,
    ) -> Result<Self, E> {
        if faces.len() != 6 {
            return Err(ScreenError::Mismatch(format!(
                "a cube map has 6 faces, the capture {}",
                faces.len()
            ))
            .into());
        }
        let s = cube.face_size();
        if faces
            .iter()
            .flatten()
            .any(|g| g.width() != s || g.height() != s)
        {
            return Err(ScreenError::Mismatch(format!("cube map layers must be {s}x{s}")).into());
        }
        let (near, far) = Self::depth_range(&faces)?;
        let t = Instant::now();
        let mut built = Vec::with_capacity(6);
        for (i, layers) in faces.into_iter().enumerate() {
            let camera = cube.face_camera(i);
            let cube = UnitCube::new(&camera, near, far)?;
            // A face that captured nothing has nothing to hit (and no depths to fit a
            // structure's parameters to).
            let empty = layers
                .iter()
                .all(|g| !g.depth.iter().any(|d| d.is_finite()));
            let tracer = if empty {
                Box::new(EmptyFace)
            } else {
                face(&cube, &layers)?
            };
            built.push(CubeFace {
                camera,
                cube,
                layers,
                tracer,
            });
        }
        Ok(Self {
            name: name.to_string(),
            faces: built,
            walk: Faces::new(cube, near, far),
            build_ms: t.elapsed().as_secs_f64() * 1e3,
            thickness: None,
        })
    }

    /// The quad-tree of every face (`opts` as given; `gamma_dist` in the faces' cube units).
    pub fn quadtree(capture: &CubeCapture, opts: &QuadTreeOptions) -> Result<Self, ScreenError> {
        Self::build(capture, "cubemap-quadtree", |cube, layers| {
            Ok(Box::new(QuadTreeTracer::build(cube, layers, opts)?) as Box<dyn ScreenTracer>)
        })
    }

    /// The DDA of every face (`opts.layers` is set to the capture's layer count).
    pub fn dda(capture: &CubeCapture, opts: &DdaOptions) -> Result<Self, ScreenError> {
        Self::build(capture, "cubemap-dda", |cube, layers| {
            let o = DdaOptions {
                layers: layers.len(),
                ..*opts
            };
            Ok(Box::new(DdaTracer::new(cube, layers, &o)?) as Box<dyn ScreenTracer>)
        })
    }

    /// Traces `ray` face by face (module docs), adding the face tracers' work to `stats`.
    pub fn trace(&self, ray: &Ray, stats: &mut TraceStats) -> CubeTrace {
        let mut out = CubeTrace {
            face: 0,
            result: TraceResult::Miss,
            visits: 0,
            truncated: false,
            back_skips: 0,
        };
        if !ray.is_valid() || ray.t_min.is_nan() || ray.t_max.is_nan() {
            return out;
        }
        let mut walk = self.walk.walk(ray);
        for (face, _) in walk.by_ref() {
            out.face = face;
            out.visits += 1;
            let mut r = *ray;
            for _ in 0..=MAX_BACK_SKIPS {
                let answer = self.faces[face].tracer.trace(&r, stats);
                match answer {
                    TraceResult::Miss => break,
                    TraceResult::Hit {
                        layer, pixel, t, ..
                    } if self.crosses_from_behind(face, layer, pixel, ray) => {
                        // Go on just past the crossing (module docs, "back sides").
                        r.t_min = t + self.skip_step(face, t, ray);
                        out.back_skips += 1;
                    }
                    TraceResult::OcclusionVolume { t, .. } if self.thickness.is_some() => {
                        let tau = self.thickness.unwrap_or(0.0);
                        match self.march_behind(face, ray, t, tau) {
                            Behind::Free(t_free) => {
                                r.t_min = t_free;
                                out.back_skips += 1;
                            }
                            Behind::Inside(hit) => {
                                out.result = hit;
                                return out;
                            }
                            Behind::Left => break,
                        }
                    }
                    answer => {
                        out.result = answer;
                        return out;
                    }
                }
            }
        }
        out.truncated = walk.truncated;
        out
    }

    /// Marches `ray` on from its occlusion entry at `t` in `face` with samples `tau` thick
    /// (module docs, "thickness").
    fn march_behind(&self, face: usize, ray: &Ray, mut t: f32, tau: f32) -> Behind {
        let f = &self.faces[face];
        let axis = parallax_scene::camera::cube::FACE_AXES[face];
        let eye = self.walk.eye;
        let size = f.camera.width;
        let Some(g0) = f.layers.first() else {
            return Behind::Left;
        };
        for _ in 0..MARCH_FACES * size {
            if !(t < ray.t_max) {
                return Behind::Left;
            }
            let p = ray.at(t);
            let Some(film) = f.camera.project(p, 0) else {
                return Behind::Left;
            };
            if !(film.x >= 0.0 && film.y >= 0.0 && film.x < size as f32 && film.y < size as f32) {
                return Behind::Left;
            }
            let q = UVec2::new(film.x as u32, film.y as u32);
            let i = g0.index(q.x, q.y);
            let d = (p - eye).dot(axis);
            for (layer, g) in f.layers.iter().enumerate() {
                let ds = g.depth[i];
                if ds.is_finite() && ds > 0.0 && d >= ds && d <= ds * (1.0 + tau) {
                    return Behind::Inside(TraceResult::Hit {
                        layer: layer as u32,
                        pixel: q,
                        position: p,
                        t,
                    });
                }
            }
            let d0 = g0.depth[i];
            if !(d0.is_finite() && d0 > 0.0) || d < d0 {
                return Behind::Free(t);
            }
            let step = self
                .skip_step(face, t, ray)
                .max(0.25 * tau * d / ray.dir.length());
            t += step;
        }
        Behind::Left
    }

    /// True when `ray` crosses the sample at `pixel` of `layer` of `face` from behind (its
    /// normal, which faces the eye, points along the ray).
    fn crosses_from_behind(&self, face: usize, layer: u32, pixel: UVec2, ray: &Ray) -> bool {
        let Some(g) = self.faces[face].layers.get(layer as usize) else {
            return false;
        };
        pixel.x < g.width()
            && pixel.y < g.height()
            && g.normal[g.index(pixel.x, pixel.y)].dot(ray.dir) > 0.0
    }

    /// How far past a back-side crossing at `t` the trace resumes: half a face pixel
    /// footprint at the crossing's distance from the eye, in units of the ray parameter.
    fn skip_step(&self, face: usize, t: f32, ray: &Ray) -> f32 {
        let p = ray.at(t);
        let depth = (p - self.walk.eye).abs().max_element();
        let footprint = 2.0 * depth / self.faces[face].camera.width as f32;
        (0.5 * footprint / ray.dir.length()).max(1e-4 * t.abs())
    }

    /// The world hit of a cube trace: the answering layer sample's surface at the traced
    /// position (module docs). `None` for a miss.
    pub fn world_hit(&self, ray: &Ray, trace: &CubeTrace) -> Option<WorldHit> {
        let (layer, pixel, t) = trace.sample()?;
        let g = self.faces[trace.face].layers.get(layer as usize)?;
        if pixel.x >= g.width() || pixel.y >= g.height() || !(t > ray.t_min && t < ray.t_max) {
            return None;
        }
        let i = g.index(pixel.x, pixel.y);
        Some(WorldHit {
            t,
            position: ray.at(t),
            prim: g.primitive_id[i],
            barycentrics: Vec2::ZERO,
            surface: HitSurface::Sampled(SampledSurface {
                normal: g.normal[i],
                albedo: g.albedo[i],
                material_id: g.material_id[i],
            }),
        })
    }

    /// Adds one traced ray's work (`s` of the face tracers, `trace` of the walk) to world
    /// stats.
    pub fn count(stats: &mut WorldStats, s: &TraceStats, trace: &CubeTrace) {
        stats.rays += 1;
        stats.nodes += s.nodes_visited + if s.nodes_visited == 0 { s.steps } else { 0 };
        stats.tests += s.box_tests + s.plane_tests;
        stats.steps += trace.visits as u64;
        stats.truncated += (s.truncated > 0 || trace.truncated) as u64;
    }
}

impl WorldTracer for CubeMapTracer {
    fn name(&self) -> &str {
        &self.name
    }

    fn is_exact(&self) -> bool {
        false
    }

    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit> {
        let mut s = TraceStats::default();
        let trace = self.trace(ray, &mut s);
        Self::count(stats, &s, &trace);
        self.world_hit(ray, &trace)
    }

    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool {
        self.closest_hit(ray, stats).is_some()
    }
}
