//! The per-ray set-up of the quad-tree traversal ([`super::traverse`]): a cube segment in grid
//! units with its slab constants, the `z`-slab constants and the per-axis data of an axis the
//! ray does not move along; pixel cells with the traversal's tie rule.
//!
//! Every value is computed once per ray and read by the traversal loop; the choices (no third
//! division, integer cells, the `dg == 0` axis constants) and their measurements are in
//! `docs/notes/quadtree.md`.

use glam::{Vec3, Vec4};

use super::tree::Z_SKIP_MARGIN;
use crate::CubeSegment;

#[inline(always)]
pub(super) fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[inline(always)]
pub(super) fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// A cube segment prepared for traversal (cube and grid units).
#[derive(Clone, Copy, Debug)]
pub struct RaySetup {
    pub p0: Vec3,
    pub d: Vec3,
    /// Grid-space origin and direction (`x W`, `y H`).
    pub o: [f32; 2],
    pub dg: [f32; 2],
    /// The slab of both axes as one 4-lane operation (`x` near, `y` near, `x` far, `y`
    /// far; [`Self::slabs`]): per-lane sides `[tie_x, tie_y, 1 - tie_x, 1 - tie_y]`, origins
    /// `[so_x, so_y, so_x, so_y]` and reciprocals likewise. The slab origin and reciprocal
    /// `so`, `sinv` of an axis are `o` and `1 / dg`, except on an axis with `dg == 0`,
    /// where they are the start pixel's centre and `+inf` ([`Self::new`]).
    pub(super) side4: Vec4,
    pub(super) so4: Vec4,
    pub(super) sinv4: Vec4,
    /// Parameter length of one pixel of screen travel (for dilations).
    pub s_per_px: f32,
    /// The `z` entry of a box (descent start, [`QuadTree::trace_layer`]): `(zmin - zoff) *
    /// inv_dz` with `zoff = p0.z + Z_SKIP_MARGIN`, `inv_dz = 1 / d.z` for `d.z > 0`, else 0.
    pub(super) zoff: f32,
    pub(super) inv_dz: f32,
    /// Per axis: the ray does not move along it (`dg == 0`), and then `floor(o)` (see the
    /// descent in [`QuadTree::trace_layer`]).
    pub(super) par: [bool; 2],
    pub(super) floor_o: [u32; 2],
    /// On a `par` axis: the pixel `cell(a, s, 0, W - 1)` (the same for every finite `s`).
    pub(super) pcell: [u32; 2],
}

impl RaySetup {
    #[inline(always)]
    pub fn new(seg: &CubeSegment, w: f32, h: f32) -> Self {
        let d = seg.p1 - seg.p0;
        let o = [seg.p0.x * w, seg.p0.y * h];
        let dg = [d.x * w, d.y * h];
        let inv = [1.0 / dg[0], 1.0 / dg[1]];
        let tie = [(dg[0] < 0.0) as u32 as f32, (dg[1] < 0.0) as u32 as f32];
        let mut r = Self {
            p0: seg.p0,
            d,
            o,
            dg,
            side4: Vec4::new(tie[0], tie[1], 1.0 - tie[0], 1.0 - tie[1]),
            so4: Vec4::ZERO,
            sinv4: Vec4::ZERO,
            // `1 / max(|dg|)` without a third division: division is correctly rounded and
            // monotone, so `1 / max(|a|, |b|) == min(1 / |a|, 1 / |b|)` exactly (`inf` when
            // both are 0).
            s_per_px: fmin(inv[0].abs(), inv[1].abs()),
            zoff: seg.p0.z + Z_SKIP_MARGIN,
            inv_dz: if d.z > 0.0 { 1.0 / d.z } else { 0.0 },
            par: [false; 2],
            floor_o: [0; 2],
            pcell: [0; 2],
        };
        // An axis the ray does not move along: the traversal never leaves the start pixel's
        // column (row) on it — its pixel is `cell(a, s, ..)` for every `s`, and a descent
        // picks the child holding it (same tie rule) — so every visited node's slab on it
        // holds the pixel centre strictly inside: with `so` = that centre and `sinv = +inf`
        // the slab is exactly `(-inf, +inf)` (a ray parallel to the slab inside it) without
        // a per-node test. (A node of the padding beyond the image
        // may miss the centre; it is empty, and the parameters the traversal takes from its
        // slab — `t_out` and the exit edge — are the same.)
        let (mut so, mut sinv) = (o, inv);
        if dg[0] == 0.0 || dg[1] == 0.0 {
            r.axis_parallel(w, h, &mut so, &mut sinv);
        }
        r.so4 = Vec4::new(so[0], so[1], so[0], so[1]);
        r.sinv4 = Vec4::new(sinv[0], sinv[1], sinv[0], sinv[1]);
        r
    }

    /// The `dg == 0` axes of [`Self::new`] (common: a horizontal stereo baseline makes
    /// every epipolar segment horizontal).
    #[inline(always)]
    fn axis_parallel(&mut self, w: f32, h: f32, so: &mut [f32; 2], sinv: &mut [f32; 2]) {
        for (a, hi) in [(0, w as u32 - 1), (1, h as u32 - 1)] {
            if self.dg[a] == 0.0 {
                self.pcell[a] = self.cell0(a, hi);
                so[a] = self.pcell[a] as f32 + 0.5;
                sinv[a] = f32::INFINITY;
                self.par[a] = true;
                // `floor(o)` for `o >= 0` (saturating: NaN and negatives to 0, which keeps
                // the descent test below: `o < 0` is below every mid line `m >= 1`).
                self.floor_o[a] = self.o[a] as u32;
            }
        }
    }

    /// Entry and exit parameters `(x in, y in, x out, y out)` of the node rectangle
    /// `[x0, x0 + size] x [y0, y0 + size]`: per axis the two products `(side - o) * inv`
    /// of the slab test (the near side is `x0 + size * tie`, exact), without branches, both
    /// axes in one 4-lane operation (each lane the same IEEE operations as the scalar form).
    #[inline(always)]
    pub(super) fn slabs(&self, x0: f32, y0: f32, size: f32) -> Vec4 {
        let side = Vec4::new(x0, y0, x0, y0) + self.side4 * size;
        (side - self.so4) * self.sinv4
    }

    /// Grid coordinate on axis `a` at `s`.
    #[inline(always)]
    pub fn at(&self, a: usize, s: f32) -> f32 {
        self.o[a] + self.dg[a] * s
    }

    /// First parameter in `[a, b]` where the ray's cube `z >= tz`.
    #[inline(always)]
    pub fn z_entry(&self, a: f32, b: f32, tz: f32) -> Option<f32> {
        let za = self.p0.z + self.d.z * a;
        if za >= tz {
            return Some(a);
        }
        let zb = self.p0.z + self.d.z * b;
        if zb >= tz && self.d.z > 0.0 {
            Some(clamp_in((tz - self.p0.z) / self.d.z, a, b))
        } else {
            None
        }
    }

    /// [`Self::cell`]`(a, s, 0, hi)`, from [`Self::pcell`] on an axis the ray does not move
    /// along (`o + 0 s = o`: the same value for every finite `s`).
    #[inline(always)]
    pub(super) fn start_cell(&self, a: usize, s: f32, hi: u32) -> u32 {
        if self.par[a] {
            debug_assert_eq!(self.pcell[a], self.cell(a, s, 0, hi));
            self.pcell[a]
        } else if s == 0.0 {
            // `o + dg * 0 = o` (`dg` finite; a signed zero floors the same).
            self.cell0(a, hi)
        } else {
            self.cell(a, s, 0, hi)
        }
    }

    /// [`Self::cell`]`(a, 0, 0, hi)` (the start pixel of a ray from the segment's start),
    /// with a short dependency chain: it feeds the start node's index. For `0 <= o < 1e7`
    /// (always, with the f64 clip: `p0` is in `[0, 1]`) the floor is the truncation, and
    /// the tie rule and the clamps are integer operations — ~15 cycles of latency instead
    /// of ~45 for the general form's float selects; otherwise the general form.
    #[inline(always)]
    #[allow(clippy::manual_range_contains)]
    fn cell0(&self, a: usize, hi: u32) -> u32 {
        let x = self.o[a];
        if x >= 0.0 && x < 1.0e7 {
            // SAFETY: `0 <= x < 1e7`, so it truncates to an in-range `i32`.
            let t = unsafe { x.to_int_unchecked::<i32>() };
            let t = t - ((t as f32 == x) & (self.dg[a] < 0.0)) as i32;
            let c = (t.max(0) as u32).min(hi);
            debug_assert_eq!(c, self.cell(a, 0.0, 0, hi));
            c
        } else {
            self.cell(a, 0.0, 0, hi)
        }
    }

    /// [`Self::cell`]`(a, s, lo, hi)` for `0 <= lo <= hi <= W - 1`: on a `par` axis the
    /// nested clamp `clamp(clamp(c, 0, W - 1), lo, hi) = clamp(c, lo, hi)` of `pcell`.
    #[inline(always)]
    pub(super) fn cell_in(&self, a: usize, s: f32, lo: u32, hi: u32) -> u32 {
        if self.par[a] {
            let c = self.pcell[a].max(lo).min(hi);
            debug_assert_eq!(c, self.cell(a, s, lo, hi));
            c
        } else {
            self.cell(a, s, lo, hi)
        }
    }

    /// Pixel cell on axis `a` at `s` (boundary ties go along the direction), clamped to
    /// `[lo, hi]` (`lo <= hi < 2^31`).
    ///
    /// Integer form with a short dependency chain (it feeds the hit pixel and, in a cascade,
    /// the start node): every `x <= 0` (and NaN) yields `lo` — its floor, minus the tie, is
    /// at most 0 — so `x` is clamped to `[0, 1e7]` first, where the floor is the truncation,
    /// and the tie rule and the clamps are integer operations. Same result as the float form
    /// (floor, tie, clamp) it replaced, for every `x`.
    #[inline(always)]
    pub(super) fn cell(&self, a: usize, s: f32, lo: u32, hi: u32) -> u32 {
        let x = self.at(a, s);
        let x = if x > 0.0 { x } else { 0.0 };
        let x = if x < 1.0e7 { x } else { 1.0e7 };
        // SAFETY: `x` is in `[0, 1e7]` (not NaN) after the selects above, so it truncates to
        // an in-range `i32` (no saturation code needed, unlike `as`).
        let t = unsafe { x.to_int_unchecked::<i32>() };
        // A boundary tie goes to the lower cell when moving down the axis.
        let t = t - ((t as f32 == x) & (self.dg[a] < 0.0)) as i32;
        (t.max(lo as i32) as u32).min(hi)
    }
}

/// `x` clamped to `[lo, hi]` (`lo <= hi`): `f32::clamp` without its `lo <= hi` assertion,
/// which kept it out of line (a call per hit). Same result (NaN stays NaN).
#[inline(always)]
pub(super) fn clamp_in(x: f32, lo: f32, hi: f32) -> f32 {
    let x = if x < lo { lo } else { x };
    if x > hi { hi } else { x }
}
