//! DIRT's multi-view setup (§4.1 "Overview"): six captures arranged as a cube map around the
//! eye (Vardis et al. 2016), one [`DirtCapture`] per face in the order +X, -X, +Y, -Y, +Z, -Z.
//! Face frames are the cube map's (mirrored) ones; the capture never relies on winding.

use parallax_scene::TriangleMesh;
use parallax_scene::camera::CubeMap;

use super::{DirtCapture, DirtError, DirtOptions};

/// Six DIRT captures of a cube map.
#[derive(Clone, Debug)]
pub struct DirtCube {
    pub cube: CubeMap,
    pub faces: Vec<DirtCapture>,
}

impl DirtCube {
    /// Builds the six faces (the triangle setup in one pass over the mesh for all faces, the
    /// fill of every band of every face in one parallel loop). `opts.max_entries` bounds the
    /// entries of the whole cube.
    pub fn build(
        mesh: &TriangleMesh,
        cube: &CubeMap,
        opts: &DirtOptions,
    ) -> Result<DirtCube, DirtError> {
        let views: Vec<_> = (0..6).map(|i| cube.face_camera(i)).collect();
        Ok(DirtCube {
            cube: cube.clone(),
            faces: super::build::build_views(mesh, &views, opts, &[opts.tile_size; 6])?,
        })
    }

    /// Face `i` (0..6).
    pub fn face(&self, i: usize) -> &DirtCapture {
        &self.faces[i]
    }

    /// Bytes of all six captures.
    pub fn bytes(&self) -> u64 {
        self.faces.iter().map(DirtCapture::bytes).sum()
    }

    /// Build time of all faces (ms).
    pub fn total_ms(&self) -> f64 {
        self.faces.iter().map(|f| f.stats().total_ms).sum()
    }
}
