//! Cube-map captures: six 90° faces around a point ([`CubeMap::face_camera`], OpenGL face
//! order and orientation), each an `N`-layer capture.
//!
//! **Seamless:** each face is exactly 90°, its frustum planes are the planes through the cube's
//! edges, and the fill rule assigns pixels by their centres only, so the six faces tile the
//! sphere of directions without gaps or overlap; a direction on a face boundary maps to the
//! edge pixel of both faces, which see the same surface up to half a pixel (tested).

use glam::{UVec2, Vec3};
use parallax_core::image::GSample;
use parallax_scene::Scene;
use parallax_scene::camera::{CameraModel, CubeMap};

use super::{LayerCapture, capture_layers};
use crate::raster::{RasterError, RasterOptions, View};

/// Six faces (order +X, -X, +Y, -Y, +Z, -Z) of layers around `cube.eye`.
#[derive(Clone, Debug)]
pub struct CubeCapture {
    pub cube: CubeMap,
    pub faces: Vec<LayerCapture>,
}

impl CubeCapture {
    /// Rasterizes the six faces of `cube`.
    pub fn capture(
        scene: &Scene,
        cube: &CubeMap,
        opts: &RasterOptions,
    ) -> Result<Self, RasterError> {
        let faces = (0..6)
            .map(|i| capture_layers(scene, &View::cube_face(cube, i)?, opts))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            cube: cube.clone(),
            faces,
        })
    }

    /// The pixel of face `face` that direction `dir` passes through (clamped onto the face, so
    /// a direction on the face's boundary maps to its edge pixel); `None` for a direction
    /// behind the face or not finite.
    pub fn pixel_on_face(&self, face: usize, dir: Vec3) -> Option<UVec2> {
        let cam = self.cube.face_camera(face);
        let f = cam.project(self.cube.eye + dir, 0)?;
        let s = self.cube.face_size();
        if !f.is_finite() {
            return None;
        }
        let x = (f.x.max(0.0) as u32).min(s - 1);
        let y = (f.y.max(0.0) as u32).min(s - 1);
        Some(UVec2::new(x, y))
    }

    /// Layer `layer` of face `face` along `dir` (a miss if `dir` is behind that face).
    pub fn sample_face(&self, face: usize, dir: Vec3, layer: usize) -> GSample {
        match self.pixel_on_face(face, dir) {
            Some(p) => self.faces[face].layers.layer(layer).get(p.x, p.y),
            None => GSample::MISS,
        }
    }

    /// Layer `layer` along direction `dir` from the face of its dominant axis.
    pub fn sample(&self, dir: Vec3, layer: usize) -> GSample {
        if !(dir.is_finite() && dir != Vec3::ZERO) {
            return GSample::MISS;
        }
        self.sample_face(CubeMap::face_of(dir), dir, layer)
    }

    /// Bytes of all faces' layers.
    pub fn bytes(&self) -> usize {
        self.faces.iter().map(LayerCapture::bytes).sum()
    }

    /// Total wall-clock milliseconds of the six captures.
    pub fn total_ms(&self) -> f64 {
        self.faces.iter().map(|f| f.stats.total_ms).sum()
    }
}
