//! Shared pieces of the baseline tracers ([`crate::dda`], [`crate::minmax`], [`crate::hiz`]):
//! validation of the captured layers, the ray as a straight segment in **pixel space** of the
//! unit cube (`x * W`, `y * H`, cube `z`), view depth <-> cube `z`, a depth pyramid (min, or
//! min and max, per cell) and the hierarchical cell-crossing loop that Hi-Z (Uludag 2014) and
//! the maximum mipmaps (Tevs et al. 2008) share.
//!
//! **Thin-shell semantics (all baselines).** A layer's surface at pixel `p` is the sheet at its
//! captured depth, `z_thickness` thick (view-depth units, McGuire & Mara 2014, §2.3 "thickness"),
//! two-sided like the BVH. A ray hits it when it crosses the sheet inside `p`'s footprint, or
//! when it enters `p`'s footprint column from the side at most `z_thickness` behind the sheet
//! (the "staircase wall" of a per-pixel height field). A ray that is farther behind is inside
//! the layer's **occlusion volume** (Widmer et al. 2015, §4.1): no hit from this layer there.

use glam::{Mat4, UVec2, Vec3};
use parallax_core::{GBuffer, Ray};

use crate::{CubeSegment, ScreenError, TraceResult, TraceStats, UnitCube};

/// Checks that every layer matches the cube's camera and returns how many layers to use
/// (`min(wanted, layers.len())`, at least 1).
pub(crate) fn check_layers(
    cube: &UnitCube,
    layers: &[GBuffer],
    wanted: usize,
) -> Result<usize, ScreenError> {
    if layers.is_empty() || wanted == 0 {
        return Err(ScreenError::Mismatch("need at least one layer".into()));
    }
    let (w, h) = (cube.camera.width, cube.camera.height);
    for (i, g) in layers.iter().enumerate() {
        if (g.width(), g.height()) != (w, h) {
            return Err(ScreenError::Mismatch(format!(
                "layer {i} is {}x{} but the reference camera is {w}x{h}",
                g.width(),
                g.height()
            )));
        }
    }
    Ok(wanted.min(layers.len()))
}

/// True for a captured surface depth.
#[inline]
pub(crate) fn covered(d: f32) -> bool {
    d.is_finite() && d > 0.0
}

/// View depth <-> cube `z` (the affine-in-`1/d` map of [`UnitCube::z_of_depth`]), in f32 for
/// the hot loops.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthMap {
    inv_near: f32,
    /// `1/near - 1/far`.
    span: f32,
}

impl DepthMap {
    pub(crate) fn new(cube: &UnitCube) -> Self {
        let inv_near = 1.0 / cube.near;
        Self {
            inv_near,
            span: inv_near - 1.0 / cube.far,
        }
    }
    #[inline]
    pub(crate) fn z(&self, depth: f32) -> f32 {
        (self.inv_near - 1.0 / depth) / self.span
    }
    #[inline]
    pub(crate) fn depth(&self, z: f32) -> f32 {
        1.0 / (self.inv_near - z * self.span)
    }
    /// Cube `z` of the back of the shell whose front is at cube `z`.
    #[inline]
    pub(crate) fn z_behind(&self, z: f32, thickness: f32) -> f32 {
        self.z(self.depth(z) + thickness)
    }
}

/// The ray clipped to the cube, as a straight segment in pixel space: `o + s d`, `s` in
/// `[0, 1]`, with `x` in `[0, W]`, `y` in `[0, H]`, `z` the cube depth.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PixelRay {
    pub seg: CubeSegment,
    pub o: Vec3,
    pub d: Vec3,
}

/// [`UnitCube::clip_ray`] in f32 with the pixel scale folded in: the per-ray set-up of every
/// baseline (the f64 version costs as much as a short march).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Clip {
    /// World `(p, 1)` -> homogeneous `(x W, y H, Z, view depth)`.
    m: Mat4,
    near: f32,
    far: f32,
    /// Image width and height (the `x`, `y` extent of the scaled cube).
    sx: f32,
    sy: f32,
}

impl Clip {
    pub(crate) fn new(cube: &UnitCube) -> Self {
        let scale = Mat4::from_scale(Vec3::new(
            cube.camera.width as f32,
            cube.camera.height as f32,
            1.0,
        ));
        Self {
            m: scale * cube.world_to_cube.as_mat4(),
            near: cube.near,
            far: cube.far,
            sx: cube.camera.width as f32,
            sy: cube.camera.height as f32,
        }
    }
}

impl PixelRay {
    /// `None` when the ray misses the cube (also for invalid rays). `max_distance` limits the
    /// world distance travelled from the ray origin. Same faces as [`UnitCube::clip_ray`]:
    /// with `W > 0` each is a linear inequality in world `t`.
    #[inline]
    pub(crate) fn new(clip: &Clip, ray: &Ray, max_distance: f32) -> Option<Self> {
        if !ray.is_valid() || ray.t_min.is_nan() || ray.t_max.is_nan() {
            return None;
        }
        let mut t_max = ray.t_max;
        if max_distance.is_finite() {
            t_max = t_max.min(max_distance / ray.dir.length());
        }
        let a = clip.m * ray.origin.extend(1.0);
        let b = clip.m * ray.dir.extend(0.0);
        let (mut lo, mut hi) = (ray.t_min.max(0.0), t_max);
        let (sx, sy) = (clip.sx, clip.sy);
        let faces = [
            (a.w - clip.near, b.w),
            (clip.far - a.w, -b.w),
            (a.x, b.x),
            (a.w * sx - a.x, b.w * sx - b.x),
            (a.y, b.y),
            (a.w * sy - a.y, b.w * sy - b.y),
        ];
        for (alpha, beta) in faces {
            if beta == 0.0 {
                if alpha < 0.0 {
                    return None;
                }
            } else {
                let root = -alpha / beta;
                if beta > 0.0 {
                    lo = lo.max(root);
                } else {
                    hi = hi.min(root);
                }
            }
        }
        if !(lo < hi && hi.is_finite()) {
            return None;
        }
        let (h0, h1) = (a + b * lo, b * hi + a);
        if !(h0.w > 0.0 && h1.w > 0.0) {
            return None;
        }
        let hi_c = Vec3::new(sx, sy, 1.0);
        let p0 = (h0.truncate() / h0.w).clamp(Vec3::ZERO, hi_c);
        let p1 = (h1.truncate() / h1.w).clamp(Vec3::ZERO, hi_c);
        let d = p1 - p0;
        let seg = CubeSegment {
            p0: p0 / hi_c,
            p1: p1 / hi_c,
            t0: lo,
            t1: hi,
            w0: h0.w as f64,
            w1: h1.w as f64,
        };
        d.is_finite().then_some(Self { seg, o: p0, d })
    }

    #[inline]
    pub(crate) fn at(&self, s: f32) -> Vec3 {
        self.o + self.d * s
    }
}

/// Per-pixel outcome of a leaf test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Leaf {
    /// Hit at segment parameter `s`.
    Hit(f32),
    /// Inside the occlusion volume from `s` on.
    Occluded(f32),
    /// Nothing in this footprint.
    Nothing,
}

/// What one layer's traversal found: the first hit and the first occlusion-volume entry
/// (segment parameter and pixel).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LayerOutcome {
    pub hit: Option<(f32, UVec2)>,
    pub occlusion: Option<(f32, UVec2)>,
}

/// A depth pyramid over a `W x H` image: level 0 per pixel, level `l` cells of `2^l x 2^l`
/// pixels, up to a single cell. Per cell `N` values (1: min `z`; 2: min `z` and max back-of-shell
/// `z`), interleaved. Empty pixels hold `+inf` in every slot, so a cell with any empty pixel
/// has `max = +inf` (the ray is never "behind all of it").
#[derive(Clone, Debug)]
pub(crate) struct Pyramid<const N: usize> {
    pub dims: Vec<(u32, u32)>,
    pub offsets: Vec<usize>,
    pub data: Vec<[f32; N]>,
}

impl<const N: usize> Pyramid<N> {
    /// Builds the levels above `base` (`W x H` values of level 0) with `reduce` combining the
    /// up-to-4 children (missing children outside the image are skipped).
    pub(crate) fn build(
        w: u32,
        h: u32,
        base: Vec<[f32; N]>,
        reduce: fn(&mut [f32; N], &[f32; N]),
    ) -> Self {
        let mut dims = vec![(w, h)];
        let mut offsets = vec![0usize];
        let mut data = base;
        let (mut lw, mut lh) = (w, h);
        while lw > 1 || lh > 1 {
            let (nw, nh) = (lw.div_ceil(2), lh.div_ceil(2));
            let prev = *offsets.last().unwrap();
            let off = data.len();
            data.reserve((nw * nh) as usize);
            for y in 0..nh {
                for x in 0..nw {
                    let mut acc = data[prev + (2 * y * lw + 2 * x) as usize];
                    for (dx, dy) in [(1, 0), (0, 1), (1, 1)] {
                        let (cx, cy) = (2 * x + dx, 2 * y + dy);
                        if cx < lw && cy < lh {
                            let c = data[prev + (cy * lw + cx) as usize];
                            reduce(&mut acc, &c);
                        }
                    }
                    data.push(acc);
                }
            }
            dims.push((nw, nh));
            offsets.push(off);
            (lw, lh) = (nw, nh);
        }
        Self {
            dims,
            offsets,
            data,
        }
    }

    #[inline]
    pub(crate) fn top(&self) -> u32 {
        (self.dims.len() - 1) as u32
    }

    #[inline]
    pub(crate) fn cell(&self, level: u32, cx: u32, cy: u32) -> [f32; N] {
        let (lw, _) = self.dims[level as usize];
        self.data[self.offsets[level as usize] + (cy * lw + cx) as usize]
    }

    pub(crate) fn bytes(&self) -> usize {
        self.data.len() * size_of::<[f32; N]>()
    }
}

/// The hierarchical cell-crossing loop (Uludag 2014; Tevs et al. 2008, §4): at a cell of level
/// `l` the ray's `z` range over the cell is compared with the cell's bounds; a potential hit
/// moves the ray forward to the cell's min-`z` plane (when it is in front and moving away) and
/// goes one level down, a miss moves it to the cell exit and one level up. At level 0 `leaf`
/// decides. With `N == 2` a cell whose back-of-shell `max` lies entirely in front of the ray
/// is skipped and recorded as an occlusion-volume entry.
///
/// Starts at the level whose cell size first exceeds the ray's screen extent. Traverses `s`
/// in `[s_start, s_end]`; at most `max_steps` iterations (then gives up with what
/// it has). Integer cell stepping: every advance moves to a different cell, so the loop
/// always progresses.
#[inline]
pub(crate) fn traverse<const N: usize>(
    pyr: &Pyramid<N>,
    ray: &PixelRay,
    s_start: f32,
    s_end: f32,
    max_steps: u32,
    stats: &mut TraceStats,
    mut leaf: impl FnMut(u32, u32, f32, f32) -> Leaf,
) -> LayerOutcome {
    let mut out = LayerOutcome::default();
    let (w, h) = pyr.dims[0];
    let (o, d) = (ray.o, ray.d);
    let inv = Vec3::ONE / d;
    let p = ray.at(s_start);
    let mut ix = (p.x.max(0.0) as u32).min(w - 1);
    let mut iy = (p.y.max(0.0) as u32).min(h - 1);
    let top = pyr.top();
    // Start at the finest level whose cells are as large as the ray's screen extent: the
    // levels above only add descents (Tevs start at the root, Uludag at a fixed level).
    let extent = d.x.abs().max(d.y.abs()) * (s_end - s_start);
    let mut level = (32 - (extent.max(0.0) as u32).leading_zeros()).min(top);
    let mut s = s_start;
    // Every `break` below ends the segment; running out of iterations is a truncation.
    'walk: {
        for _ in 0..max_steps {
            stats.steps += 1;
            stats.nodes_visited += 1;
            let (cx, cy) = (ix >> level, iy >> level);
            let size = (1u32 << level) as f32;
            let sx = if d.x > 0.0 {
                ((cx + 1) as f32 * size - o.x) * inv.x
            } else if d.x < 0.0 {
                (cx as f32 * size - o.x) * inv.x
            } else {
                f32::INFINITY
            };
            let sy = if d.y > 0.0 {
                ((cy + 1) as f32 * size - o.y) * inv.y
            } else if d.y < 0.0 {
                (cy as f32 * size - o.y) * inv.y
            } else {
                f32::INFINITY
            };
            let se = sx.min(sy).min(s_end).max(s);
            let (za, zb) = (o.z + d.z * s, o.z + d.z * se);
            let (zlo, zhi) = if za <= zb { (za, zb) } else { (zb, za) };
            let b = pyr.cell(level, cx, cy);
            stats.box_tests += 1;
            let overlaps = zhi >= b[0] && (N == 1 || zlo <= b[N - 1]);
            if overlaps {
                if level == 0 {
                    stats.plane_tests += 1;
                    match leaf(ix, iy, s, se) {
                        Leaf::Hit(sh) => {
                            out.hit = Some((sh, UVec2::new(ix, iy)));
                            return out;
                        }
                        Leaf::Occluded(so) => {
                            if out.occlusion.is_none() {
                                out.occlusion = Some((so, UVec2::new(ix, iy)));
                            }
                        }
                        Leaf::Nothing => {}
                    }
                } else {
                    if d.z > 0.0 && za < b[0] {
                        // Nothing in this cell is nearer than its min plane: skip to it.
                        let sm = ((b[0] - o.z) * inv.z).clamp(s, se);
                        if sm > s {
                            s = sm;
                            let q = ray.at(s);
                            let (x0, y0) = (cx << level, cy << level);
                            let m = (1u32 << level) - 1;
                            ix = (q.x.max(0.0) as u32).clamp(x0, (x0 + m).min(w - 1));
                            iy = (q.y.max(0.0) as u32).clamp(y0, (y0 + m).min(h - 1));
                        }
                    }
                    level -= 1;
                    continue;
                }
            } else if N == 2 && zlo > b[N - 1] && out.occlusion.is_none() {
                out.occlusion = Some((s, UVec2::new(ix, iy)));
            }
            // Advance to the cell exit.
            if se >= s_end {
                break 'walk;
            }
            s = se;
            let q = ray.at(s);
            let (x0, y0) = (cx << level, cy << level);
            let m = (1u32 << level) - 1;
            let step_x = sx <= sy;
            let step_y = sy <= sx;
            if step_x {
                if d.x > 0.0 {
                    ix = (cx + 1) << level;
                    if ix >= w {
                        break 'walk;
                    }
                } else {
                    if x0 == 0 {
                        break 'walk;
                    }
                    ix = x0 - 1;
                }
            } else {
                ix = (q.x.max(0.0) as u32).clamp(x0, (x0 + m).min(w - 1));
            }
            if step_y {
                if d.y > 0.0 {
                    iy = (cy + 1) << level;
                    if iy >= h {
                        break 'walk;
                    }
                } else {
                    if y0 == 0 {
                        break 'walk;
                    }
                    iy = y0 - 1;
                }
            } else {
                iy = (q.y.max(0.0) as u32).clamp(y0, (y0 + m).min(h - 1));
            }
            level = (level + 1).min(top);
        }
        stats.truncated += 1;
    }
    out
}

/// A hit or occlusion entry of the cascade: segment parameter, layer, pixel.
pub(crate) type LayerHit = (f32, u32, UVec2);

/// Cascade over layers (Widmer et al. 2015, §4.1): layer 0 is traced first; a deeper layer is
/// traced only when the previous one reported an occlusion-volume entry before its hit (or
/// without a hit), and only from that entry on. Returns the nearest hit over the traced
/// layers `(s, layer, pixel)` and the deepest traced layer's occlusion entry (a layer without
/// one keeps the previous layer's).
pub(crate) fn cascade(
    layers: usize,
    mut trace_layer: impl FnMut(usize, f32, f32) -> LayerOutcome,
) -> (Option<LayerHit>, Option<LayerHit>) {
    let mut best: Option<LayerHit> = None;
    let mut occ: Option<LayerHit> = None;
    let mut start = 0.0f32;
    for li in 0..layers {
        let end = best.map_or(1.0, |b| b.0);
        let r = trace_layer(li, start, end);
        if let Some((s, px)) = r.hit
            && best.is_none_or(|b| s < b.0)
        {
            best = Some((s, li as u32, px));
        }
        // A deeper layer that reports no occlusion entry (e.g. empty where the ray passes)
        // keeps the shallower layer's: the ray is still behind that layer's surface with no
        // information (replacing it by `None` turned such rays into misses).
        if let Some((s, px)) = r.occlusion {
            occ = Some((s, li as u32, px));
        }
        match (r.occlusion, best) {
            (Some((so, _)), Some((sh, _, _))) if so < sh => start = so,
            (Some((so, _)), None) => start = so,
            _ => break,
        }
    }
    // An occlusion entry behind the final hit does not matter.
    if let (Some(b), Some(o)) = (best, occ)
        && o.0 >= b.0
    {
        occ = None;
    }
    (best, occ)
}

/// The [`TraceResult`] of a cascade's outcome, counting hits and occlusion volumes.
pub(crate) fn finish(
    ray: &Ray,
    pr: &PixelRay,
    best: Option<LayerHit>,
    occ: Option<LayerHit>,
    stats: &mut TraceStats,
) -> TraceResult {
    if let Some((s, layer, pixel)) = best {
        stats.hits += 1;
        let t = pr.seg.world_t(s);
        TraceResult::Hit {
            layer,
            pixel,
            position: ray.at(t),
            t,
        }
    } else if let Some((s, layer, pixel)) = occ {
        stats.occlusion_volumes += 1;
        TraceResult::OcclusionVolume {
            layer,
            pixel,
            t: pr.seg.world_t(s),
        }
    } else {
        TraceResult::Miss
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramid_levels_and_reduce() {
        let base: Vec<[f32; 1]> = (0..15).map(|i| [i as f32]).collect();
        let p = Pyramid::<1>::build(5, 3, base, |a, c| a[0] = a[0].min(c[0]));
        assert_eq!(p.dims, vec![(5, 3), (3, 2), (2, 1), (1, 1)]);
        assert_eq!(p.cell(1, 2, 0), [4.0]);
        assert_eq!(p.cell(1, 1, 1), [12.0]);
        assert_eq!(p.cell(3, 0, 0), [0.0]);
    }
}
