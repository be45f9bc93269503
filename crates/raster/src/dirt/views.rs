//! Everything DIRT's tracer reads (Vardis et al. 2017, §3 "Data structures" and §4.1
//! "Overview"): the triangle buffer, the camera view's capture and the six captures of a cube
//! map around the camera's eye (the multi-view setup of Vardis et al. 2016). Together the views
//! see every direction from the eye, so every triangle farther than the near plane is listed in
//! some view; the camera view adds the camera's (usually finer) grid where most rays travel.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `face_size` | u32 | 256 | cube face size in pixels (`1..=`[`MAX_FACE_SIZE`]) |
//! | `capture` | [`DirtOptions`] | S = 1, B = 8 | tile size `S`, buckets `B`, near plane and entry budget of every view (the budget bounds the sum over all views) |
//! | `camera_tile_size` | `Option<u32>` | `None` | the camera view's `S` when it differs from the cube faces' (`capture.tile_size`); a coarser camera grid lists fewer cell-triangle pairs (a cheaper build) in larger cells (more triangle tests per ray) |
//!
//! The camera view and the six faces are built together: one triangle setup pass over the mesh
//! for all seven views, then the fill of every band of every view in one parallel loop (one
//! entry budget for all views); the triangle buffer is gathered in parallel with them.
//!
//! The camera view is optional: without one (a camera model that is not a pinhole) the cube
//! alone answers every ray.

use std::time::Instant;

use glam::Vec3;
use parallax_scene::TriangleMesh;
use parallax_scene::camera::{CubeMap, Pinhole};
use serde::Serialize;

use super::{DirtCapture, DirtCube, DirtError, DirtOptions, DirtTriangles};

/// Largest allowed cube face size (pixels).
pub const MAX_FACE_SIZE: u32 = 4096;

/// Options of [`DirtViews::build`] (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DirtViewsOptions {
    pub face_size: u32,
    pub capture: DirtOptions,
    pub camera_tile_size: Option<u32>,
}

impl DirtViewsOptions {
    /// The configuration tracing uses: 128^2 cube faces, 4 x 4 tiles on the faces and 8 x 8 on
    /// the camera view, 16 buckets (the fastest trace of `bench dirt`'s sweeps at a build close
    /// to the BVH's; the camera view's coarser grid lists ~55 % fewer cell-triangle pairs for
    /// about the same trace; docs/notes/dirt.md).
    pub const TRACING: DirtViewsOptions = DirtViewsOptions {
        face_size: 128,
        capture: DirtOptions {
            tile_size: 4,
            buckets: 16,
            near: 1e-4,
            max_entries: 1 << 28,
            cell_depth: super::CellDepth::Corners,
        },
        camera_tile_size: Some(8),
    };
}

impl DirtViewsOptions {
    /// These options with a user's two tile flags applied: `camera` sets the camera view's S;
    /// `all` sets S of the cube faces and, when `camera` is not given, of the camera view too;
    /// neither keeps these options' sizes.
    pub fn with_tile_flags(mut self, all: Option<u32>, camera: Option<u32>) -> Self {
        if let Some(s) = all {
            self.capture.tile_size = s;
        }
        self.camera_tile_size = match (camera, all) {
            (Some(s), _) => Some(s),
            (None, Some(_)) => None,
            (None, None) => self.camera_tile_size,
        };
        self
    }
}

impl Default for DirtViewsOptions {
    fn default() -> Self {
        Self {
            face_size: 256,
            capture: DirtOptions::default(),
            camera_tile_size: None,
        }
    }
}

/// Build times (ms) and sizes of the views (the triangle buffer is gathered while the captures
/// are built, so `triangles_ms + camera_ms + cube_ms` can exceed the wall time `total_ms`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct DirtViewsStats {
    pub triangles_ms: f64,
    pub camera_ms: f64,
    pub cube_ms: f64,
    pub total_ms: f64,
    /// Bytes of the triangle buffer.
    pub triangle_bytes: u64,
    /// Bytes of all captures (depth bounds with mips, offsets, ids).
    pub capture_bytes: u64,
}

/// The triangle buffer, the camera view (optional) and the cube map of DIRT.
#[derive(Clone, Debug)]
pub struct DirtViews {
    pub triangles: DirtTriangles,
    pub camera: Option<DirtCapture>,
    pub cube: DirtCube,
    pub options: DirtViewsOptions,
    pub stats: DirtViewsStats,
}

impl DirtViews {
    /// Builds the triangle buffer, the capture of `camera` (if any, at its own film size) and
    /// the cube map around `eye` (the camera's position when a camera is given).
    pub fn build(
        mesh: &TriangleMesh,
        camera: Option<&Pinhole>,
        eye: Vec3,
        opts: &DirtViewsOptions,
    ) -> Result<DirtViews, DirtError> {
        if opts.face_size == 0 || opts.face_size > MAX_FACE_SIZE {
            return Err(DirtError::InvalidOptions(format!(
                "cube face size {} must be in 1..={MAX_FACE_SIZE}",
                opts.face_size
            )));
        }
        let eye = camera.map_or(eye, |c| c.frame.position);
        if !eye.is_finite() {
            return Err(DirtError::InvalidView(format!(
                "cube map centre {eye} is not finite"
            )));
        }
        let t0 = Instant::now();
        // The camera view and the six faces share one triangle setup pass over the mesh and
        // one entry budget; the triangle buffer is gathered alongside.
        let cube_map = CubeMap {
            eye,
            face: opts.face_size,
        };
        let pinholes: Vec<Pinhole> = camera
            .into_iter()
            .cloned()
            .chain((0..6).map(|i| cube_map.face_camera(i)))
            .collect();
        let s = opts.capture.tile_size;
        let tiles: Vec<u32> = camera
            .map(|_| opts.camera_tile_size.unwrap_or(s))
            .into_iter()
            .chain([s; 6])
            .collect();
        let ((triangles, triangles_ms), caps) = rayon::join(
            || {
                let t = Instant::now();
                (DirtTriangles::from_mesh(mesh), ms(t))
            },
            || super::build::build_views(mesh, &pinholes, &opts.capture, &tiles),
        );
        let mut caps = caps?;
        let faces = caps.split_off(caps.len() - 6);
        let camera = caps.pop();
        let camera_ms = camera.as_ref().map_or(0.0, |c| c.stats().total_ms);
        let cube = DirtCube {
            cube: cube_map,
            faces,
        };
        let cube_ms = cube.total_ms();
        let capture_bytes = cube.bytes() + camera.as_ref().map_or(0, DirtCapture::bytes);
        let stats = DirtViewsStats {
            triangles_ms,
            camera_ms,
            cube_ms,
            total_ms: ms(t0),
            triangle_bytes: triangles.bytes(),
            capture_bytes,
        };
        Ok(DirtViews {
            triangles,
            camera,
            cube,
            options: *opts,
            stats,
        })
    }

    /// Every view: the camera view first (if any), then the cube faces +X, -X, +Y, -Y, +Z, -Z.
    pub fn views(&self) -> impl Iterator<Item = &DirtCapture> {
        self.camera.iter().chain(self.cube.faces.iter())
    }

    /// Bytes of the triangle buffer and every capture.
    pub fn bytes(&self) -> u64 {
        self.triangles.bytes() + self.views().map(DirtCapture::bytes).sum::<u64>()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
