//! The traversal of one view (Vardis et al. 2017, §4.2.1 and Algorithm 1): Hi-Z over the
//! min-max mips of the depth bounds (lines 1-6), and at the finest level the bucket tracing of
//! the cell's id lists (lines 7-22) with analytic ray-triangle tests.
//!
//! **Hi-Z** (Uludag 2014 on a min-max pyramid, as the paper's GPU code): the walk keeps the
//! level-0 cell `(cx, cy)` that contains the ray at the current parameter `t` and a level `L`.
//! The texel `(cx >> L, cy >> L)` is left by the ray at `t_exit` (the first of its column or
//! row boundary crossings in the ray's film direction, or the end of the interval); the ray's
//! view depth over `[t, t_exit]` is the interval between the depths at the two ends (depth is
//! affine in `t`). Disjoint from the texel's `[zmin, zmax]`: the texel is skipped, the walk
//! moves to `t_exit` and one level up. Overlapping above level 0: one level down. At level 0:
//! bucket tracing, then on to `t_exit` and one level up.
//!
//! **Bucket tracing.** The ray's depth span in the cell gives the bucket range by eq. 1
//! ([`bucket_index`], the capture's own function); buckets are visited in ray order (towards
//! the far plane: ascending; towards the eye: descending) and every triangle listed in them is
//! tested with the watertight test, four at a time (`tri4`: the lanes of
//! [`parallax_core::math::watertight_lanes`], the scalar
//! [`parallax_core::math::WatertightRay::intersect_within`] where an edge function is exactly
//! zero). A hit is kept when it
//! is the closest so far (ties in `t`: the lower triangle id). It is *accepted* — the answer —
//! once the walk has reached it: its `t` is at most the cell's exit (it projects into this
//! cell, or an earlier one: the paper's test "the hit point lies within the candidate pixel
//! tile", done in ray parameter instead of by projecting) and its depth's bucket is not after
//! the bucket just traced (the early exit of Alg. 1 line 19, which the paper takes as soon as
//! any hit is found in a bucket; a triangle listed in this bucket can be hit at a depth of a
//! later bucket, so we wait until the walk has reached that depth). The paper drops a hit
//! outside the current cell; we keep it as the best so far (it is a real hit, and it bounds
//! the `t` of every later test and of the walk), which returns the same answer.
//!
//! **Why the answer is exact.** The capture lists a triangle in every cell its clipped part
//! overlaps, in every bucket its depth range overlaps (widened by more than the f32 error of
//! the depth and the film position of a hit). A hit at `t*` lies in the cell whose interval
//! holds `t*`, at a depth inside that cell's ray depth span, so its triangle is in a bucket the
//! walk traces there. When a hit is accepted, every untested triangle's hit lies in a later
//! cell or a later bucket, so at a larger `t`. The tests are the BVH's test on the same f32
//! corners, so `t` and barycentrics are bit-identical to the BVH's.

use parallax_raster::dirt::{CellRecord, DirtCapture, bucket_index, bucket_mask};

use super::tri4::Query;
use super::view::{ViewConsts, ViewRay};

/// How a walk ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WalkEnd {
    /// The answer is known: the closest hit was accepted, or (occlusion) a hit was found.
    Done,
    /// The ray left the interval without an accepted hit.
    Continue,
}

/// Parameters where the ray crosses the cell boundaries of one film axis: boundary `k` (in
/// cells) has slope `c0 + k ck`, crossed at `t(k) = (n0 + k nk) / (d0 + k dk)` (`view`
/// module docs); an axis the ray does not move along has `t = 1 / 0 = +inf`.
struct Axis {
    n0: f32,
    nk: f32,
    d0: f32,
    dk: f32,
    /// 1 when the ray moves towards higher cell indices.
    up: u32,
    /// The ray moves along this axis.
    moving: bool,
}

impl Axis {
    /// An axis the ray does not move along.
    const STILL: Axis = Axis {
        n0: 1.0,
        nk: 0.0,
        d0: 0.0,
        dk: 0.0,
        up: 0,
        moving: false,
    };
}

impl Axis {
    #[inline(always)]
    fn new(step: i32, c0: f32, ck: f32, r: &ViewRay, o: f32, d: f32) -> Axis {
        if step == 0 {
            return Axis::STILL;
        }
        Axis {
            n0: c0 * r.z0 - o,
            nk: ck * r.z0,
            d0: d - c0 * r.dz,
            dk: -ck * r.dz,
            up: (step > 0) as u32,
            moving: true,
        }
    }

    /// The crossing of boundary `k` in front of the eye (`+inf` if the line meets the
    /// boundary's plane behind the eye: the projection's asymptote stops short of it).
    #[inline(always)]
    fn cross(&self, k: u32, r: &ViewRay) -> f32 {
        let k = k as f32;
        let t = (self.n0 + k * self.nk) / (self.d0 + k * self.dk);
        if r.depth(t) > 0.0 { t } else { f32::INFINITY }
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
pub(crate) fn walk(
    vc: &ViewConsts,
    cap: &DirtCapture,
    r: &ViewRay,
    t_start: f32,
    t_end: f32,
    q: &mut Query,
) -> WalkEnd {
    let t_end = fmin(t_end, q.best.t);
    if !(t_start < t_end) {
        return WalkEnd::Continue;
    }
    q.counters.views += 1;
    let (_, bounds) = cap.mip_arrays();
    let records = cap.cell_records();
    let offsets = cap.offsets();
    let s = vc.tile as f32;
    let mut xs = Axis::new(r.step_x, vc.a0, vc.ax * s, r, r.o.x, r.d.x);
    let mut ys = Axis::new(r.step_y, vc.b0, -vc.by * s, r, r.o.y, r.d.y);

    // The start cell (clamped onto the grid: the start may lie on the frustum's boundary).
    let (u, v) = r.slopes(t_start);
    let mut cx = cell_index((u - vc.a0) * vc.cells_per_u, vc.cells_x);
    let mut cy = cell_index((vc.b0 - v) * vc.cells_per_v, vc.cells_y);
    let mut level = 0usize;
    let mut t = t_start;
    let mut z_t = r.depth(t);
    let ascending = r.dz >= 0.0;
    let mut texels = 0u64;
    let mut end = None;

    while texels < vc.max_steps as u64 {
        texels += 1;
        let (tx, ty) = (cx >> level, cy >> level);
        // Where the ray leaves the texel: its next column and row boundaries (in cells).
        let (kx, ky) = ((tx + xs.up) << level, (ty + ys.up) << level);
        let mut t_col = xs.cross(kx, r);
        let mut t_row = ys.cross(ky, r);
        if t_col < t {
            t_col = behind(t, kx as f32 * s, || (r.slopes(t).0 - vc.a0) / vc.ax);
        }
        if t_row < t {
            t_row = behind(t, ky as f32 * s, || (vc.b0 - r.slopes(t).1) / vc.by);
        }
        let t_exit = fmax(fmin(fmin(t_col, t_row), t_end), t);
        let z_exit = r.depth(t_exit);
        let (z_lo, z_hi) = if ascending {
            (z_t, z_exit)
        } else {
            (z_exit, z_t)
        };
        let overlaps = if level == 0 {
            let index = cy as usize * vc.cells_x as usize + cx as usize;
            // The cell's bucket offsets do not depend on its record: start their load now so
            // that the two cache misses overlap.
            prefetch(offsets, index * vc.buckets as usize);
            let rec = &records[index];
            let overlaps = z_hi >= rec.zmin && z_lo <= rec.zmax;
            if overlaps {
                let cell = Cell {
                    index,
                    rec: *rec,
                    t_exit,
                    z: (z_t, z_exit),
                };
                if trace_cell(vc, cap, r, &cell, q) {
                    end = Some(WalkEnd::Done);
                    break;
                }
            }
            overlaps
        } else {
            let texel = vc.level_offset[level] + ty as usize * vc.level_width[level] + tx as usize;
            let [lo, hi] = bounds[texel];
            if z_hi >= lo && z_lo <= hi {
                level -= 1;
                continue;
            }
            false
        };
        // On to the next texel.
        if t_exit >= t_end {
            end = Some(WalkEnd::Continue);
            break;
        }
        let lv = level as u32;
        if t_col <= t_row {
            cx = next_cell(cx, kx, &mut xs, vc.cells_x);
            if t_row == t_col {
                cy = next_cell(cy, ky, &mut ys, vc.cells_y);
            } else if level > 0 {
                let (_, v) = r.slopes(t_exit);
                cy = refine(cy, ty, lv, &ys, (vc.b0 - v) * vc.cells_per_v, vc.cells_y);
            }
        } else {
            cy = next_cell(cy, ky, &mut ys, vc.cells_y);
            if level > 0 {
                let (u, _) = r.slopes(t_exit);
                cx = refine(cx, tx, lv, &xs, (u - vc.a0) * vc.cells_per_u, vc.cells_x);
            }
        }
        t = t_exit;
        z_t = z_exit;
        // Up a level after a skip (Hi-Z); after tracing a cell the ray is among surfaces,
        // where the next cell is likely to overlap too: stay at the finest level.
        if !overlaps && level < vc.top {
            level += 1;
        }
    }
    q.counters.texels += texels;
    end.unwrap_or_else(|| {
        q.counters.truncated += 1;
        WalkEnd::Continue
    })
}

/// A level-0 cell the walk traces.
struct Cell {
    index: usize,
    rec: CellRecord,
    t_exit: f32,
    /// The ray's depth at entry and at exit.
    z: (f32, f32),
}

/// Bucket tracing in one cell (Alg. 1 lines 7-22); true when the answer is known. Not
/// inlined: the walk's loop keeps its state in registers.
#[inline(never)]
fn trace_cell(vc: &ViewConsts, cap: &DirtCapture, r: &ViewRay, c: &Cell, q: &mut Query) -> bool {
    q.counters.cells += 1;
    let (lo, scale, nb) = (c.rec.zmin, c.rec.scale, vc.buckets);
    let b_a = bucket_index(lo, scale, nb, c.z.0);
    let b_b = bucket_index(lo, scale, nb, c.z.1);
    // Skip the cell when every bucket of the range is empty (null head pointers).
    if c.rec.mask & bucket_mask(b_a.min(b_b), b_a.max(b_b), nb) == 0 {
        return false;
    }
    let (offsets, ids) = (cap.offsets(), cap.ids());
    let base = c.index * nb as usize;
    let ascending = b_a <= b_b;
    let mut b = b_a;
    loop {
        q.counters.buckets += 1;
        let k = base + b as usize;
        if q.test(&ids[offsets[k] as usize..offsets[k + 1] as usize]) {
            return true;
        }
        if q.best.found() && q.best.t <= c.t_exit {
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

/// How close (pixels) the ray must be to a boundary whose crossing was computed behind the
/// current parameter for the crossing to count as "now" (rounding); farther away, the computed
/// crossing is the numerically undecided one of a ray whose projection runs parallel to the
/// boundary (`du/dt` or `dv/dt` within rounding of 0: the line meets the plane near the eye
/// plane, behind the walk), and the ray never crosses it.
const EDGE_PX: f32 = 1e-3;

/// A crossing computed behind the current parameter `t` (see [`EDGE_PX`]): `t` if the ray
/// is at the boundary (film coordinate `film_at_t()` within [`EDGE_PX`] of `boundary_px`),
/// else never.
#[cold]
fn behind(t: f32, boundary_px: f32, film_at_t: impl FnOnce() -> f32) -> f32 {
    if (film_at_t() - boundary_px).abs() <= EDGE_PX {
        t
    } else {
        f32::INFINITY
    }
}

/// Hints the CPU to bring `data[i]` into the cache (no effect off x86-64, or out of range).
#[inline(always)]
fn prefetch<T>(data: &[T], i: usize) {
    #[cfg(target_arch = "x86_64")]
    if let Some(x) = data.get(i) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch reads nothing (it is a hint, even for an invalid address), and
        // SSE is part of the x86-64 baseline.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (data, i);
}

/// `floor(f)` clamped to `[0, n)`.
#[inline(always)]
fn cell_index(f: f32, n: u32) -> u32 {
    if f > 0.0 { (f as u32).min(n - 1) } else { 0 }
}

/// The cell across boundary `k` (in cells) in the axis' direction. Off the grid before the
/// end of the walk's interval (clipped to the frustum), the ray runs along the film's edge
/// within rounding of it (its film direction is numerically undecided): it stays in the edge
/// cells and the axis stops stepping.
#[inline(always)]
fn next_cell(c: u32, k: u32, axis: &mut Axis, n: u32) -> u32 {
    if !axis.moving {
        return c;
    }
    if axis.up == 1 {
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
/// at `level`: `floor(f)` kept inside the texel and never behind `c` in the ray's direction.
#[inline(always)]
fn refine(c: u32, t: u32, level: u32, axis: &Axis, f: f32, n: u32) -> u32 {
    if !axis.moving {
        return c;
    }
    let lo = t << level;
    let hi = (((t + 1) << level) - 1).min(n - 1);
    let f = if f > 0.0 { f as u32 } else { 0 };
    let f = f.clamp(lo, hi);
    if axis.up == 1 { f.max(c) } else { f.min(c) }
}
