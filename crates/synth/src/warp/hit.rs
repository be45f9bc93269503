//! What a warped pixel's ray found and how its colour is read ([`HitKind`], [`Resample`]), and
//! the same-surface test of the depth-aware resampling and of the layer-0 guard: a neighbour
//! sample is the hit's surface when it lies within [`SAME_SURFACE_PX`] pixel footprints of the
//! hit sample's tangent plane and its normal is within 60° (our choice; Widmer et al. 2015,
//! §5.1, leave the colour lookup open).

use glam::Vec3;

use crate::layers::Reference;

/// How a hit's colour is read from its layer (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum Resample {
    /// The hit pixel's colour.
    Nearest,
    /// Depth-aware bilinear interpolation at the hit's sub-pixel position (same layer, same
    /// surface neighbours only, weights renormalised).
    #[default]
    Bilinear,
}

/// Neighbours farther than this many pixel footprints (at the hit's depth) from the hit
/// sample's tangent plane are another surface and are not blended.
pub const SAME_SURFACE_PX: f32 = 1.0;

/// What a target pixel's ray found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HitKind {
    /// A captured surface of this layer.
    Hit(u8),
    /// Nothing: left the reference frustum (environment colour).
    Miss,
    /// An occlusion volume of this layer (inpainted).
    Occlusion(u8),
}

impl HitKind {
    /// The layer the answer came from (`None` for a miss).
    pub fn layer(self) -> Option<u8> {
        match self {
            HitKind::Hit(l) | HitKind::Occlusion(l) => Some(l),
            HitKind::Miss => None,
        }
    }
}

/// Distance from a tangent plane under which a neighbour at view depth `depth` is the same
/// surface ([`SAME_SURFACE_PX`] pixel footprints + 0.01% of the depth).
#[inline]
pub(crate) fn same_surface_tol(reference: &Reference, depth: f32) -> f32 {
    let footprint = depth * 2.0 * reference.camera.tan_half_y / reference.height() as f32;
    SAME_SURFACE_PX * footprint + 1e-4 * depth
}

/// True when sample `i` of `g` is covered and lies on the surface through `p` with normal `n`
/// (within `tol` of the plane, normals within 60°).
#[inline]
pub(crate) fn same_surface(
    g: &parallax_core::GBuffer,
    i: usize,
    p: Vec3,
    n: Vec3,
    tol: f32,
) -> bool {
    g.depth[i].is_finite()
        && g.depth[i] > 0.0
        && n.dot(g.normal[i]) > 0.5
        && n.dot(g.position[i] - p).abs() <= tol
}
