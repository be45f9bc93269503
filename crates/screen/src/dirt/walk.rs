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
//! docs). Overlapping above level 0: down by child scans (`scan`: the texel's children along
//! the ray tested in ray order, the walk going on at the first that overlaps, or leaving the
//! texel when none does). At level 0: the cell's record (bounds, eq. 1
//! scale, non-empty bucket mask), the buckets of the ray's depth span there, and if any of
//! them holds a triangle, bucket tracing; then on to `λ_exit`.
//!
//! **Bucket tracing.** The ray's depth span in the cell gives the bucket range by eq. 1
//! (`parallax_raster::dirt::bucket_index`, the capture's own function); buckets are visited in ray order (towards
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

use parallax_raster::dirt::DirtCapture;

use super::cell::{Cell, HitLambda, any_bucket, bucket_at, trace_cell};
use super::scan::{Parent, Scan, scan_children};
use super::segment::{Axis, Segment, cell_index, fmax, fmin, next_cell, refine};
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

/// Walks view `cap` (constants `vc`) along `r` over `[t_start, t_end]` (inside the view's
/// frustum), updating `q.best`. Inlined into the tracer's copies (`DirtTracer::trace`), so
/// the segment's set-up runs on the copy's instruction set too.
#[inline(always)]
pub(crate) fn walk(
    vc: &ViewConsts,
    cap: &DirtCapture,
    slabs: &Slabs,
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
            return unsafe { f(vc, cap, slabs, r, &seg, xs, ys, q) };
        }
        Isa::X86V3 => {
            let f = by_dir!(walk_dir_v3);
            // SAFETY: as above, for `Isa::X86V3`.
            return unsafe { f(vc, cap, slabs, r, &seg, xs, ys, q) };
        }
        Isa::Baseline => {}
    }
    let f = by_dir!(walk_dir);
    f(vc, cap, slabs, r, &seg, xs, ys, q)
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
            r: &ViewRay,
            seg: &Segment,
            xs: Axis,
            ys: Axis,
            q: &mut Query,
        ) -> WalkEnd {
            walk_body::<UX, UY, W_FALLS, { $isa as u8 }>(vc, cap, slabs, r, seg, xs, ys, q)
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
    r: &ViewRay,
    seg: &Segment,
    mut xs: Axis,
    mut ys: Axis,
    q: &mut Query,
) -> WalkEnd {
    let texels = slabs.texels.as_slice();
    let records = cap.cell_records();
    // The unchecked texel and record reads below rely on these (`ViewConsts::new` checks the
    // level table against the grid; the texels and records must be this view's).
    assert!(
        texels.len() == vc.texel_count
            && records.len() == vc.cells_x as usize * vc.cells_y as usize,
        "view constants, texels and records of different views"
    );

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

    // Texels tested by child scans (below), besides one per loop iteration.
    let mut scanned = 0u64;
    // Whether the texel at `(cx, cy, level)` over `[λ0, λ1]` (`w` from `w0` to `w1`) may hold a
    // cell to trace: its min-max bounds, then its depth slabs (`slabs`).
    let test = |cx: u32, cy: u32, level: usize, w0: f32, w1: f32| {
        let (w_lo, w_hi) = if W_FALLS { (w1, w0) } else { (w0, w1) };
        let (tx, ty) = (cx >> level, cy >> level);
        // Loop invariant: `cx < cells_x`, `cy < cells_y` (`cell_index`, `next_cell` and
        // `refine` keep the cell on the grid) and `level <= top`, so `(tx, ty)` is a texel of
        // level `level` and `texel < texels.len()` (`ViewConsts::new`'s checks).
        debug_assert!(cx < vc.cells_x && cy < vc.cells_y && level <= vc.top);
        let lv = vc.levels[level & (MAX_LEVELS - 1)];
        let texel = (lv as u32) as usize + ty as usize * (lv >> 32) as usize + tx as usize;
        debug_assert!(texel < texels.len());
        // SAFETY: `texel < texels.len()` by the loop invariant above.
        let t = unsafe { texels.get_unchecked(texel) };
        w_hi >= t.lo && w_lo <= t.hi && t.meets(w_lo, w_hi)
    };

    while left > 0 {
        left -= 1;
        let (mut tx, mut ty) = (cx >> level, cy >> level);
        // Where the ray leaves the texel: its next column and row boundaries (in cells).
        let (mut kx, mut ky) = ((tx + UX as u32) << level, (ty + UY as u32) << level);
        let mut l_col = xs.cross(kx);
        let mut l_row = ys.cross(ky);
        let mut l_exit = fmax(fmin(fmin(l_col, l_row), 1.0), l);
        let mut w_exit = seg.w_at(l_exit);
        let mut overlaps = test(cx, cy, level, w_l, w_exit);
        let mut stay = false;
        if overlaps {
            // Down to level 0 by child scans: the children of the overlapping texel along
            // the ray, in ray order, up to the first that overlaps (`scan_children`).
            let mut fallback = false;
            while level > 0 {
                let parent = Parent {
                    tx,
                    ty,
                    level,
                    kx,
                    ky,
                    l_col,
                    l_row,
                };
                let scan = scan_children::<UX, UY>(
                    (vc.cells_x, vc.cells_y),
                    seg,
                    &xs,
                    &ys,
                    &parent,
                    cx,
                    cy,
                    l,
                    w_l,
                    &test,
                );
                scanned += scan.1;
                match scan.0 {
                    Scan::Child(c) => {
                        level -= 1;
                        (cx, cy, l, w_l) = (c.cx, c.cy, c.l, c.w);
                        (l_col, l_row, l_exit, w_exit) = (c.l_col, c.l_row, c.l_exit, c.w_exit);
                        (tx, ty) = (cx >> level, cy >> level);
                        (kx, ky) = (c.kx, c.ky);
                    }
                    Scan::None => {
                        overlaps = false;
                        stay = true;
                        break;
                    }
                    Scan::Edge => {
                        fallback = true;
                        break;
                    }
                }
            }
            if fallback {
                // A far child off the grid: one level down, the plain Hi-Z step.
                level -= 1;
                continue;
            }
        }
        if overlaps {
            q.counters.cells += 1;
            let index = cy as usize * vc.cells_x as usize + cx as usize;
            // SAFETY: `index < cells_x * cells_y = records.len()` (the loop invariant, and
            // the assertion before the loop).
            let rec = unsafe { records.get_unchecked(index) };
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
                if trace_cell::<ISA>(vc, cap, r, seg, &cell, &mut hit_l, q) {
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
        if !overlaps && !stay && level < vc.top {
            level += 1;
        }
    }
    q.counters.texels += scanned;
    q.counters.texels += (vc.max_steps - left) as u64;
    end.unwrap_or_else(|| {
        q.counters.truncated += 1;
        WalkEnd::Continue
    })
}
