//! A region of interest for the layered depth cube fitted to a view (Bürger et al. 2007 build
//! the cube over the whole scene, §1.2; this fitting is ours): an interior whose bounds are
//! dominated by one huge surface (the classroom's 222 m ground quad) spreads the LDI pixels
//! over that surface, so the room the camera looks at gets a few pixels per metre. The fitted
//! box holds what the view sees, with a margin for the surfaces its secondary rays reach
//! (behind the camera, around corners).
//!
//! **Fit.** Per axis the `[trim, 1 - trim]` quantiles of the G-buffer's hit positions (a few
//! pixels seeing far geometry through a window or a door do not stretch the box), joined with
//! the camera's position, grown by `margin` times the box's longest side on every side, and
//! clipped to the scene bounds. The fit is kept only when it buys resolution: when its longest
//! side is at most [`MIN_GAIN`]`⁻¹` of the scene's (the classroom: 19 m of 222 m); otherwise
//! (Sponza, a room the view sees whole) it would only cut geometry off, and the region is the
//! scene's bounds (`None`), as it is without any hit.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `trim` | f32 | [`DEFAULT_TRIM`] (0.01) | fraction of the hits ignored at each end of each axis |
//! | `margin` | f32 | [`DEFAULT_MARGIN`] (0.25) | growth on every side, fraction of the longest side |
//!
//! **Invariant:** the result is `None` or a box with `min < max` on every axis inside the scene
//! bounds (so [`parallax_raster::ldc::LayeredDepthCube::build`] accepts it).

use glam::Vec3;
use parallax_core::Aabb;
use parallax_core::image::GBuffer;
use parallax_scene::Scene;
use parallax_scene::camera::Pinhole;

/// Default fraction of hits ignored at each end of each axis.
pub const DEFAULT_TRIM: f32 = 0.01;

/// Default margin, fraction of the fitted box's longest side.
pub const DEFAULT_MARGIN: f32 = 0.25;

/// The fitted box is used only when the scene's longest side is at least this many times its
/// longest side.
pub const MIN_GAIN: f32 = 2.0;

/// The region of interest of `camera`'s view `g` of `scene` (module docs), or `None` when the
/// view sees nothing or the fit gains less than [`MIN_GAIN`] in resolution.
pub fn view_roi(
    scene: &Scene,
    camera: &Pinhole,
    g: &GBuffer,
    trim: f32,
    margin: f32,
) -> Option<[Vec3; 2]> {
    let hits: Vec<Vec3> = (0..g.depth.len())
        .filter(|&i| g.depth[i].is_finite() && g.position[i].is_finite())
        .map(|i| g.position[i])
        .collect();
    if hits.is_empty() {
        return None;
    }
    let trim = trim.clamp(0.0, 0.49);
    let (mut lo, mut hi) = (Vec3::ZERO, Vec3::ZERO);
    let mut values = Vec::with_capacity(hits.len());
    for axis in 0..3 {
        values.clear();
        values.extend(hits.iter().map(|p| p[axis]));
        values.sort_unstable_by(f32::total_cmp);
        let n = values.len();
        let k = ((trim * n as f32) as usize).min(n - 1);
        lo[axis] = values[k];
        hi[axis] = values[n - 1 - k];
    }
    let eye = camera.frame.position;
    let fitted = Aabb::new(lo.min(eye), hi.max(eye));
    let grow = margin.max(0.0) * fitted.extent().max_element();
    let scene_box = scene.mesh.bounds();
    let lo = (fitted.min - grow).max(scene_box.min);
    let hi = (fitted.max + grow).min(scene_box.max);
    if !lo.cmplt(hi).all() || MIN_GAIN * (hi - lo).max_element() > scene_box.extent().max_element()
    {
        return None;
    }
    Some([lo, hi])
}
