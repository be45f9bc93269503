//! The `--tracer` factory: the one place that builds a world-space tracer
//! ([`parallax_core::WorldTracer`]) for a scene and a camera, so that every command and bench
//! runs the same path tracer over any structure.
//!
//! | name | structure | hits | built from |
//! |---|---|---|---|
//! | `bvh` | binned-SAH 8-wide BVH ([`parallax_bvh::Bvh`], called through [`BvhTracer`]: packets for a pinhole's camera rays) | exact | the scene's triangles |
//! | `dirt` | DIRT's per-view primitive lists ([`parallax_screen::DirtTracer`], Vardis et al. 2017) | exact | a capture of the camera's view (a pinhole camera; other models: none) and of a cube map around the camera |
//! | `ldc` | two-level layered depth cube ([`parallax_screen::ldc::LdcTracer`], Bürger et al. 2007) | sampled | three all-layers LDIs of the scene box at [`LdcSettings::resolution`] |
//! | `cubemap` | one quad-tree per face of a cube map at the camera ([`parallax_screen::CubeMapTracer`], Widmer et al. 2015, §5.4) | sampled | [`CubeMapSettings::layers`] depth-peeled layers (every surface) of six [`CubeMapSettings::face`]² faces |
//!
//! Image-space structures that need the camera (DIRT's views around it, the layered depth
//! cube's capture) add their variant here; [`TracerOptions`] carries their parameters.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `dirt` | [`DirtViewsOptions`] | face 128, S 4, B 16 | DIRT's cube face size, tile size `S` and buckets `B` (`--dirt-face`, `--dirt-tile`, `--dirt-buckets`) |
//! | `ldc` | [`LdcSettings`] | resolution 1024 | the cube's resolution, build and trace options |
//! | `cubemap` | [`CubeMapSettings`] | face 512, 2 layers, default quad-tree | face size, layers and quad-tree options of the cube map |

use std::time::Instant;

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::{Aabb, WorldTracer};
use parallax_raster::dirt::{DirtViews, DirtViewsOptions};
use parallax_raster::ldc::{LayeredDepthCube, LdcOptions, LdcStats};
use parallax_raster::{CubeCapture, RasterOptions};
use parallax_scene::camera::{Camera, CameraModel, CubeMap};
use parallax_scene::{CameraDesc, Scene};
use parallax_screen::ldc::{LdcTraceOptions, LdcTracer};
use parallax_screen::{CubeMapTracer, DirtTracer, QuadTreeOptions};
use serde::Serialize;

use crate::bvh_tracer::BvhTracer;
use crate::error::{PathError, Result};

/// Which structure answers the path tracer's rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TracerKind {
    /// The exact BVH over the scene's triangles (the reference).
    #[default]
    Bvh,
    /// DIRT: Hi-Z and bucket tracing through per-view primitive lists, exact.
    Dirt,
    /// The two-level layered depth cube (sampled hits).
    Ldc,
    /// Widmer et al.'s cube map of layers with a quad-tree per face (sampled hits).
    CubeMap,
}

impl TracerKind {
    pub const ALL: [TracerKind; 4] = [
        TracerKind::Bvh,
        TracerKind::Dirt,
        TracerKind::Ldc,
        TracerKind::CubeMap,
    ];

    pub fn name(self) -> &'static str {
        match self {
            TracerKind::Bvh => "bvh",
            TracerKind::Dirt => "dirt",
            TracerKind::Ldc => "ldc",
            TracerKind::CubeMap => "cubemap",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| PathError::UnknownTracer {
                name: s.to_string(),
                known: Self::ALL.map(|k| k.name()).join(", "),
            })
    }
}

/// How the `ldc` tracer is built.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LdcSettings {
    /// Pixels along the cube's longest side (the paper: 512 or 1024).
    pub resolution: u32,
    pub build: LdcOptions,
    pub trace: LdcTraceOptions,
}

impl Default for LdcSettings {
    fn default() -> Self {
        Self {
            resolution: 1024,
            build: LdcOptions::default(),
            trace: LdcTraceOptions::default(),
        }
    }
}

/// How the `cubemap` tracer is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CubeMapSettings {
    /// Face size in pixels (the paper: 1024).
    pub face: u32,
    /// Depth-peeled layers per face.
    pub layers: usize,
    pub quadtree: QuadTreeOptions,
}

impl Default for CubeMapSettings {
    fn default() -> Self {
        Self {
            face: 512,
            layers: 2,
            quadtree: QuadTreeOptions::default(),
        }
    }
}

/// Parameters of the structures that have any (none for the BVH; see the module table).
#[derive(Clone, Debug, PartialEq)]
pub struct TracerOptions {
    pub dirt: DirtViewsOptions,
    pub ldc: LdcSettings,
    pub cubemap: CubeMapSettings,
}

/// DIRT's configuration for path tracing ([`DirtViewsOptions::TRACING`]).
pub const DIRT_DEFAULTS: DirtViewsOptions = DirtViewsOptions::TRACING;

impl Default for TracerOptions {
    fn default() -> Self {
        Self {
            dirt: DIRT_DEFAULTS,
            ldc: LdcSettings::default(),
            cubemap: CubeMapSettings::default(),
        }
    }
}

/// Where `camera` sits: the origin of its ray through the film centre (the centre of DIRT's
/// cube map; any point is exact, the camera's own is where the views are finest).
pub fn camera_centre(camera: &Camera) -> Vec3 {
    let film = Vec2::new(camera.width() as f32, camera.height() as f32) * 0.5;
    camera
        .generate_ray(film, Vec2::splat(0.5), 1)
        .map_or(Vec3::ZERO, |r| r.ray.origin)
}

/// A built tracer and what building it cost.
pub struct BuiltTracer {
    pub tracer: Box<dyn WorldTracer>,
    /// Wall-clock milliseconds of the build.
    pub build_ms: f64,
    /// Bytes of the structure.
    pub bytes: usize,
    /// The box the structure covers when it covers only part of the scene (an LDC fitted to
    /// a region of interest).
    pub bounds: Option<Aabb>,
    /// The layered depth cube's build stats (`ldc` only).
    pub ldc: Option<LdcStats>,
}

/// Builds the `kind` tracer for `scene` seen by `camera`.
pub fn build_tracer(
    kind: TracerKind,
    scene: &Scene,
    camera: &Camera,
    opts: &TracerOptions,
) -> Result<BuiltTracer> {
    let start = Instant::now();
    let failed = |e: &dyn std::fmt::Display| PathError::Build {
        tracer: kind.name().into(),
        message: e.to_string(),
    };
    let (tracer, bytes, bounds, ldc): (Box<dyn WorldTracer>, _, _, _) = match kind {
        TracerKind::Bvh => {
            let bvh = Bvh::try_build(&scene.mesh).map_err(|e| failed(&e))?;
            let bytes = bvh.bytes();
            (Box::new(BvhTracer::new(bvh)), bytes, None, None)
        }
        TracerKind::Dirt => {
            let pinhole = match camera {
                Camera::Pinhole(p) => Some(p),
                _ => None,
            };
            let views = DirtViews::build(&scene.mesh, pinhole, camera_centre(camera), &opts.dirt)
                .map_err(|e| failed(&e))?;
            let bytes = views.bytes() as usize;
            (Box::new(DirtTracer::new(views)), bytes, None, None)
        }
        TracerKind::Ldc => {
            let s = &opts.ldc;
            let cube =
                LayeredDepthCube::build(scene, s.resolution, &s.build).map_err(|e| failed(&e))?;
            let (stats, bounds) = (cube.stats, s.build.roi.map(|_| cube.bounds));
            let t = LdcTracer::new(cube, s.trace).map_err(|e| failed(&e))?;
            let bytes = t.bytes();
            (Box::new(t), bytes, bounds, Some(stats))
        }
        TracerKind::CubeMap => {
            let s = &opts.cubemap;
            let eye = camera_centre(camera);
            let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0);
            let cube = CubeMap::new(&desc, s.face).map_err(|e| failed(&e))?;
            let capture = CubeCapture::capture(scene, &cube, &RasterOptions::layers(s.layers))
                .map_err(|e| failed(&e))?;
            let t = CubeMapTracer::quadtree(&capture, &s.quadtree).map_err(|e| failed(&e))?;
            (Box::new(t), capture.bytes(), None, None)
        }
    };
    Ok(BuiltTracer {
        tracer,
        build_ms: start.elapsed().as_secs_f64() * 1e3,
        bytes,
        bounds,
        ldc,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_raster::dirt::DirtOptions;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_known() {
        for k in TracerKind::ALL {
            assert_eq!(TracerKind::parse(k.name()).unwrap(), k);
        }
        let e = TracerKind::parse("octree").unwrap_err().to_string();
        assert!(
            e.contains("octree") && e.contains("bvh") && e.contains("dirt") && e.contains("ldc"),
            "{e}"
        );
    }

    /// The cornell box and a small pinhole of its first camera.
    fn cornell() -> (Scene, Camera) {
        let scene = Scene::load("cornell").unwrap();
        let desc = scene.camera(None).unwrap();
        let camera = Camera::new(
            parallax_scene::camera::ModelKind::Pinhole,
            &desc,
            16,
            12,
            &Default::default(),
        )
        .unwrap();
        (scene, camera)
    }

    #[test]
    fn dirt_options_out_of_range_are_build_errors() {
        let (scene, camera) = cornell();
        for (face, buckets) in [(0, 16), (5000, 16), (64, 0), (64, 4096)] {
            let opts = TracerOptions {
                dirt: DirtViewsOptions {
                    face_size: face,
                    capture: DirtOptions {
                        buckets,
                        ..DIRT_DEFAULTS.capture
                    },
                    ..DIRT_DEFAULTS
                },
                ..TracerOptions::default()
            };
            let e = build_tracer(TracerKind::Dirt, &scene, &camera, &opts)
                .err()
                .expect("out of range")
                .to_string();
            assert!(e.contains("dirt") && e.contains("must be in"), "{e}");
        }
        let ok =
            build_tracer(TracerKind::Dirt, &scene, &camera, &TracerOptions::default()).unwrap();
        assert_eq!(ok.tracer.name(), "dirt");
    }

    #[test]
    fn the_cubemap_tracer_builds_and_answers_like_the_bvh_where_the_eye_sees() {
        let (scene, camera) = cornell();
        let mut opts = TracerOptions::default();
        opts.cubemap.face = 0;
        let e = build_tracer(TracerKind::CubeMap, &scene, &camera, &opts)
            .err()
            .expect("a face of 0 pixels")
            .to_string();
        assert!(e.contains("cubemap"), "{e}");
        opts.cubemap.face = 128;
        let cube = build_tracer(TracerKind::CubeMap, &scene, &camera, &opts).unwrap();
        let bvh = build_tracer(TracerKind::Bvh, &scene, &camera, &opts).unwrap();
        assert!(!cube.tracer.is_exact() && cube.bytes > 0);
        // Rays from the eye: the cube map's first layer holds what they hit.
        let eye = camera_centre(&camera);
        let mut stats = parallax_core::WorldStats::default();
        let mut worst = 0.0f32;
        for i in 0..64 {
            let a = i as f32 * 0.7;
            let dir = Vec3::new(a.cos(), 0.6 * (1.3 * a).sin(), a.sin()).normalize();
            let ray = parallax_core::Ray::new(eye, dir);
            let t = bvh.tracer.closest_hit(&ray, &mut stats).map(|h| h.position);
            let c = cube
                .tracer
                .closest_hit(&ray, &mut stats)
                .map(|h| h.position);
            match (t, c) {
                (Some(t), Some(c)) => worst = worst.max((t - c).length() / (t - eye).length()),
                (None, None) => {}
                (t, c) => panic!("BVH {t:?}, cube map {c:?}"),
            }
        }
        // Measured: 128^2 faces, the worst ray 3e-6 of its distance off.
        assert!(worst < 1e-4, "{worst}");
    }
}
