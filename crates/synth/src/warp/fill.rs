//! Widmer et al. 2015, Fig. 6e: the colour of an occlusion-volume answer from the nearest
//! background pixel along the ray's epipolar line.

use glam::{UVec2, Vec2};
use parallax_core::Rgb;

use crate::layers::Reference;

/// Steps of the background search of `background_fill` (pixels along the epipolar line).
pub const BACKGROUND_SEARCH_PX: u32 = 8;

/// A pixel deeper than the occluder edge by more than this fraction of its depth is
/// background for `background_fill`.
const BACKGROUND_REL: f32 = 0.01;

/// Fig. 6e's "nearest background pixel" for an occlusion-volume answer at `pixel` of `layer`
/// (module docs): the occluder edge depth is the nearer of `pixel` and the next pixel along
/// the ray's screen direction in the reference; walking back from `pixel` against that
/// direction one pixel at a time (at most [`BACKGROUND_SEARCH_PX`] steps), the first pixel
/// that is uncovered or deeper than the edge by [`BACKGROUND_REL`] gives the colour. `None`
/// when there is none (the caller keeps the crossed pixel's colour).
pub(super) fn background_fill(
    reference: &Reference,
    layer: u32,
    pixel: UVec2,
    ray: &parallax_core::Ray,
) -> Option<Rgb> {
    let g = reference.layers.get(layer as usize)?;
    let colors = reference.colors.get(layer as usize)?;
    let (w, h) = (g.width(), g.height());
    if pixel.x >= w || pixel.y >= h {
        return None;
    }
    let seg = reference.cube.clip_ray(ray)?;
    let d = seg.p1 - seg.p0;
    let dir = Vec2::new(d.x * w as f32, d.y * h as f32);
    let len = dir.x.abs().max(dir.y.abs());
    if !(len > 1e-6 && len.is_finite()) {
        return None;
    }
    // One pixel per step along the major axis.
    let step = dir / len;
    let centre = Vec2::new(pixel.x as f32 + 0.5, pixel.y as f32 + 0.5);
    let at = |p: Vec2| -> Option<usize> {
        (p.x >= 0.0 && p.y >= 0.0 && p.x < w as f32 && p.y < h as f32)
            .then(|| g.index(p.x as u32, p.y as u32))
    };
    let depth = |i: usize| {
        let d = g.depth[i];
        if d.is_finite() && d > 0.0 {
            d
        } else {
            f32::INFINITY
        }
    };
    let mut edge = depth(g.index(pixel.x, pixel.y));
    if let Some(i) = at(centre + step) {
        edge = edge.min(depth(i));
    }
    if !edge.is_finite() {
        return None;
    }
    let limit = edge * (1.0 + BACKGROUND_REL);
    for k in 0..=BACKGROUND_SEARCH_PX {
        let i = at(centre - step * k as f32)?;
        if depth(i) > limit {
            let (x, y) = (i as u32 % w, i as u32 / w);
            return Some(if g.depth[i].is_finite() && g.depth[i] > 0.0 {
                *colors.get(x, y)
            } else {
                reference.environment_colour(ray.dir)
            });
        }
    }
    None
}
