//! Normals from depth for depth-only inputs, with a per-pixel depth-discontinuity flag.
//!
//! Widmer et al. 2015 (§3.2, "Bottom level generation") initialise every quad-tree leaf from
//! a depth pixel as a tiny plane with a normal and a binary flag `O` marking planes "close to a
//! depth discontinuity"; all their examples compute the normals from depth rather than from a
//! G-buffer. This module does the same for a pinhole view:
//!
//! 1. Each pixel is unprojected to camera space, `q = z * camera_dir(x + 0.5, y + 0.5)` (the
//!    direction has `z = -1`, so the view depth `z` is the ray parameter).
//! 2. Per axis, of the two one-sided differences (left/right, up/down) the one whose
//!    neighbours continue the pixel's surface best is taken, so normals never smooth across
//!    a discontinuity. "Best" is the second-order extrapolation error in **inverse** depth
//!    `u = 1 / z`: on a plane seen through a pinhole `u` is an affine function of the film
//!    position, so `e = |2 u(x±1) - u(x±2) - u(x)| / u(x)` is zero on any plane up to rounding
//!    (also at grazing angles, where depth itself is far from linear). A side with only one
//!    neighbour (next to the image border) falls back to the zeroth-order `|u(x±1) - u(x)| /
//!    u(x)`; a side whose neighbour is outside the image or a miss is unavailable.
//! 3. The normal is `T_x × T_y` of the chosen differences, turned to face the camera, rotated
//!    to **world space**.
//!
//! **Flag** (`O`): the edge between two neighbouring pixels `p`, `p + 1` is a discontinuity when
//! neither surface continues across it, i.e. both the extrapolation from `p`'s far side
//! (`u(p - 1), u(p)` predicting `u(p + 1)`) and from `p + 1`'s far side (`u(p + 2), u(p + 1)`
//! predicting `u(p)`) miss by more than `max_rel_error` (relative to the predicted pixel's
//! inverse depth). An edge to a miss pixel is always a discontinuity. A pixel is flagged when
//! any of its four edges is. On a depth step both pixels that touch the step are flagged and
//! nothing else; creases sharper than the threshold are flagged too (the cracks Widmer's flag
//! is meant to mask appear between differently oriented neighbours, so that is desired).
//! Limitation: across a run of at most two hit pixels between the border and/or misses no
//! second-order prediction exists, the zeroth-order fallback is used and a slanted surface
//! there may be flagged (conservatively).
//!
//! **Threshold.** For a plane the prediction error is rounding only: depths are f32 (relative
//! error `2^-24`), and `2 u1 - u2 - u0` amplifies it at most 4-fold, so errors stay below
//! `1e-6`. A curved surface of radius `r` at depth `z` seen with pixel footprint `s` gives a
//! relative error of about `s^2 / (r z)`, far below 1% for any surface larger than a few
//! pixels. A depth jump of relative size `Δz / z` gives an error of about `Δz / z`. The
//! default [`DEFAULT_MAX_REL_ERROR`] = 1% therefore separates rounding and smooth curvature from
//! jumps of more than 1% of the depth.

use glam::{DVec3, Vec3};
use parallax_core::Image;
use parallax_scene::camera::Pinhole;

use crate::RasterError;

/// Default relative inverse-depth extrapolation error above which neighbours are treated as
/// different surfaces (see the module docs for the derivation).
pub const DEFAULT_MAX_REL_ERROR: f32 = 0.01;

/// Per-pixel normals reconstructed from depth, and the discontinuity flag `O`.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthNormals {
    /// Unit world-space normals facing the camera; `Vec3::ZERO` for misses. A hit pixel with
    /// no usable neighbour along some axis gets the direction back to the eye (and is flagged).
    pub normals: Image<Vec3>,
    /// True where the pixel touches a depth discontinuity (or a miss); false for misses.
    pub discontinuity: Image<bool>,
}

impl DepthNormals {
    /// Number of flagged pixels.
    pub fn flagged(&self) -> usize {
        self.discontinuity.data().iter().filter(|&&f| f).count()
    }
}

/// Relative extrapolation error of predicting `c` from the neighbours `n1` (adjacent) and `n2`
/// (one further) on one side; `None` when the side is unavailable (`n1` missing).
#[inline]
fn side_error(c: f64, n1: Option<f64>, n2: Option<f64>) -> Option<f64> {
    let n1 = n1?;
    let pred = match n2 {
        Some(n2) => 2.0 * n1 - n2,
        None => n1,
    };
    Some((pred - c).abs() / c)
}

/// Camera-space point of pixel `(x, y)` at view depth `z` (f64 for precise differences).
#[inline]
fn unproject(cam: &Pinhole, x: u32, y: u32, z: f64) -> DVec3 {
    let (w, h) = (cam.width as f64, cam.height as f64);
    let thy = cam.tan_half_y as f64;
    let thx = thy * w / h;
    let ndc_x = 2.0 * (x as f64 + 0.5) / w - 1.0;
    let ndc_y = 1.0 - 2.0 * (y as f64 + 0.5) / h;
    DVec3::new(
        (ndc_x + cam.shift.x as f64) * thx * z,
        (ndc_y + cam.shift.y as f64) * thy * z,
        -z,
    )
}

/// Normals and discontinuity flags from a view-depth image (`+inf`, NaN or `<= 0` = miss) seen
/// by `camera` (its size must match). `max_rel_error` is the flag threshold (module docs;
/// [`DEFAULT_MAX_REL_ERROR`] is a good default).
pub fn normals_from_depth(
    depth: &Image<f32>,
    camera: &Pinhole,
    max_rel_error: f32,
) -> Result<DepthNormals, RasterError> {
    let (w, h) = (depth.width(), depth.height());
    if (w, h) != (camera.width, camera.height) {
        return Err(RasterError::InvalidView(format!(
            "depth image is {w}x{h} but the camera is {}x{}",
            camera.width, camera.height
        )));
    }
    if !(max_rel_error.is_finite() && max_rel_error > 0.0) {
        return Err(RasterError::InvalidOptions(format!(
            "max_rel_error must be finite and > 0, got {max_rel_error}"
        )));
    }
    let tau = max_rel_error as f64;
    // Inverse depth per pixel, None for misses.
    let inv: Vec<Option<f64>> = depth
        .data()
        .iter()
        .map(|&z| (z.is_finite() && z > 0.0).then(|| 1.0 / z as f64))
        .collect();
    let at = |x: i64, y: i64| -> Option<f64> {
        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
            None
        } else {
            inv[y as usize * w as usize + x as usize]
        }
    };
    let basis = camera.frame.basis.as_dmat3();
    let mut normals = Vec::with_capacity(inv.len());
    let mut flags = Vec::with_capacity(inv.len());
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let Some(c) = at(x, y) else {
                normals.push(Vec3::ZERO);
                flags.push(false);
                continue;
            };
            let z = 1.0 / c;
            let p = unproject(camera, x as u32, y as u32, z);
            let mut flag = false;
            let mut tangents = [DVec3::ZERO; 2];
            let mut ok = true;
            for (axis, (dx, dy)) in [(1i64, 0i64), (0, 1)].into_iter().enumerate() {
                let fwd = side_error(c, at(x + dx, y + dy), at(x + 2 * dx, y + 2 * dy));
                let bwd = side_error(c, at(x - dx, y - dy), at(x - 2 * dx, y - 2 * dy));
                // Edge discontinuities: the neighbour's far-side extrapolation of this pixel is
                // `fwd` / `bwd`; this pixel's far-side extrapolation of the neighbour is the
                // neighbour's error from the other direction.
                for s in [1i64, -1] {
                    let (nx, ny) = (x + s * dx, y + s * dy);
                    if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        continue; // image border: not an edge
                    }
                    let Some(nc) = at(nx, ny) else {
                        flag = true; // edge to a miss
                        continue;
                    };
                    // The neighbour's error seen from its far side (which predicts this pixel).
                    let theirs = if s == 1 { fwd } else { bwd };
                    // This pixel's surface (from the opposite side) predicting the neighbour.
                    let ours = side_error(nc, Some(c), at(x - s * dx, y - s * dy));
                    let bad = |e: Option<f64>| e.is_none_or(|e| e > tau);
                    if bad(theirs) && bad(ours) {
                        flag = true;
                    }
                }
                let forward = match (fwd, bwd) {
                    (Some(f), Some(b)) => f <= b,
                    (Some(_), None) => true,
                    (None, Some(_)) => false,
                    (None, None) => {
                        ok = false;
                        continue;
                    }
                };
                let t = if forward {
                    let n = at(x + dx, y + dy).unwrap_or(c);
                    unproject(camera, (x + dx) as u32, (y + dy) as u32, 1.0 / n) - p
                } else {
                    let n = at(x - dx, y - dy).unwrap_or(c);
                    p - unproject(camera, (x - dx) as u32, (y - dy) as u32, 1.0 / n)
                };
                tangents[axis] = t;
            }
            let mut n = tangents[0].cross(tangents[1]);
            if !ok || !(n.length_squared() > 0.0) || !n.is_finite() {
                n = -p;
                flag = true;
            } else if n.dot(p) > 0.0 {
                n = -n;
            }
            normals.push((basis * n).normalize_or_zero().as_vec3());
            flags.push(flag);
        }
    }
    let map = |e: parallax_core::CoreError| RasterError::Size(e);
    Ok(DepthNormals {
        normals: Image::from_vec(w, h, normals).map_err(map)?,
        discontinuity: Image::from_vec(w, h, flags).map_err(map)?,
    })
}
