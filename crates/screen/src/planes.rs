//! Per-pixel planes of a captured layer in the unit cube (Widmer et al. 2015, §3.2, "Bottom
//! level generation": "each pixel is represented as a tiny plane with a normal vector N and
//! plane origin P_origin", plus the binary flag `O` marking planes close to a depth
//! discontinuity).
//!
//! For each covered pixel `(i, j)` (finite positive view depth `d`) the sample point is the
//! pixel-centre ray at depth `d` (as Widmer, whose `P_origin` has the pixel's 2D position); its
//! world normal comes from the G-buffer or from depth ([`parallax_raster::normals`]); the world
//! plane through them is mapped to the cube by the covector transform
//! ([`UnitCube::map_plane`]). The plane is valid only over the pixel's **footprint**: the
//! column `[i/W, (i+1)/W] x [j/H, (j+1)/H] x [0, 1]` of the cube (its reference-view frustum
//! between near and far).
//!
//! Stored flat: `normal[k]`, `offset[k]` with `normal · P = offset` (unit cube normal facing
//! the eye, `normal.z <= 0`), `flag[k]` (= `O`), `k = j W + i`. Uncovered pixels (and planes
//! that map degenerately) have `normal == Vec3::ZERO`.

use glam::Vec3;
use parallax_core::{GBuffer, Image};
use parallax_raster::normals::normals_from_depth;

use crate::{ScreenError, UnitCube};

/// Where the per-pixel normals come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalSource {
    /// The G-buffer's shading normals; `O` is false everywhere.
    GBuffer,
    /// Reconstructed from depth with the given flag threshold (Widmer's choice; `O` from
    /// [`parallax_raster::normals::normals_from_depth`]).
    Depth { max_rel_error: f32 },
}

/// The per-pixel cube planes of one layer.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerPlanes {
    pub width: u32,
    pub height: u32,
    pub normal: Vec<Vec3>,
    pub offset: Vec<f32>,
    pub flag: Vec<bool>,
}

impl LayerPlanes {
    /// Planes of `layer` (captured from `cube.camera`).
    pub fn build(
        cube: &UnitCube,
        layer: &GBuffer,
        source: NormalSource,
    ) -> Result<Self, ScreenError> {
        let cam = &cube.camera;
        let (w, h) = (layer.width(), layer.height());
        if (w, h) != (cam.width, cam.height) {
            return Err(ScreenError::Mismatch(format!(
                "layer is {w}x{h} but the reference camera is {}x{}",
                cam.width, cam.height
            )));
        }
        let (normals, flag) = match source {
            NormalSource::GBuffer => (layer.normal.clone(), vec![false; layer.depth.len()]),
            NormalSource::Depth { max_rel_error } => {
                let depth = Image::from_vec(w, h, layer.depth.clone())?;
                let dn = normals_from_depth(&depth, cam, max_rel_error)?;
                (dn.normals.into_vec(), dn.discontinuity.into_vec())
            }
        };
        let n = layer.depth.len();
        let mut normal = vec![Vec3::ZERO; n];
        let mut offset = vec![0.0; n];
        for j in 0..h {
            for i in 0..w {
                let k = (j * w + i) as usize;
                let d = layer.depth[k];
                if !(d.is_finite() && d > 0.0) || normals[k] == Vec3::ZERO {
                    continue;
                }
                let film = glam::Vec2::new(i as f32 + 0.5, j as f32 + 0.5);
                let p = cam.frame.position + cam.frame.dir_to_world(cam.camera_dir(film)) * d;
                if let Some((nc, c)) = cube.map_plane(p, normals[k]) {
                    normal[k] = nc;
                    offset[k] = c;
                }
            }
        }
        Ok(Self {
            width: w,
            height: h,
            normal,
            offset,
            flag,
        })
    }

    /// True when pixel `k` holds a plane.
    #[inline]
    pub fn covered(&self, k: usize) -> bool {
        self.normal[k] != Vec3::ZERO
    }

    /// Signed distance-like value `normal · p - offset` of pixel `k`'s plane: positive in front
    /// (towards the eye), negative behind (inside the occlusion volume).
    #[inline]
    pub fn side(&self, k: usize, p: Vec3) -> f32 {
        self.normal[k].dot(p) - self.offset[k]
    }

    /// Bytes of the planes.
    pub fn bytes(&self) -> usize {
        self.normal.len() * (size_of::<Vec3>() + size_of::<f32>() + size_of::<bool>())
    }
}
