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
//!
//! **Flag `O` with G-buffer normals** ([`crack_flags`], [`NormalSource::GBufferFlagged`];
//! plain [`NormalSource::GBuffer`] flags nothing). Widmer et al. (§3.2) store "a binary
//! flag `O`, which indicates whether the plane is close to a depth discontinuity", used "to
//! adaptively dilate the screen-space bounding-box to mask tiny cracks between neighbors with
//! different orientations"; their normals come from depth (our [`NormalSource::Depth`], whose
//! flag is the depth-discontinuity test of [`parallax_raster::normals`]). G-buffer normals
//! (shading normals, interpolated across triangles) need their own definition, since nothing
//! in the normal tells where the per-pixel planes fail to join. Ours, stated on the planes
//! themselves (what the traversal intersects): two 4-neighbour pixels `p`, `q` *meet* at their
//! shared footprint edge when, at both end points of that edge, their planes' cube depths
//! differ by at most `max_rel_gap` in relative inverse depth,
//! `|z_p - z_q| (1/n - 1/f) / u <= max_rel_gap` with `u = 1/n - z_p (1/n - 1/f)` the inverse
//! view depth at `p`'s sample (cube `z` is affine in inverse depth, so this is the relative
//! depth gap up to second order). A covered pixel is flagged when it does not meet one of its
//! covered 4-neighbours, or when a 4-neighbour inside the image is uncovered (an edge to a miss
//! is a depth discontinuity, as for depth normals); the image border is not an edge. A real
//! depth step fails the test on both of its sides, and so do the unaligned neighbours §6
//! ("Limitations") blames for the cracks rays slip through; planes that join (a flat floor,
//! up to the f16 slope rounding of the quad-tree's nodes) are not flagged. Defaults [`CRACK_REL_GAP`] and
//! [`CRACK_MAX_GAP`]; a finite upper bound `max_rel_gap` restricts the flag to small gaps
//! (cracks proper) and leaves real depth steps and edges to uncovered pixels unflagged.
//!
//! G-buffer flags are opt-in ([`NormalSource::GBufferFlagged`]): crack dilation on them stops
//! rays that legitimately pass behind an edge and scored below the warp's DDA re-check
//! (`docs/notes/screen.md`).

use glam::Vec3;
use parallax_core::{GBuffer, Image};
use parallax_raster::normals::normals_from_depth;

use crate::{ScreenError, UnitCube};

/// Where the per-pixel normals come from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalSource {
    /// The G-buffer's shading normals; `O` is false everywhere (the default: crack dilation
    /// with [`NormalSource::GBufferFlagged`] scored worse, module docs).
    GBuffer,
    /// The G-buffer's shading normals with `O` from [`crack_flags`]: set where a 4-neighbour's
    /// plane misses this pixel's plane at their shared footprint edge by a relative gap in
    /// `(min_rel_gap, max_rel_gap]` (`max_rel_gap = inf`: every depth step and every edge to an
    /// uncovered pixel counts). [`NormalSource::gbuffer_flagged`] gives the defaults.
    GBufferFlagged { min_rel_gap: f32, max_rel_gap: f32 },
    /// Reconstructed from depth with the given flag threshold (Widmer's choice; `O` from
    /// [`parallax_raster::normals::normals_from_depth`]).
    Depth { max_rel_error: f32 },
}

impl NormalSource {
    /// [`NormalSource::GBufferFlagged`] with [`CRACK_REL_GAP`] and [`CRACK_MAX_GAP`].
    pub fn gbuffer_flagged() -> Self {
        NormalSource::GBufferFlagged {
            min_rel_gap: CRACK_REL_GAP,
            max_rel_gap: CRACK_MAX_GAP,
        }
    }
}

/// The size of `layer`, which must be the reference camera's.
pub(crate) fn layer_size(cube: &UnitCube, layer: &GBuffer) -> Result<(u32, u32), ScreenError> {
    let cam = &cube.camera;
    let (w, h) = (layer.width(), layer.height());
    if (w, h) != (cam.width, cam.height) {
        return Err(ScreenError::Mismatch(format!(
            "layer is {w}x{h} but the reference camera is {}x{}",
            cam.width, cam.height
        )));
    }
    Ok((w, h))
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
        let (w, h) = layer_size(cube, layer)?;
        let (normals, depth_flag) = match source {
            NormalSource::GBuffer => (layer.normal.clone(), Some(vec![false; layer.depth.len()])),
            NormalSource::GBufferFlagged { .. } => (layer.normal.clone(), None),
            NormalSource::Depth { max_rel_error } => {
                let depth = Image::from_vec(w, h, layer.depth.clone())?;
                let dn = normals_from_depth(&depth, cam, max_rel_error)?;
                (dn.normals.into_vec(), Some(dn.discontinuity.into_vec()))
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
        let flag = match (depth_flag, source) {
            (Some(f), _) => f,
            (None, src) => {
                let (lo, hi) = match src {
                    NormalSource::GBufferFlagged {
                        min_rel_gap,
                        max_rel_gap,
                    } => (min_rel_gap, max_rel_gap),
                    _ => (CRACK_REL_GAP, CRACK_MAX_GAP),
                };
                let (wf, hf) = (w as f32, h as f32);
                crack_flags(cube, w, h, lo, hi, |k| {
                    let n = normal[k];
                    if n == Vec3::ZERO {
                        return None;
                    }
                    let (i, j) = (k as u32 % w, k as u32 / w);
                    let (xc, yc) = ((i as f32 + 0.5) / wf, (j as f32 + 0.5) / hf);
                    let zc = (offset[k] - n.x * xc - n.y * yc) / n.z;
                    Some((zc, -n.x / n.z, -n.y / n.z))
                })
            }
        };
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

/// Default threshold of [`crack_flags`] (relative inverse-depth gap at a shared footprint
/// edge). Flat surfaces stay below it: the f16 slopes of the quad-tree's nodes move a
/// plane's `z` at a footprint corner by at most `2^-12` of its own `z` spread over the
/// footprint plus ~1e-7 ([`crate::quadtree::node`]), and smooth curvature of radius
/// `r` at depth `d` with pixel footprint `s` opens gaps of about `s^2 / (8 r d)`.
pub const CRACK_REL_GAP: f32 = 1e-3;

/// Gaps above this relative size are depth discontinuities, not cracks: not flagged.
pub const CRACK_MAX_GAP: f32 = f32::INFINITY;

/// The flag `O` of a layer's planes (module docs): `plane(k)` gives pixel `k`'s plane as
/// `(z_c, dz/dx, dz/dy)` — its cube `z` at the pixel centre and its cube-`z` gradient per
/// cube `x`, `y` unit — or `None` for an uncovered pixel. Returns one flag per pixel
/// (`k = j W + i`).
pub fn crack_flags(
    cube: &UnitCube,
    w: u32,
    h: u32,
    max_rel_gap: f32,
    max_crack_gap: f32,
    plane: impl Fn(usize) -> Option<(f32, f32, f32)> + Sync,
) -> Vec<bool> {
    use rayon::prelude::*;
    let n = (w as usize) * (h as usize);
    let (hx, hy) = (0.5 / w as f32, 0.5 / h as f32);
    // Plane z at the four footprint corners: (x0, y0), (x1, y0), (x0, y1), (x1, y1).
    let mut corners: Vec<Option<[f32; 4]>> = vec![None; n];
    corners
        .par_chunks_mut(w.max(1) as usize)
        .enumerate()
        .for_each(|(j, row)| {
            for (i, c) in row.iter_mut().enumerate() {
                if let Some((zc, gx, gy)) = plane(j * w as usize + i) {
                    *c = Some([
                        zc - gx * hx - gy * hy,
                        zc + gx * hx - gy * hy,
                        zc - gx * hx + gy * hy,
                        zc + gx * hx + gy * hy,
                    ]);
                }
            }
        });
    let inv_n = 1.0 / cube.near as f64;
    let kk = (inv_n - 1.0 / cube.far as f64) as f32;
    let inv_n = inv_n as f32;
    let mut flag = vec![false; n];
    flag.par_chunks_mut(w.max(1) as usize)
        .enumerate()
        .for_each(|(j, row)| {
            let j = j as u32;
            for (i, f) in row.iter_mut().enumerate() {
                let i = i as u32;
                let k = (j * w + i) as usize;
                let Some(me) = corners[k] else {
                    continue;
                };
                let zc = 0.25 * (me[0] + me[1] + me[2] + me[3]);
                let scale = (inv_n - zc * kk) / kk;
                let (lo, hi) = (max_rel_gap * scale, max_crack_gap * scale);
                // (neighbour offset, my two corners, its two corners)
                let edges: [(i64, i64, [usize; 2], [usize; 2]); 4] = [
                    (1, 0, [1, 3], [0, 2]),
                    (-1, 0, [0, 2], [1, 3]),
                    (0, 1, [2, 3], [0, 1]),
                    (0, -1, [0, 1], [2, 3]),
                ];
                *f = edges.iter().any(|&(dx, dy, mine, theirs)| {
                    let (x, y) = (i as i64 + dx, j as i64 + dy);
                    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                        return false;
                    }
                    let Some(o) = corners[(y as u32 * w + x as u32) as usize] else {
                        return max_crack_gap == f32::INFINITY;
                    };
                    let gap = (me[mine[0]] - o[theirs[0]])
                        .abs()
                        .max((me[mine[1]] - o[theirs[1]]).abs());
                    // NaN (a degenerate plane) counts as an infinite gap.
                    let gap = if gap.is_nan() { f32::INFINITY } else { gap };
                    gap > lo && (gap <= hi || max_crack_gap == f32::INFINITY)
                });
            }
        });
    flag
}
