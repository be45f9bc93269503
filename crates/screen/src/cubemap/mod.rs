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
use parallax_scene::camera::Pinhole;

use crate::{
    DdaOptions, DdaTracer, QuadTreeOptions, QuadTreeTracer, ScreenError, ScreenTracer, TraceResult,
    TraceStats, UnitCube,
};
pub use faces::{Exit, FaceWalk, Faces};

/// One face: its pinhole, unit cube, layers and tracer.
pub struct CubeFace {
    pub camera: Pinhole,
    pub cube: UnitCube,
    pub layers: Vec<GBuffer>,
    pub tracer: Box<dyn ScreenTracer>,
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
}

impl CubeMapTracer {
    /// The shared depth range of a capture's faces: `near` = half the nearest captured
    /// depth over all faces and layers, `far` = twice the farthest.
    pub fn depth_range(capture: &CubeCapture) -> Result<(f32, f32), ScreenError> {
        let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
        for f in &capture.faces {
            for g in &f.layers.layers {
                for &d in &g.depth {
                    if d.is_finite() && d > 0.0 {
                        lo = lo.min(d);
                        hi = hi.max(d);
                    }
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

    /// Builds one tracer per face with `face(cube, layers)` over `capture`, named `name`
    /// (e.g. `cubemap-quadtree`), all faces in the cube of [`Self::depth_range`].
    pub fn build<E: From<ScreenError>>(
        capture: &CubeCapture,
        name: &str,
        face: impl Fn(&UnitCube, &[GBuffer]) -> Result<Box<dyn ScreenTracer>, E>,
    ) -> Result<Self, E> {
        if capture.faces.len() != 6 {
            return Err(ScreenError::Mismatch(format!(
                "a cube map has 6 faces, the capture {}",
                capture.faces.len()
            ))
            .into());
        }
        let (near, far) = Self::depth_range(capture)?;
        let t = Instant::now();
        let mut faces = Vec::with_capacity(6);
        for (i, f) in capture.faces.iter().enumerate() {
            let camera = capture.cube.face_camera(i);
            let cube = UnitCube::new(&camera, near, far)?;
            let layers = f.layers.layers.clone();
            let tracer = face(&cube, &layers)?;
            faces.push(CubeFace {
                camera,
                cube,
                layers,
                tracer,
            });
        }
        Ok(Self {
            name: name.to_string(),
            faces,
            walk: Faces::new(&capture.cube, near, far),
            build_ms: t.elapsed().as_secs_f64() * 1e3,
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
        };
        if !ray.is_valid() || ray.t_min.is_nan() || ray.t_max.is_nan() {
            return out;
        }
        let mut walk = self.walk.walk(ray);
        for (face, _) in walk.by_ref() {
            out.face = face;
            out.visits += 1;
            let r = self.faces[face].tracer.trace(ray, stats);
            if !matches!(r, TraceResult::Miss) {
                out.result = r;
                return out;
            }
        }
        out.truncated = walk.truncated;
        out
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

    /// Adds one traced ray's work to world stats.
    fn count(stats: &mut WorldStats, s: &TraceStats, trace: &CubeTrace) {
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
