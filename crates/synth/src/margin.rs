//! Reference views widened by a margin, for reprojections whose rays start away from the
//! reference eye: lens rays (depth of field, Widmer et al. 2015 §5.2) and the off-axis views
//! of a light field (§5.3) see, near the image border, parts of the scene just outside the
//! reference's frustum, so the reference is captured a few pixels wider on each side (same
//! frame, same pixel size, same image centre).
//!
//! **How wide.** A ray from a point `b` off the reference eye (`|b| <= B` along the image
//! plane) that passes through the reference ray of film position `f` at view depth `F` (the
//! lens's focus distance, the light field's focal plane) meets view depth `d` at
//! `b (1 - d/F) + q(f) d/F`, which the reference sees `B f_px |1/d - 1/F|` pixels from `f`
//! (`f_px = H / (2 tan(fov_y / 2))`). Over the depths `d >= d_min` of the scene that is at
//! most `B f_px max(1/d_min - 1/F, 1/F)` ([`parallax_px`]), with `d_min` probed by BVH
//! rays on a coarse grid of the view ([`nearest_depth`], every [`PROBE_STRIDE`]-th pixel,
//! not timed as part of `T_ref`), capped at [`MAX_MARGIN_FRACTION`] of `max(W, H)`.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_scene::camera::{CameraModel, Pinhole};

/// Stride of the nearest-depth probe (pixels).
pub const PROBE_STRIDE: u32 = 4;
/// A margin is at most this fraction of `max(W, H)`.
pub const MAX_MARGIN_FRACTION: f32 = 0.25;

/// `p` with `gx` more pixels on the left and right and `gy` more at the top and bottom:
/// same frame, pixel size and image centre (an off-axis window keeps its offset). Pixel
/// `(x, y)` of `p` is pixel `(x + gx, y + gy)` of the result.
pub fn widened(p: &Pinhole, gx: u32, gy: u32) -> Pinhole {
    let (w, h) = (p.width + 2 * gx, p.height + 2 * gy);
    let sy = h as f32 / p.height as f32;
    let sx = w as f32 / p.width as f32;
    Pinhole::from_frame(p.frame, w, h, p.tan_half_y * sy)
        .with_shift(Vec2::new(p.shift.x / sx, p.shift.y / sy))
}

/// The nearest view depth the BVH finds on a coarse grid of `p`'s pixel rays (module docs);
/// `None` when every probe misses.
pub fn nearest_depth(bvh: &Bvh, p: &Pinhole) -> Option<f32> {
    let mut d_min = f32::INFINITY;
    for y in (0..p.height).step_by(PROBE_STRIDE as usize) {
        for x in (0..p.width).step_by(PROBE_STRIDE as usize) {
            let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let Some(cr) = p.generate_ray(film, Vec2::splat(0.5), 0) else {
                continue;
            };
            if let Some(hit) = bvh.closest_hit(&cr.ray) {
                d_min = d_min.min(cr.view_depth(hit.t));
            }
        }
    }
    (d_min.is_finite() && d_min > 0.0).then_some(d_min)
}

/// The largest displacement in pixels of `p` of a ray from up to `baseline` metres off its
/// eye through the reference ray's point at depth `focus`, over depths `>= d_min` (all
/// depths beyond `focus` when `None`; module docs).
pub fn parallax_px(p: &Pinhole, baseline: f32, focus: f32, d_min: Option<f32>) -> f32 {
    let f_px = p.height as f32 / (2.0 * p.tan_half_y);
    let near = d_min.map_or(0.0, |d| (1.0 / d - 1.0 / focus).abs());
    baseline * f_px * near.max(1.0 / focus)
}

/// The margin in whole pixels for rays up to `baseline` off `p`'s eye focused at `focus`
/// over the scene of `bvh` (module docs): the displacement rounded up, plus one pixel.
pub fn margin_px(bvh: &Bvh, p: &Pinhole, baseline: f32, focus: f32) -> u32 {
    let px = parallax_px(p, baseline, focus, nearest_depth(bvh, p));
    let cap = MAX_MARGIN_FRACTION * p.width.max(p.height) as f32;
    (px.min(cap).ceil() as u32) + 1
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use parallax_scene::CameraDesc;

    #[test]
    fn widening_keeps_pixel_size_and_centre() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 50.0);
        let p = Pinhole::new(&desc, 64, 48)
            .unwrap()
            .with_shift(Vec2::new(0.2, -0.1));
        let q = widened(&p, 5, 3);
        assert_eq!((q.width, q.height), (74, 54));
        for film in [
            Vec2::new(0.5, 0.5),
            Vec2::new(31.25, 40.0),
            Vec2::new(63.5, 47.5),
        ] {
            let a = p.camera_dir(film);
            let b = q.camera_dir(film + Vec2::new(5.0, 3.0));
            assert!((a - b).length() < 1e-5, "{a} {b}");
        }
    }

    #[test]
    fn displacement_grows_with_baseline_and_nearness() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0);
        let p = Pinhole::new(&desc, 100, 100).unwrap();
        // f_px = 50: at infinity 0.1 m off, focused at 10 m: 0.1 * 50 / 10.
        assert!((parallax_px(&p, 0.1, 10.0, None) - 0.5).abs() < 1e-6);
        assert!((parallax_px(&p, 0.1, 10.0, Some(1.0)) - 4.5).abs() < 1e-5);
        assert_eq!(parallax_px(&p, 0.0, 10.0, Some(1.0)), 0.0);
    }
}
