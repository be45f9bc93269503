//! The layer-0 guard of the stereo warp ([`super`]): an answer from layer 1 or deeper
//! is re-checked against layer 0 before it is shaded. Ours, not in Widmer et al. 2015.
//!
//! **Layer-0 guard** (default on, the same for every tracer; only with 2+ layers): an answer
//! from layer 1 or deeper is re-checked against layer 0, in two separately switchable parts,
//! [`super::WarpOptions::side_entry_guard`] (a) and [`super::WarpOptions::dda_recheck`] (b).
//! (a) A ray that enters the reference frustum through a side face (not the near plane)
//! already more than 1% behind layer 0's depth at the entry pixel has its true surface outside
//! the captured view (the strip of an eye that the cyclopean reference does not see); a deeper
//! layer there is a wrong guess, so the answer becomes layer 0's occlusion volume at the entry
//! pixel (the single-layer inpainting). (b) A hit in a deeper layer is replaced
//! by layer 0's hit when a one-layer DDA (McGuire & Mara 2014 thin shell, 0.1 m,
//! [`DdaTracer`]) hits layer 0 earlier: rays slipping through the cracks between the per-pixel
//! planes of a layer-0 surface (which a single layer reports as an occlusion volume and
//! inpaints) otherwise land on the surface behind it. The guard is our addition, not in Widmer et al. 2015; its DDA work is counted in the stats.
//! (c) With (b) on, a deeper-layer hit is rejected when its reference view depth is more
//! than 0.1% in front of layer 0's depth at the same pixel (a layer-k plane extrapolated in
//! front of layer 0) or when its sample lies less than 1% behind layer 0 there (a contact surface:
//! floor under a column base, wall behind attached trim, a face buried in another; such
//! samples lie inside or under the occluder, shade black, and a ray meeting their plane
//! meets the visible surface beside it in truth). The answer becomes the layer-0 DDA hit if
//! there is one, else layer 0's occlusion volume at that pixel (then filled). Part (b) is the special case Widmer's own crack handling (flag `O` + crack dilation,
//! §3.2) should cover; with G-buffer normals we now derive `O` from the planes
//! ([`parallax_screen::planes::crack_flags`]), but (a) + crack dilation scores below (a) + (b),
//! so (b) stays.
//!
//! (d) [`super::WarpOptions::silhouette_check`] (with 2+ layers, after (a)-(c)): a deeper-layer hit is
//! kept only when the ray reached it by passing behind a layer-0 *silhouette*. The ray's
//! screen path in the reference is walked back from the hit while the ray lies behind layer
//! 0; if it comes out in front of layer 0 (or leaves the image) without any layer-0 depth
//! discontinuity (> 5% between neighbours, [`EDGE_REL`]) in the 3x3 around the walked pixels,
//! the ray went behind a continuous surface — it entered behind it from outside the captured
//! view or slipped through it beyond the DDA's reach — and the reference knows nothing of what
//! lies between layer 0 and the deeper layer there; the answer becomes layer 0's occlusion
//! volume (then filled). Ours, not in Widmer et al. 2015.
//!
//! (e) [`super::WarpOptions::nearer_neighbour_check`] (with 2+ layers, after (d)): a deeper-layer hit
//! is rejected (layer 0's occlusion volume, then filled) when a layer-0 sample of its bilinear
//! cell (the 2x2 around the hit's projected position, the footprint the resampling reads)
//! is visible background nearer than the hit — more than 5% behind layer 0 at the hit pixel,
//! more than 1% in front of the hit — not on the hit sample's surface, and the ray meets
//! that sample's tangent plane before the hit within one pixel of the sample's centre (its
//! surface extended half a pixel beyond its footprint, into the hit pixel). Such a neighbour
//! shows a surface passing in front of the deeper sample just beside the occluder's edge; a ray
//! passing the edge there meets that surface (or one the layers do not hold, between the two)
//! before the deeper sample. Ours, not in Widmer et al. 2015.
//!
//! What each part gains (and costs) on atrium and Sponza: `docs/notes/synth.md`.

use glam::{UVec2, Vec2, Vec3};
use parallax_core::math::floor_i64;
use parallax_screen::{DdaTracer, ScreenTracer, TraceResult, TraceStats};

use super::hit::{same_surface, same_surface_tol};
use crate::layers::Reference;

/// The layer-0 guard of an answer `r` from layer 1 or deeper (module docs): layer 0's
/// occlusion volume at the entry pixel when the ray enters the reference frustum through a
/// side face already behind layer 0 (its true surface lies outside the captured view); for a
/// hit, layer 0's thin-shell hit when the DDA over layer 0 finds one before it; else `r`.
pub(super) fn guard_deep(
    reference: &Reference,
    side_entry: bool,
    guard: Option<&DdaTracer>,
    ray: &parallax_core::Ray,
    r: TraceResult,
    stats: &mut TraceStats,
) -> TraceResult {
    let deep = match r {
        TraceResult::Hit { layer, .. } | TraceResult::OcclusionVolume { layer, .. } => layer >= 1,
        TraceResult::Miss => false,
    };
    if !deep {
        return r;
    }
    if side_entry
        && let Some(seg) = reference.cube.clip_ray(ray)
        && seg.p0.z > 1e-4
    {
        let g0 = &reference.layers[0];
        let (w, h) = (g0.width(), g0.height());
        let px = ((seg.p0.x * w as f32) as u32).min(w - 1);
        let py = ((seg.p0.y * h as f32) as u32).min(h - 1);
        let d0 = g0.depth[g0.index(px, py)];
        if d0.is_finite() && d0 > 0.0 && seg.w0 as f32 > d0 * (1.0 + ENTRY_BEHIND_REL) {
            return TraceResult::OcclusionVolume {
                layer: 0,
                pixel: UVec2::new(px, py),
                t: seg.t0,
            };
        }
    }
    let (Some(guard), Some(t)) = (guard, r.hit_t()) else {
        return r;
    };
    // (c) A deeper layer's plane met in front of layer 0's depth at the same pixel is an
    // extrapolation, not a surface (layer k lies behind layer 0 in every pixel).
    let in_front = match r {
        TraceResult::Hit {
            layer,
            pixel,
            position,
            ..
        } if layer >= 1 => {
            let g0 = &reference.layers[0];
            let d0 = g0.depth[g0.index(pixel.x, pixel.y)];
            let dh = reference.cube.homogeneous(position).w as f32;
            let gk = &reference.layers[layer as usize];
            let dk = gk.depth[gk.index(pixel.x, pixel.y)];
            d0.is_finite()
                && d0 > 0.0
                && (dh < d0 * (1.0 - IN_FRONT_REL) || dk < d0 * (1.0 + CONTACT_REL))
        }
        _ => false,
    };
    let r0 = guard.trace(ray, stats);
    match (r0, r) {
        (TraceResult::Hit { t: t0, pixel, .. }, _) if t0 < t && interior(reference, pixel) => r0,
        (TraceResult::Hit { .. }, _) if in_front => r0,
        (_, TraceResult::Hit { pixel, t, .. }) if in_front => {
            TraceResult::OcclusionVolume { layer: 0, pixel, t }
        }
        _ => r,
    }
}

/// True when the 4-neighbours of layer-0 `pixel` are covered and lie on its surface (the
/// same-surface test of `warp::bilinear`): a ray meeting layer 0 there slipped through a crack
/// between pixel planes; at a depth edge it may pass legitimately behind the edge pixel.
fn interior(reference: &Reference, pixel: UVec2) -> bool {
    let g = &reference.layers[0];
    let (w, h) = (g.width(), g.height());
    let (x, y) = (pixel.x, pixel.y);
    if x == 0 || y == 0 || x + 1 >= w || y + 1 >= h {
        return false;
    }
    let i = g.index(x, y);
    let (p, n, d) = (g.position[i], g.normal[i], g.depth[i]);
    let tol = same_surface_tol(reference, d);
    [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
        .into_iter()
        .all(|(a, b)| same_surface(g, g.index(a, b), p, n, tol))
}

/// A deeper-layer hit more than this fraction of layer 0's depth in front of layer 0 (same
/// pixel) is rejected by the DDA recheck (guard part c, module docs).
const IN_FRONT_REL: f32 = 0.001;

/// A deeper-layer sample less than this fraction of layer 0's depth behind layer 0 is a
/// contact surface (guard part c, module docs).
const CONTACT_REL: f32 = 0.01;

/// A ray entering the cube through a side face more than this fraction of layer 0's depth
/// behind layer 0 entered from behind it.
const ENTRY_BEHIND_REL: f32 = 0.01;

/// `(layer, pixel, position, t)` of a hit in layer 1 or deeper; `None` for anything else.
#[inline]
fn deep_hit(r: TraceResult) -> Option<(u32, UVec2, Vec3, f32)> {
    match r {
        TraceResult::Hit {
            layer,
            pixel,
            position,
            t,
        } if layer >= 1 => Some((layer, pixel, position, t)),
        _ => None,
    }
}

/// Layer-0 guard part (d) (module docs): a hit `r` in layer 1 or deeper is kept only when the
/// ray reached it by passing behind a layer-0 silhouette. The ray's screen path in the
/// reference is walked back from the hit, one pixel at a time, while the ray lies behind layer
/// 0: the hit is kept as soon as layer 0 shows a depth discontinuity (neighbouring depths
/// differing by more than [`EDGE_REL`], or an uncovered pixel) in the 3x3 around the walked
/// pixel, or when the ray's path is longer than [`SILHOUETTE_SEARCH_PX`]. It becomes layer 0's occlusion
/// volume at the hit pixel (then filled) when the walk reaches a pixel where the ray is in front
/// of layer 0, or leaves the image, without meeting a discontinuity: the ray went behind a
/// continuous surface (through it, or from outside the captured view), where the reference
/// knows nothing of what lies between layer 0 and the deeper layer.
pub(super) fn silhouette_guard(
    reference: &Reference,
    ray: &parallax_core::Ray,
    r: TraceResult,
) -> TraceResult {
    let Some((_, pixel, position, t)) = deep_hit(r) else {
        return r;
    };
    let Some(g0) = reference.layers.first() else {
        return r;
    };
    let Some(seg) = reference.cube.clip_ray(ray) else {
        return r;
    };
    let (w, h) = (g0.width(), g0.height());
    let (wf, hf) = (w as f32, h as f32);
    let s0 = Vec2::new(seg.p0.x * wf, seg.p0.y * hf);
    let s1 = Vec2::new(seg.p1.x * wf, seg.p1.y * hf);
    let hc = reference.cube.homogeneous(position);
    if !(hc.w > 0.0) {
        return r;
    }
    let sq = Vec2::new((hc.x / hc.w) as f32 * wf, (hc.y / hc.w) as f32 * hf);
    let d = s1 - s0;
    let len = d.x.abs().max(d.y.abs());
    if !(len > 1e-6 && len.is_finite() && sq.is_finite()) {
        return r;
    }
    let step = d / len;
    let depth0 = |x: i64, y: i64| -> Option<f32> {
        (x >= 0 && y >= 0 && x < w as i64 && y < h as i64).then(|| {
            let d = g0.depth[g0.index(x as u32, y as u32)];
            if d.is_finite() && d > 0.0 {
                d
            } else {
                f32::INFINITY
            }
        })
    };
    // A depth discontinuity of layer 0 in the 3x3 around (x, y).
    let edge_near = |x: i64, y: i64, dc: f32| -> bool {
        if !dc.is_finite() {
            return true;
        }
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                depth0(x + dx, y + dy).is_some_and(|dn| !((dn - dc).abs() <= EDGE_REL * dn.min(dc)))
            })
        })
    };
    // Perspective-correct view depth of the ray at screen position `s` on the segment.
    let (iw0, iw1) = (1.0 / seg.w0 as f32, 1.0 / seg.w1 as f32);
    let ray_depth = |s: Vec2| -> f32 {
        let u = ((s - s0).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        1.0 / (iw0 + (iw1 - iw0) * u)
    };
    let path = (sq - s0).abs().max_element().ceil() as u32;
    if path > SILHOUETTE_SEARCH_PX {
        return r;
    }
    for k in 0..=path {
        let s = sq - step * k as f32;
        let (x, y) = (floor_i64(s.x), floor_i64(s.y));
        let Some(dc) = depth0(x, y) else {
            break;
        };
        if edge_near(x, y, dc) {
            return r;
        }
        if k > 0 && ray_depth(s) < dc {
            break;
        }
    }
    TraceResult::OcclusionVolume { layer: 0, pixel, t }
}

/// Bound of the walk of [`silhouette_guard`] (pixels).
pub const SILHOUETTE_SEARCH_PX: u32 = 256;

/// Neighbouring layer-0 depths differing by more than this fraction are a silhouette for
/// [`silhouette_guard`].
const EDGE_REL: f32 = 0.05;

/// Layer-0 guard part (e) (module docs): a hit `r` in layer 1 or deeper becomes layer 0's
/// occlusion volume at the hit pixel when one of the four layer-0 samples around the hit's
/// projected position (its bilinear cell) is covered, lies more than [`EDGE_REL`] behind layer
/// 0 at the hit pixel and more than [`NEARER_REL`] in front of the hit, and is not on the hit
/// sample's surface (the same-surface test of the bilinear resampling, tolerance x
/// [`NEARER_SURFACE_TOL`]), and the ray meets that sample's tangent plane before the hit within
/// [`NEARER_EXTENT_PX`] of the sample's pixel centre; any other answer is returned unchanged.
pub(super) fn nearer_neighbour_guard(
    reference: &Reference,
    ray: &parallax_core::Ray,
    r: TraceResult,
) -> TraceResult {
    let Some((layer, pixel, position, t)) = deep_hit(r) else {
        return r;
    };
    let g0 = &reference.layers[0];
    let (w, h) = (g0.width() as i64, g0.height() as i64);
    let d0 = g0.depth[g0.index(pixel.x, pixel.y)];
    let dh = reference.cube.homogeneous(position).w as f32;
    if !(d0.is_finite() && d0 > 0.0) {
        return r;
    }
    let lo = d0 * (1.0 + EDGE_REL);
    let hi = dh * (1.0 - NEARER_REL);
    let gk = &reference.layers[layer as usize];
    let hk = gk.index(pixel.x, pixel.y);
    let (p_hit, n_hit) = (gk.position[hk], gk.normal[hk]);
    let tol = same_surface_tol(reference, dh) * NEARER_SURFACE_TOL;
    let between = |x: i64, y: i64| -> bool {
        if x < 0 || y < 0 || x >= w || y >= h {
            return false;
        }
        let i = g0.index(x as u32, y as u32);
        let d = g0.depth[i];
        if !(d.is_finite() && d > lo && d < hi && !same_surface(g0, i, p_hit, n_hit, tol)) {
            return false;
        }
        // The ray meets the neighbour's tangent plane before the hit, within
        // `NEARER_EXTENT_PX` pixels of the neighbour's centre.
        let (pn, nn) = (g0.position[i], g0.normal[i]);
        let den = nn.dot(ray.dir);
        if den.abs() < 1e-8 {
            return false;
        }
        let tn = nn.dot(pn - ray.origin) / den;
        if !(tn > 0.0 && tn < t) {
            return false;
        }
        let q = reference.cube.homogeneous(ray.origin + ray.dir * tn);
        if !(q.w > 0.0) {
            return false;
        }
        let qx = (q.x / q.w) as f32 * w as f32 - 0.5 - x as f32;
        let qy = (q.y / q.w) as f32 * h as f32 - 0.5 - y as f32;
        qx.abs().max(qy.abs()) <= NEARER_EXTENT_PX
    };
    let hc = reference.cube.homogeneous(position);
    let fx = (hc.x / hc.w) as f32 * w as f32 - 0.5;
    let fy = (hc.y / hc.w) as f32 * h as f32 - 0.5;
    if !(fx.is_finite() && fy.is_finite()) {
        return r;
    }
    let (x0, y0) = (floor_i64(fx), floor_i64(fy));
    let found = [(0, 0), (1, 0), (0, 1), (1, 1)]
        .iter()
        .any(|(dx, dy)| between(x0 + dx, y0 + dy));
    if found {
        TraceResult::OcclusionVolume { layer: 0, pixel, t }
    } else {
        r
    }
}

/// A layer-0 neighbour must lie more than this fraction of the hit's depth in front of a
/// deeper-layer hit to reject it (guard part e).
const NEARER_REL: f32 = 0.01;

/// Same-surface tolerance of guard part (e), in units of the bilinear one.
const NEARER_SURFACE_TOL: f32 = 2.0;

/// Guard part (e): a neighbour's surface counts where the ray meets its tangent plane within
/// this many pixels (max norm) of the neighbour's centre (its own footprint and half a pixel
/// beyond).
const NEARER_EXTENT_PX: f32 = 1.0;
