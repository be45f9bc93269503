//! The traversal of one view (Vardis et al. 2017, §4.2.1 and Algorithm 1): Hi-Z over the
//! min-max mips of the depth bounds (lines 1-6), and at the finest level the bucket tracing of
//! the cell's id lists (lines 7-22) with analytic ray-triangle tests.
//!
//! **The walk in film space** (as screen-space ray marchers step in homogeneous space,
//! McGuire & Mara 2014): the ray's clipped segment `[t_a, t_b]` is projected once, at its two
//! ends, onto the view's cell grid (film position in cells) with reciprocal view depth
//! `w = 1 / depth`. Along the projected segment, film position and `w` are both affine in
//! one screen-space parameter `λ in [0, 1]`, so the crossing of cell boundary `k` is
//! `λ = k inv + c` and the ray's `w` there is `w_a + λ (w_b - w_a)`: a multiply-add each, no
//! division per texel. The mips are read as reciprocal bounds `[1 / zmax, 1 / zmin]`
//! (`DirtCapture::recip_mip`, widened outward), so a texel test needs no division either;
//! only a traced cell turns its two `w` into depths for eq. 1.
//!
//! **Hi-Z** (Uludag 2014 on a min-max pyramid, as the paper's GPU code): the walk keeps the
//! level-0 cell `(cx, cy)` that contains the ray at the current `λ` and a level `L`. The
//! texel `(cx >> L, cy >> L)` is left at `λ_exit` (the first of its column or row boundary
//! crossings in the ray's film direction, or the end of the segment); the ray's `w` over
//! `[λ, λ_exit]` is the interval between its values at the two ends. Disjoint from the
//! texel's reciprocal bounds, or (`slabs`) its slabs of `w` missing every occupied slab of the
//! texel: the texel is skipped, the walk moves to `λ_exit` and one level up (a skip by the
//! slabs drops only cells whose buckets at the ray's depths are all empty, `slabs` module
//! docs). Overlapping above level 0: one level down. At level 0: the cell's record (bounds, eq. 1
//! scale, non-empty bucket mask), the buckets of the ray's depth span there, and if any of
//! them holds a triangle, bucket tracing; then on to `λ_exit`.
//!
//! **Bucket tracing.** The ray's depth span in the cell gives the bucket range by eq. 1
//! ([`bucket_index`], the capture's own function); buckets are visited in ray order (towards
//! the far plane: ascending; towards the eye: descending), the empty ones skipped by the
//! record's mask, and every triangle listed in them is
//! tested with the watertight test, four at a time (`tri4`: the lanes of
//! [`parallax_core::math::watertight_lanes`], the scalar
//! [`parallax_core::math::WatertightRay::intersect_within`] where an edge function is exactly
//! zero). A hit is kept when it
//! is the closest so far (ties in `t`: the lower triangle id). It is *accepted* — the answer —
//! once the walk has reached it: its `λ` is at most the cell's exit (it projects into this
//! cell, or an earlier one: the paper's test "the hit point lies within the candidate pixel
//! tile", done in the walk's parameter instead of by projecting; the hit's `λ` is computed
//! once per best hit) and its depth's bucket is not after
//! the bucket just traced (the early exit of Alg. 1 line 19, which the paper takes as soon as
//! any hit is found in a bucket; a triangle listed in this bucket can be hit at a depth of a
//! later bucket, so we wait until the walk has reached that depth). The paper drops a hit
//! outside the current cell; we keep it as the best so far (it is a real hit, and it bounds
//! the `t` of every later test and of the walk), which returns the same answer.
//!
//! **Why the answer is exact.** The capture lists a triangle in every cell its clipped part
//! overlaps, in every bucket its depth range overlaps, with the cells widened by
//! `FILM_MARGIN_PX` and the depth ranges by a relative `2^-16` (more than the f32 error of a
//! hit's depth and film position). The walk's cells split `[0, 1]` into consecutive `λ`
//! intervals that share their computed end points, and consecutive cells share the computed
//! `w` at their common boundary, so every point of the segment is in some traced interval.
//! The rounding of the walk only moves where the film position and `w` are evaluated: the
//! projected ends are the ray's within a few f32 ulps, a computed crossing `λ` lies within
//! ulps (times the segment's film length) of the boundary, and `w_a + λ (w_b - w_a)` is the
//! segment's reciprocal depth at a `λ` within an ulp of the computed one, within ulps. So the
//! film positions the walk assigns to a cell are within a thousandth of the film margin of
//! it, and the depth spans it traces there are the ray's depths over them within a few ulps:
//! a hit at `t*` lies in a cell the walk traces (the cell of its `λ`, or a neighbour within
//! the margin, which lists the triangle too), at a depth inside that cell's traced span, so
//! its triangle is in a bucket the walk traces there. When a hit is accepted, every untested
//! triangle's hit lies in a later cell or a later bucket, so at a larger `t`. The tests are
//! the BVH's test on the same f32 corners, so `t` and barycentrics are bit-identical to the
//! BVH's.

use parallax_raster::dirt::{DirtCapture, bucket_index};

use super::cells::{CellLine, CellLines, Entries};
use super::slabs::Slabs;
use super::tri4::Query;
use super::view::{Isa, MAX_LEVELS, ViewConsts, ViewRay};

/// How a walk ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WalkEnd {
    /// The answer is known: the closest hit was accepted, or (occlusion) a hit was found.
    Done,
    /// The ray left the interval without an accepted hit.
    Continue,
}

/// One film axis of the projected segment: boundary `k` (in cells) is crossed at
/// `λ = k inv + c` (`inv = 1 / (x_b - x_a)`, `c = -x_a inv`); an axis the ray does not move
/// along has `inv = 0`, `c = +inf`, so every crossing is at `+inf` and the walk never steps
/// it (a step needs a crossing before the segment's end, `λ < 1`). The direction (`up`) is
/// not stored: the walk is specialised on it.
#[derive(Clone, Copy)]
struct Axis {
    inv: f32,
    c: f32,
}

impl Axis {
    /// An axis the ray does not move along.
    const STILL: Axis = Axis {
        inv: 0.0,
        c: f32::INFINITY,
    };

    /// The axis of a segment from `a` to `b` (cells), and whether the ray moves towards
    /// higher cell indices. Below `MIN_SPAN` cells the axis does not move (its film span is
    /// far inside the capture's film margin, and `1 / span` stays finite with room for
    /// `k inv`).
    #[inline(always)]
    fn new(a: f32, b: f32) -> (Axis, bool) {
        const MIN_SPAN: f32 = 1e-30;
        let span = b - a;
        if span.abs() <= MIN_SPAN || span.is_nan() {
            return (Axis::STILL, span > 0.0);
        }
        let inv = 1.0 / span;
        (Axis { inv, c: -a * inv }, span > 0.0)
    }

    /// `λ` of the crossing of boundary `k`.
    #[inline(always)]
    fn cross(&self, k: u32) -> f32 {
        k as f32 * self.inv + self.c
    }
}

/// The ray's clipped segment `[t_a, t_b]` projected onto the view's cell grid: film position
/// (in cells) and reciprocal view depth `w = 1 / depth` are affine in the screen-space
/// parameter `λ in [0, 1]` (module docs).
struct Segment {
    x: f32,
    y: f32,
    dx: f32,
    dy: f32,
    w: f32,
    dw: f32,
    /// The ends in `t`, `t_b - t_a` and the depth at `t_b`, to map a hit's `t` to `λ`.
    t_a: f32,
    t_b: f32,
    dt: f32,
    z_b: f32,
}

impl Segment {
    #[inline(always)]
    fn new(vc: &ViewConsts, r: &ViewRay, t_a: f32, t_b: f32) -> Segment {
        let (z_a, z_b) = (r.depth(t_a), r.depth(t_b));
        let (w_a, w_b) = (1.0 / z_a, 1.0 / z_b);
        let film = |t: f32, w: f32| {
            let (u, v) = ((r.o.x + t * r.d.x) * w, (r.o.y + t * r.d.y) * w);
            ((u - vc.a0) * vc.cells_per_u, (vc.b0 - v) * vc.cells_per_v)
        };
        let (x_a, y_a) = film(t_a, w_a);
        let (x_b, y_b) = film(t_b, w_b);
        Segment {
            x: x_a,
            y: y_a,
            dx: x_b - x_a,
            dy: y_b - y_a,
            w: w_a,
            dw: w_b - w_a,
            t_a,
            t_b,
            dt: t_b - t_a,
            z_b,
        }
    }

    /// Reciprocal depth at `λ` (monotone in `λ`).
    #[inline(always)]
    fn w_at(&self, l: f32) -> f32 {
        self.w + l * self.dw
    }

    /// `λ` of the ray point at `t`: `(t - t_a) z_b / ((t_b - t_a) z(t))` inside the segment
    /// (at most 1), 0 before it, `+inf` after it.
    #[inline]
    fn lambda_of(&self, r: &ViewRay, t: f32) -> f32 {
        if t <= self.t_a {
            0.0
        } else if t <= self.t_b {
            fmin((t - self.t_a) * self.z_b / (self.dt * r.depth(t)), 1.0)
        } else {
            f32::INFINITY
        }
    }
}

/// `min` and `max` of two finite-or-infinite, non-NaN floats (plain comparisons; `f32::min`
/// pays for NaN handling the walk never needs).
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Walks view `cap` (constants `vc`) along `r` over `[t_start, t_end]` (inside the view's
/// frustum), updating `q.best`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk(
    vc: &ViewConsts,
    cap: &DirtCapture,
    slabs: &Slabs,
    cells: &CellLines,
    r: &ViewRay,
    t_start: f32,
    t_end: f32,
    q: &mut Query,
) -> WalkEnd {
    let t_end = fmin(t_end, q.best.t);
    if t_start.partial_cmp(&t_end) != Some(std::cmp::Ordering::Less) {
        return WalkEnd::Continue;
    }
    q.counters.views += 1;
    let seg = Segment::new(vc, r, t_start, t_end);
    let (xs, x_up) = Axis::new(seg.x, seg.x + seg.dx);
    let (ys, y_up) = Axis::new(seg.y, seg.y + seg.dy);
    // The loop specialised on the ray's film direction and on the sign of `dw` (fewer live
    // values and no selects per texel).
    let dir = (x_up, y_up, seg.dw < 0.0);
    macro_rules! by_dir {
        ($f:ident) => {
            match dir {
                (false, false, false) => $f::<false, false, false>,
                (false, false, true) => $f::<false, false, true>,
                (false, true, false) => $f::<false, true, false>,
                (false, true, true) => $f::<false, true, true>,
                (true, false, false) => $f::<true, false, false>,
                (true, false, true) => $f::<true, false, true>,
                (true, true, false) => $f::<true, true, false>,
                (true, true, true) => $f::<true, true, true>,
            }
        };
    }
    #[cfg(target_arch = "x86_64")]
    match vc.isa {
        Isa::X86V4 => {
            let f = by_dir!(walk_dir_v4);
            // SAFETY: `Isa::X86V4` is only chosen when the CPU has the features (`Isa::detect`).
            return unsafe { f(vc, cap, slabs, cells, r, &seg, xs, ys, q) };
        }
        Isa::X86V3 => {
            let f = by_dir!(walk_dir_v3);
            // SAFETY: as above, for `Isa::X86V3`.
            return unsafe { f(vc, cap, slabs, cells, r, &seg, xs, ys, q) };
        }
        Isa::Baseline => {}
    }
    let f = by_dir!(walk_dir);
    f(vc, cap, slabs, cells, r, &seg, xs, ys, q)
}

/// Defines a copy of the walk for one film direction (`UX`, `UY`: the ray moves towards
/// higher cell indices) and sign of `dw` (`W_FALLS`: `w` decreases along the segment), for one
/// instruction set: the same source ([`walk_body`]), so the same operations and results (Rust
/// never contracts a multiply and an add into an FMA).
macro_rules! walk_copy {
    ($(#[$attr:meta])* $name:ident, $isa:expr, $($unsafe:ident)?) => {
        $(#[$attr])*
        #[inline(never)]
        #[allow(clippy::too_many_arguments)]
        $($unsafe)? fn $name<const UX: bool, const UY: bool, const W_FALLS: bool>(
            vc: &ViewConsts,
            cap: &DirtCapture,
            slabs: &Slabs,
            cells: &CellLines,
            r: &ViewRay,
            seg: &Segment,
            xs: Axis,
            ys: Axis,
            q: &mut Query,
        ) -> WalkEnd {
            walk_body::<UX, UY, W_FALLS, { $isa as u8 }>(vc, cap, slabs, cells, r, seg, xs, ys, q)
        }
    };
}

walk_copy!(
    /// The build's baseline instruction set (the portable twin).
    walk_dir,
    Isa::Baseline,
);
walk_copy!(
    /// x86-64-v3 (AVX2, BMI1/2, LZCNT): the variable shifts of the texel and slab arithmetic
    /// become `shlx`/`shrx`, the float ops three-operand VEX forms.
    ///
    /// # Safety
    /// The CPU must have the enabled features (`Isa::detect`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    walk_dir_v3,
    Isa::X86V3,
    unsafe
);
walk_copy!(
    /// x86-64-v3 and AVX-512 F/VL/BW/DQ (EVEX: 32 vector registers for the float state).
    ///
    /// # Safety
    /// The CPU must have the enabled features (`Isa::detect`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl,avx512bw,avx512dq")]
    walk_dir_v4,
    Isa::X86V4,
    unsafe
);

/// The loop of the walk (inlined into each instruction-set copy; `ISA`: the copy's `Isa`, whose
/// bucket tracing calls the triangle tests' copy of the same instruction set).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn walk_body<const UX: bool, const UY: bool, const W_FALLS: bool, const ISA: u8>(
    vc: &ViewConsts,
    cap: &DirtCapture,
    slabs: &Slabs,
    cells: &CellLines,
    r: &ViewRay,
    seg: &Segment,
    mut xs: Axis,
    mut ys: Axis,
    q: &mut Query,
) -> WalkEnd {
    let texels = slabs.texels.as_slice();
    let lines = cells.lines.as_slice();

    // The start cell (clamped onto the grid: the start may lie on the frustum's boundary).
    let mut cx = cell_index(seg.x, vc.cells_x);
    let mut cy = cell_index(seg.y, vc.cells_y);
    let mut level = 0usize;
    let mut l = 0.0f32;
    let mut w_l = seg.w;
    let mut hit_l = HitLambda::NONE;
    // Iterations left (the bound `max_steps`), counted down.
    let mut left = vc.max_steps;
    let mut end = None;

    while left > 0 {
        left -= 1;
        let (tx, ty) = (cx >> level, cy >> level);
        // Where the ray leaves the texel: its next column and row boundaries (in cells).
        let (kx, ky) = ((tx + UX as u32) << level, (ty + UY as u32) << level);
        let l_col = xs.cross(kx);
        let l_row = ys.cross(ky);
        let l_exit = fmax(fmin(fmin(l_col, l_row), 1.0), l);
        let w_exit = seg.w_at(l_exit);
        let (w_lo, w_hi) = if W_FALLS {
            (w_exit, w_l)
        } else {
            (w_l, w_exit)
        };
        let lv_i = level & (MAX_LEVELS - 1);
        let texel = vc.level_offset[lv_i] as usize
            + ty as usize * vc.level_width[lv_i] as usize
            + tx as usize;
        let t = &texels[texel];
        // The min-max bounds, then the depth slabs (`slabs`).
        let overlaps = w_hi >= t.lo && w_lo <= t.hi && t.meets(w_lo, w_hi);
        if overlaps {
            if level > 0 {
                level -= 1;
                continue;
            }
            q.counters.cells += 1;
            let index = cy as usize * vc.cells_x as usize + cx as usize;
            let rec = &lines[index];
            let nb = vc.buckets;
            let b_a = bucket_at(rec.zmin, rec.scale, nb, 1.0 / w_l);
            let b_b = bucket_at(rec.zmin, rec.scale, nb, 1.0 / w_exit);
            // Skip the cell when every bucket of the range is empty (null head pointers).
            if any_bucket(rec.mask, b_a.min(b_b), b_a.max(b_b), nb) {
                let cell = Cell {
                    index,
                    zmin: rec.zmin,
                    scale: rec.scale,
                    mask: rec.mask,
                    buckets: (b_a, b_b),
                    l_exit,
                };
                if trace_cell::<ISA>(vc, cap, cells, rec, r, seg, &cell, &mut hit_l, q) {
                    end = Some(WalkEnd::Done);
                    break;
                }
            }
        }
        // On to the next texel.
        if l_exit >= 1.0 {
            end = Some(WalkEnd::Continue);
            break;
        }
        let lv = level as u32;
        if l_col <= l_row {
            cx = next_cell::<UX>(cx, kx, &mut xs, vc.cells_x);
            if l_row == l_col {
                cy = next_cell::<UY>(cy, ky, &mut ys, vc.cells_y);
            } else if level > 0 {
                let y = seg.y + l_exit * seg.dy;
                cy = refine::<UY>(cy, ty, lv, y, vc.cells_y);
            }
        } else {
            cy = next_cell::<UY>(cy, ky, &mut ys, vc.cells_y);
            if level > 0 {
                let x = seg.x + l_exit * seg.dx;
                cx = refine::<UX>(cx, tx, lv, x, vc.cells_x);
            }
        }
        l = l_exit;
        w_l = w_exit;
        // Up a level after a skip (Hi-Z); after tracing a cell the ray is among surfaces,
        // where the next cell is likely to overlap too: stay at the finest level.
        if !overlaps && level < vc.top {
            level += 1;
        }
    }
    q.counters.texels += (vc.max_steps - left) as u64;
    end.unwrap_or_else(|| {
        q.counters.truncated += 1;
        WalkEnd::Continue
    })
}

/// `λ` of the best hit so far, computed once per best hit.
struct HitLambda {
    t: f32,
    l: f32,
}

impl HitLambda {
    const NONE: HitLambda = HitLambda {
        t: f32::NAN,
        l: 0.0,
    };

    #[inline]
    fn get(&mut self, seg: &Segment, r: &ViewRay, t: f32) -> f32 {
        if self.t != t {
            *self = HitLambda {
                t,
                l: seg.lambda_of(r, t),
            };
        }
        self.l
    }
}

/// A level-0 cell the walk traces.
struct Cell {
    index: usize,
    /// The cell's eq. 1 constants (its record).
    zmin: f32,
    scale: f32,
    /// Its non-empty buckets ([`parallax_raster::dirt::bucket_mask`]).
    mask: u32,
    /// The buckets of the ray's depth at entry and at exit.
    buckets: (u32, u32),
    /// `λ` where the ray leaves the cell.
    l_exit: f32,
}

/// Bucket tracing in one cell whose range of buckets holds a triangle (Alg. 1 lines 7-22);
/// true when the answer is known. Inlined into the walk's loop (a call would store and reload
/// the walk's state around it: every XMM register is caller-saved).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_cell<const ISA: u8>(
    vc: &ViewConsts,
    cap: &DirtCapture,
    cells: &CellLines,
    line: &CellLine,
    r: &ViewRay,
    seg: &Segment,
    c: &Cell,
    hit_l: &mut HitLambda,
    q: &mut Query,
) -> bool {
    let (lo, scale, nb) = (c.zmin, c.scale, vc.buckets);
    let (b_a, b_b) = c.buckets;
    let (offsets, ids, halves) = (cap.offsets(), cap.ids(), cells.halves());
    let ascending = b_a <= b_b;
    let mut b = b_a;
    loop {
        if any_bucket(c.mask, b, b, nb) {
            q.counters.buckets += 1;
            let found = match cells.bucket(line, c.index, b, nb, offsets) {
                // The bucket's entries in the cell's line, then after the lines (`cells`).
                Entries::Packed { base, ranges } => ranges
                    .iter()
                    .any(|&(s, e)| s < e && q.test16::<ISA>(base, &halves[s..e])),
                Entries::Capture(s, e) => q.test::<ISA>(&ids[s..e]),
            };
            if found {
                return true;
            }
        }
        if q.best.found() && hit_l.get(seg, r, q.best.t) <= c.l_exit {
            // Accept once the walk has reached the hit's bucket (module docs).
            let bb = bucket_index(lo, scale, nb, r.depth(q.best.t));
            if (ascending && bb <= b) || (!ascending && bb >= b) {
                return true;
            }
        }
        if b == b_b {
            return false;
        }
        if ascending {
            b += 1;
        } else {
            b -= 1;
        }
    }
}

/// [`bucket_index`] (eq. 1) with the conversion done by `cvttss2si` on 64 bits, which needs
/// no saturation fix-ups: for `v > 0` below `2^63` it is `floor(v)`, above (and `+inf`) it is
/// `i64::MIN`, `2^63` as `u64`; either way the `min` with `buckets - 1` gives what the
/// saturating `v as u32` gives. Tested equal to [`bucket_index`].
#[inline(always)]
fn bucket_at(zmin: f32, scale: f32, buckets: u32, z: f32) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvttss_si64, _mm_set_ss};
        let v = (z - zmin) * scale;
        if v > 0.0 {
            // SAFETY: SSE is part of the x86_64 baseline.
            let i = unsafe { _mm_cvttss_si64(_mm_set_ss(v)) } as u64;
            i.min(buckets as u64 - 1) as u32
        } else {
            0
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    bucket_index(zmin, scale, buckets, z)
}

/// Whether `mask` (a cell's non-empty buckets, [`parallax_raster::dirt::bucket_mask`]) has a bit of buckets
/// `b0..=b1` (`b0 <= b1 < buckets`): `mask & bucket_mask(b0, b1, buckets) != 0` in two
/// shifts (the bits at and above `b0`'s, then only the `b1 - b0 + 1` lowest kept).
#[inline(always)]
fn any_bucket(mask: u32, b0: u32, b1: u32, buckets: u32) -> bool {
    let (lo, hi) = if buckets <= 32 {
        (b0, b1)
    } else {
        let g = buckets.div_ceil(32);
        (b0 / g, b1 / g)
    };
    ((mask >> (lo & 31)) << ((31 - (hi - lo)) & 31)) != 0
}

/// `floor(f)` clamped to `[0, n)`.
#[inline(always)]
fn cell_index(f: f32, n: u32) -> u32 {
    if f > 0.0 { (f as u32).min(n - 1) } else { 0 }
}

/// The cell across boundary `k` (in cells) in the ray's direction along the axis (`UP`:
/// towards higher indices). Only called for an axis whose crossing comes before the
/// segment's end, so a moving one. Off the grid before the end of the walk's interval
/// (clipped to the frustum), the ray runs along the film's edge within rounding of it (its
/// film direction is numerically undecided): it stays in the edge cells and the axis stops
/// stepping.
#[inline(always)]
fn next_cell<const UP: bool>(c: u32, k: u32, axis: &mut Axis, n: u32) -> u32 {
    if UP {
        if k < n {
            return k;
        }
    } else if k > 0 {
        return k - 1;
    }
    *axis = Axis::STILL;
    c
}

/// The cell coordinate (along the axis the ray did not leave through) at the exit of texel `t`
/// at `level`: `floor(f)` kept inside the texel and never behind `c` in the ray's direction
/// (`UP`). The same on an axis that does not step (`Axis::STILL`): `f` is the ray's film
/// position there as on a moving axis (on an axis still from the start it floors to the start
/// cell; on one stopped at the grid's edge it is within rounding of that edge).
#[inline(always)]
fn refine<const UP: bool>(c: u32, t: u32, level: u32, f: f32, n: u32) -> u32 {
    let lo = t << level;
    let hi = (((t + 1) << level) - 1).min(n - 1);
    let f = if f > 0.0 { f as u32 } else { 0 };
    let f = f.clamp(lo, hi);
    if UP { f.max(c) } else { f.min(c) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_raster::dirt::bucket_mask;

    /// [`bucket_at`] is [`bucket_index`].
    #[test]
    fn bucket_at_is_bucket_index() {
        let zs = [
            0.0f32,
            -1.0,
            0.5,
            1.0,
            1.000_001,
            2.5,
            3.999_999,
            4.0,
            7.75,
            100.0,
            1e9,
            4.3e9,
            1e19,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NAN,
        ];
        for buckets in [1u32, 2, 16, 32, 255, 1 << 20] {
            for &(zmin, scale) in &[(0.0f32, 1.0f32), (1.0, 0.37), (0.25, 16.0), (2.0, 1e-3)] {
                for &z in &zs {
                    for z in [z, z + zmin, z * 0.5 + zmin] {
                        assert_eq!(
                            bucket_at(zmin, scale, buckets, z),
                            bucket_index(zmin, scale, buckets, z),
                            "z {z} zmin {zmin} scale {scale} buckets {buckets}"
                        );
                    }
                }
            }
        }
    }

    /// [`any_bucket`] is the mask test by [`bucket_mask`].
    #[test]
    fn any_bucket_is_the_mask_test() {
        let masks = [
            0u32,
            1,
            0x8000_0000,
            u32::MAX,
            0x0001_0000,
            0x5555_5555,
            0xa0a0_0001,
            0x0000_0ff0,
        ];
        for buckets in [1u32, 2, 7, 16, 31, 32, 33, 48, 64, 100, 255] {
            for b0 in 0..buckets {
                for b1 in b0..buckets {
                    for &m in &masks {
                        assert_eq!(
                            any_bucket(m, b0, b1, buckets),
                            m & bucket_mask(b0, b1, buckets) != 0,
                            "mask {m:#x} buckets {b0}..={b1} of {buckets}"
                        );
                    }
                }
            }
        }
    }
}
