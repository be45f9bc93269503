//! The DIRT build's rasterization and band fill: conservative rasterization of a set-up
//! triangle into the view's cells with each cell-triangle pair's view-depth range (DIRT Fig.
//! 6a; [`raster`], called right after the triangle's setup, its fragments kept per screen
//! band), then per band "Fill Depth" (§4.1.1) and "Fill Primitives" (§4.1.2, eq. 1) as count /
//! prefix sum / fill ([`fill_band`]).
//!
//! **Coverage.** For each cell row the triangle's projection touches, the polygon is cut to the
//! row's slab (widened by [`FILM_MARGIN_PX`]); every cell column in the x range of that cut
//! (widened too) overlaps the triangle, because the cut is convex.
//!
//! **Depth range of a cell** (`w = 1 / depth`). The default, [`CellDepth::Corners`]: the range
//! of the triangle's `w` plane over the cell's (widened) rectangle — its corners — intersected
//! with the exact range over the row's cut; exact for cells inside the triangle, and a
//! superset of the exact range at its edges, in O(1) per cell. [`CellDepth::Exact`], the slow
//! twin: the exact range over the triangle cut to the cell (Sutherland-Hodgman's vertex set).
//! Both are widened by a relative `2^-16` and the triangle's absolute margin (module docs of
//! `dirt`).
//!
//! **Shortcuts that keep the capture bit for bit** (unit tests against the plain forms): a
//! polygon inside one row slab is its own cut (its set-up x and `w` ranges, no clipping); the
//! plane's y terms are taken once per row; cell spans are `trunc` of clamped quotients instead
//! of `floor` calls (`Grid::span`); bucket indices by the saturating conversion and an
//! integer clamp (`fast_bucket_index`); `widen`'s outward steps on the bits (`down_then_clamped`,
//! `up_of_below`); a cell's non-empty mask is the union of its fragments' bucket ranges,
//! gathered by the count pass.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::DVec3;

use super::capture::{
    CellDepth, CellRecord, DirtError, DirtOptions, FILM_MARGIN_PX, bucket_mask, bucket_scale,
};
use super::clip::Poly;
use super::setup::{SetupEntry, ViewXf, WPlane};

/// Relative margin on a clipped depth range.
const DEPTH_REL_MARGIN: f64 = 1.0 / 65536.0;

/// One cell-triangle pair with the (widened) view-depth range.
#[derive(Clone, Copy)]
pub(super) struct Fragment {
    cell: u32,
    tri: u32,
    zlo: f32,
    zhi: f32,
    /// Its first and last bucket (eq. 1a/1b), once the cell's bounds are known: computed by
    /// the count pass, read by the fill pass.
    b0: u16,
    b1: u16,
}

/// The cell grid and its split into bands of whole cell rows.
pub(super) struct Grid {
    pub s: u32,
    pub cells_x: u32,
    pub cells_y: u32,
    pub buckets: u32,
    pub band_rows: u32,
}

impl Grid {
    /// Cells a film interval `[v0, v1]` (widened by the margin) can touch, clamped to
    /// `[lo, hi)`: `max(floor((v0 - m) / s), lo) ..= min(floor((v1 + m) / s), hi - 1)`, computed
    /// as `trunc` of the clamped quotients (the same integers: `lo` and `hi - 1` are integers,
    /// and a clamped lower end is `>= lo >= 0`, where `floor` is `trunc`; an upper end below 0
    /// is empty either way). `s` is a power of two, so `* (1 / s)` is the exact `/ s`.
    #[inline(always)]
    pub fn span(v0: f64, v1: f64, s: u32, lo: u32, hi: u32) -> Option<(u32, u32)> {
        let m = FILM_MARGIN_PX;
        let inv = 1.0 / s as f64;
        let (lo, top) = (lo as f64, hi as f64 - 1.0);
        let a = (v0 - m) * inv;
        let b = (v1 + m) * inv;
        let a = if a > lo { a } else { lo };
        let b = if b < top { b } else { top };
        if !(b >= 0.0) {
            return None;
        }
        let (a, b) = (a as u32, b as u32);
        (a <= b).then_some((a, b))
    }

    /// Screen bands of the grid.
    pub fn bands(&self) -> u32 {
        self.cells_y.div_ceil(self.band_rows)
    }
}

/// `bucket_index` of `capture` (the same integer for every input) without branches: the
/// saturating conversion maps a negative value or a NaN to 0 and a huge one to `u32::MAX`,
/// then the integer clamp to `B - 1` (the same as clamping in f32 first: `B - 1` is an
/// integer and the conversion truncates).
#[inline(always)]
fn fast_bucket_index(zmin: f32, scale: f32, buckets: u32, z: f32) -> u32 {
    (((z - zmin) * scale) as u32).min(buckets - 1)
}

/// [`bucket_mask`] (the same bits), for `B <= 32` as one subtraction of 64-bit powers of two.
#[inline(always)]
fn fast_bucket_mask(b0: u32, b1: u32, buckets: u32) -> u32 {
    if buckets <= 32 {
        ((2u64 << b1) - (1u64 << b0)) as u32
    } else {
        bucket_mask(b0, b1, buckets)
    }
}

/// Fragments counted locally between two updates of the shared entry budget.
pub(super) const BILL_EVERY: u64 = 4096;

/// Adds `*unbilled` entries to the shared `budget` (and zeroes it); the build fails once the
/// total exceeds `max`.
#[inline]
pub(super) fn bill(budget: &AtomicU64, unbilled: &mut u64, max: u64) -> Result<(), DirtError> {
    let n = std::mem::take(unbilled);
    if budget.fetch_add(n, Ordering::Relaxed) + n > max {
        return Err(DirtError::TooLarge { max });
    }
    Ok(())
}

/// A band's share of the result.
pub(super) struct BandOut {
    /// Per cell: its bounds `[zmin, zmax]`, bucket scale and non-empty mask.
    pub cells: Vec<CellRecord>,
    /// Local exclusive prefix sums, `cells * B + 1`.
    pub offsets: Vec<u32>,
    pub ids: Vec<u32>,
    pub fragments: u64,
}

/// `if take { a } else { b }` on the bits, without a branch: `widen`'s rounding goes either
/// way about equally often, so a branch there is mispredicted about every other fragment.
#[inline(always)]
fn select_bits(take: bool, a: f32, b: f32) -> f32 {
    let m = (take as u32).wrapping_neg();
    f32::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// Widens `[zlo, zhi]` by the margins and rounds outward to f32 (each end stepped one f32
/// outward where the conversion rounded inward; branch-free, the same bits as the plain
/// form `widen_reference` of the tests).
#[inline]
fn widen(zlo: f64, zhi: f64, abs_margin: f64) -> (f32, f32) {
    let lo = zlo * (1.0 - DEPTH_REL_MARGIN) - abs_margin;
    let hi = zhi * (1.0 + DEPTH_REL_MARGIN) + abs_margin;
    let (l, h) = (lo as f32, hi as f32);
    let l = select_bits((l as f64) > lo, down_then_clamped(l), l);
    let h = select_bits((h as f64) < hi, up_of_below(h), h);
    (l.max(0.0), h)
}

/// A value whose `max(0.0)` equals `l.next_down().max(0.0)`, for an `l` that is not NaN or
/// `-inf`: for `l > 0` (`+inf` included) the next f32 below, one less in the bits; for
/// `l <= 0` the next value below is negative, so -1 does as well.
#[inline(always)]
fn down_then_clamped(l: f32) -> f32 {
    select_bits(l > 0.0, f32::from_bits(l.to_bits().wrapping_sub(1)), -1.0)
}

/// `h.next_up()` for an `h` that is not NaN or `+inf`: one more in the bits of a value
/// `>= +0`, one less in those of a value `< -0`, the smallest positive subnormal for `-0`.
#[inline(always)]
fn up_of_below(h: f32) -> f32 {
    let b = h.to_bits();
    let up = if b >> 31 == 0 {
        b + 1
    } else if b == 0x8000_0000 {
        1
    } else {
        b - 1
    };
    f32::from_bits(up)
}

/// The `w` range of a triangle's plane `p` over cell column `[left, right]` of a row whose
/// slab cuts the triangle to `row_w` (`(min, max)` of its vertices), with the plane's y terms
/// over the slab already sorted (`y_lo <= y_hi`): the range over the cell's corners, cut to
/// `row_w` (`row_w` itself if the two do not overlap after rounding).
#[inline(always)]
fn plane_w_range(
    p: &WPlane,
    row_w: (f64, f64),
    (left, right): (f64, f64),
    (y_lo, y_hi): (f64, f64),
) -> (f64, f64) {
    let (ax, bx) = (p.px * left, p.px * right);
    let (x_lo, x_hi) = if ax < bx { (ax, bx) } else { (bx, ax) };
    let lo = p.p0 + x_lo + y_lo;
    let hi = p.p0 + x_hi + y_hi;
    let lo = if lo > row_w.0 { lo } else { row_w.0 };
    let hi = if hi < row_w.1 { hi } else { row_w.1 };
    if lo <= hi { (lo, hi) } else { row_w }
}

/// The x and w ranges of a polygon cut to a row slab.
struct RowSpan {
    x: (f64, f64),
    w: (f64, f64),
}

/// [`span_in_slab`] along film y, for x and w only, with plain comparisons (the values are
/// finite): the exact ranges over the polygon cut to `top <= y <= bottom`.
#[inline(always)]
fn row_span(verts: &[DVec3], top: f64, bottom: f64) -> Option<RowSpan> {
    let mut x = (f64::INFINITY, f64::NEG_INFINITY);
    let mut w = x;
    let mut add = |px: f64, pw: f64| {
        x = (
            if px < x.0 { px } else { x.0 },
            if px > x.1 { px } else { x.1 },
        );
        w = (
            if pw < w.0 { pw } else { w.0 },
            if pw > w.1 { pw } else { w.1 },
        );
    };
    let mut a = *verts.last()?;
    for &b in verts {
        if b.y >= top && b.y <= bottom {
            add(b.x, b.z);
        }
        for line in [top, bottom] {
            if (a.y < line && b.y > line) || (a.y > line && b.y < line) {
                let t = (line - a.y) / (b.y - a.y);
                add(a.x + (b.x - a.x) * t, a.z + (b.z - a.z) * t);
            }
        }
        a = b;
    }
    (x.0 <= x.1).then_some(RowSpan { x, w })
}

/// A cell-triangle pair of the rasterization: the cell's index in the view (row-major), the
/// triangle and its widened view-depth range.
#[derive(Clone, Copy, Default)]
pub(super) struct RawFrag {
    cell: u32,
    tri: u32,
    zlo: f32,
    zhi: f32,
}

/// Conservative rasterization of one set-up triangle (`e`, its clipped projection `poly`)
/// into the cells of the whole view (module docs: row slabs, then columns, with each cell's
/// `w` range), appending its fragments of screen band `b` to `out[b]` in row-major order.
/// Returns the number of fragments, or `None` when its projection touches no cell row of the
/// view.
#[inline(always)]
pub(super) fn raster(
    e: &SetupEntry,
    poly: &[DVec3],
    g: &Grid,
    xf: &ViewXf,
    cell_depth: CellDepth,
    out: &mut [Vec<RawFrag>],
) -> Option<u32> {
    let m = FILM_MARGIN_PX;
    let s = g.s as f64;
    let t = e.tri;
    let (r0, r1) = Grid::span(e.y.0, e.y.1, g.s, 0, g.cells_y)?;
    let mut n = 0u32;
    for r in r0..r1 + 1 {
        let top = r as f64 * s - m;
        let bottom = ((r as f64 + 1.0) * s).min(xf.h) + m;
        // A polygon inside the slab is its own cut (the same points `row_span` would add).
        let row = if e.y.0 >= top && e.y.1 <= bottom {
            RowSpan { x: e.x, w: e.w }
        } else {
            match row_span(poly, top, bottom) {
                Some(row) => row,
                None => continue,
            }
        };
        let Some((c0, c1)) = Grid::span(row.x.0, row.x.1, g.s, 0, g.cells_x) else {
            continue;
        };
        // The fragment of cell column `c` with `w` range `[wlo, whi]` (w = 1 / depth > 0
        // after the near clip).
        let rbase = r * g.cells_x;
        let out = &mut out[(r / g.band_rows) as usize];
        let mut emit = |c: u32, wlo: f64, whi: f64| {
            let (zlo, zhi) = widen(1.0 / whi, 1.0 / wlo, e.abs_margin);
            n += 1;
            out.push(RawFrag {
                cell: rbase + c,
                tri: t,
                zlo,
                zhi,
            });
        };
        // Cell column `c`'s `[left, right]` (widened); the cut is convex, so the column
        // overlaps it iff it overlaps its x range.
        let column = |c: u32| {
            let left = c as f64 * s - m;
            let right = ((c as f64 + 1.0) * s).min(xf.w) + m;
            (left, right, !(right < row.x.0 || left > row.x.1))
        };
        match (cell_depth, e.plane) {
            (CellDepth::Exact, _) => {
                let mut p = Poly::EMPTY;
                p.v[..poly.len()].copy_from_slice(poly);
                p.n = poly.len();
                let rp = p.clip_axis(1, top, 1.0).clip_axis(1, bottom, -1.0);
                for c in c0..c1 + 1 {
                    let (left, right, overlaps) = column(c);
                    if let (true, Some((wlo, whi))) = (overlaps, rp.z_range_in_strip(left, right)) {
                        emit(c, wlo, whi);
                    }
                }
            }
            (CellDepth::Corners, Some(p)) => {
                // The plane's y terms are the row's (`cell_w_range` with them hoisted).
                let (ay, by) = (p.py * top, p.py * bottom);
                let (y_lo, y_hi) = if ay < by { (ay, by) } else { (by, ay) };
                for c in c0..c1 + 1 {
                    let (left, right, overlaps) = column(c);
                    if overlaps {
                        let (wlo, whi) = plane_w_range(&p, row.w, (left, right), (y_lo, y_hi));
                        emit(c, wlo, whi);
                    }
                }
            }
            (CellDepth::Corners, None) => {
                for c in c0..c1 + 1 {
                    if column(c).2 {
                        emit(c, row.w.0, row.w.1);
                    }
                }
            }
        }
    }
    Some(n)
}

/// One view's fragments of one chunk of triangles, grouped by screen band (band `b`'s are
/// `frags[band_start[b]..band_start[b + 1]]`, in triangle order within the band).
#[derive(Default)]
pub(super) struct ViewFrags {
    pub frags: Vec<RawFrag>,
    pub band_start: Vec<u32>,
    /// Triangles whose clipped projection touches a cell row of the view.
    pub in_view: u64,
}

impl ViewFrags {
    /// The bands' fragments (`bands[b]`, in triangle order) concatenated.
    pub fn concat(bands: &[Vec<RawFrag>], in_view: u64) -> ViewFrags {
        let mut band_start = Vec::with_capacity(bands.len() + 1);
        band_start.push(0u32);
        let mut frags = Vec::with_capacity(bands.iter().map(Vec::len).sum());
        for b in bands {
            frags.extend_from_slice(b);
            band_start.push(frags.len() as u32);
        }
        ViewFrags {
            frags,
            band_start,
            in_view,
        }
    }

    fn band(&self, b: u32) -> &[RawFrag] {
        &self.frags[self.band_start[b as usize] as usize..self.band_start[b as usize + 1] as usize]
    }
}

/// What every band of one view's fill reads.
pub(super) struct FillJob<'a> {
    /// The view's fragments, chunk by chunk in triangle order.
    pub chunks: &'a [ViewFrags],
    pub grid: &'a Grid,
    pub opts: &'a DirtOptions,
    /// Entries of all views so far, against `opts.max_entries`.
    pub budget: &'a AtomicU64,
}

thread_local! {
    /// Each worker's fragment buffer, kept across bands and builds (no allocation once warm).
    static FRAGMENTS: std::cell::RefCell<Vec<Fragment>> =
        const { std::cell::RefCell::new(Vec::new()) };
}

/// Fill Depth and Fill Primitives of band `band` from its fragments.
pub(super) fn fill_band(job: &FillJob, band: u32) -> Result<BandOut, DirtError> {
    FRAGMENTS.with_borrow_mut(|frags| {
        frags.clear();
        fill_band_with(job, band, frags)
    })
}

/// [`fill_band`] compiled with the build's x86-64-v4 features (`build::wide_available`).
///
/// # Safety
/// The CPU must have them (`build::wide_available`).
#[cfg(target_arch = "x86_64")]
#[target_feature(
    enable = "avx512f,avx512vl,avx512bw,avx512dq,avx2,fma,bmi1,bmi2,lzcnt,popcnt,f16c"
)]
pub(super) unsafe fn fill_band_v4(job: &FillJob, band: u32) -> Result<BandOut, DirtError> {
    // The closure written here, not [`fill_band`]'s: it holds the inlined fill and takes this
    // function's target features.
    FRAGMENTS.with_borrow_mut(|frags| {
        frags.clear();
        fill_band_with(job, band, frags)
    })
}

/// [`fill_band`] with an empty fragment buffer.
#[inline(always)]
fn fill_band_with(
    job: &FillJob,
    band: u32,
    frags: &mut Vec<Fragment>,
) -> Result<BandOut, DirtError> {
    let FillJob {
        chunks,
        grid: g,
        opts,
        budget,
    } = *job;
    let row0 = band * g.band_rows;
    let row1 = (row0 + g.band_rows).min(g.cells_y);
    let ncells = ((row1 - row0) * g.cells_x) as usize;
    let cell0 = row0 * g.cells_x;
    // Fill Depth (§4.1.1) writes each cell's bounds into its record; the count pass adds the
    // scale and the mask.
    let mut cells = vec![
        CellRecord {
            zmin: f32::INFINITY,
            zmax: f32::NEG_INFINITY,
            scale: 0.0,
            mask: 0,
        };
        ncells
    ];
    for ch in chunks {
        for f in ch.band(band) {
            let k = f.cell - cell0;
            let cell = &mut cells[k as usize];
            // Branch-free (a new triangle in a cell is nearer or farther unpredictably).
            cell.zmin = select_bits(f.zlo < cell.zmin, f.zlo, cell.zmin);
            cell.zmax = select_bits(f.zhi > cell.zmax, f.zhi, cell.zmax);
            frags.push(Fragment {
                cell: k,
                tri: f.tri,
                zlo: f.zlo,
                zhi: f.zhi,
                b0: 0,
                b1: 0,
            });
        }
    }

    // Fill Primitives (§4.1.2): count per bucket (eq. 1a/1b), prefix sum, fill.
    let nb = g.buckets as usize;
    for c in &mut cells {
        c.scale = bucket_scale(c.zmin, c.zmax, g.buckets);
    }
    // Counts per cell-bucket in `offsets[k]`; after the inclusive prefix sum `offsets[k]` is
    // bucket `k`'s end, and the fill (fragments in reverse, each entry decrementing its
    // bucket's end) leaves it at the bucket's start with the ids ascending in every bucket.
    // The non-empty mask of a cell is the union of its fragments' bucket ranges.
    let mut offsets = vec![0u32; ncells * nb + 1];
    let mut total = 0u64;
    for f in frags.iter_mut() {
        let cell = &mut cells[f.cell as usize];
        let b0 = fast_bucket_index(cell.zmin, cell.scale, g.buckets, f.zlo) as usize;
        let b1 = fast_bucket_index(cell.zmin, cell.scale, g.buckets, f.zhi) as usize;
        cell.mask |= fast_bucket_mask(b0 as u32, b1 as u32, g.buckets);
        (f.b0, f.b1) = (b0 as u16, b1 as u16);
        let base = f.cell as usize * nb;
        if b0 == b1 {
            offsets[base + b0] += 1;
        } else {
            for o in &mut offsets[base + b0..base + b1 + 1] {
                *o += 1;
            }
        }
        total += (b1 - b0 + 1) as u64;
    }
    // Entries beyond fragments (triangles in several buckets) count against the budget too
    // (the fragments were billed by the rasterization).
    let mut extra = total - frags.len() as u64;
    bill(budget, &mut extra, opts.max_entries)?;
    // The running sum kept in a register (not reloaded from the previous slot).
    let mut sum = 0u32;
    for o in &mut offsets[..ncells * nb] {
        sum += *o;
        *o = sum;
    }
    offsets[ncells * nb] = total as u32;
    let mut ids = vec![0u32; total as usize];
    for f in frags.iter().rev() {
        let (b0, b1) = (f.b0 as usize, f.b1 as usize);
        let base = f.cell as usize * nb;
        if b0 == b1 {
            let end = &mut offsets[base + b0];
            *end -= 1;
            ids[*end as usize] = f.tri;
        } else {
            for end in &mut offsets[base + b0..base + b1 + 1] {
                *end -= 1;
                ids[*end as usize] = f.tri;
            }
        }
    }
    Ok(BandOut {
        cells,
        offsets,
        ids,
        fragments: frags.len() as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::super::capture::bucket_index;
    use super::*;

    /// `Grid::span` as it was written first: `floor` of the widened ends, then clamped.
    fn span_reference(v0: f64, v1: f64, s: u32, lo: u32, hi: u32) -> Option<(u32, u32)> {
        let m = FILM_MARGIN_PX;
        let a = ((v0 - m) / s as f64).floor().max(lo as f64);
        let b = ((v1 + m) / s as f64).floor().min(hi as f64 - 1.0);
        (a <= b).then_some((a as u32, b as u32))
    }

    /// Film values around the cell boundaries `k s` (exactly on them, one margin and one ulp
    /// either side) and random ones, from left of the guard band to past the film.
    fn film_values(s: u32, rng: &mut parallax_core::Rng) -> Vec<f64> {
        let m = FILM_MARGIN_PX;
        let mut v = vec![-3.0, -1.0, -m, 0.0, 1e300, -1e300];
        for k in -1..=9 {
            let b = (k * s as i32) as f64;
            for x in [b, b - m, b + m, b - 2.0 * m, b + 2.0 * m] {
                v.extend([x, x.next_up(), x.next_down()]);
            }
        }
        v.extend((0..200).map(|_| rng.next_f32() as f64 * 10.0 * s as f64 - 3.0));
        v
    }

    #[test]
    fn span_equals_the_floor_reference() {
        let mut rng = parallax_core::Rng::new(3, 1);
        let mut cases = 0u64;
        for s in [1, 2, 4, 8] {
            let v = film_values(s, &mut rng);
            for &v0 in &v {
                for &v1 in &v {
                    for (lo, hi) in [(0, 8), (2, 5), (0, 1), (3, 4), (7, 8)] {
                        assert_eq!(
                            Grid::span(v0, v1, s, lo, hi),
                            span_reference(v0, v1, s, lo, hi),
                            "v0 {v0} v1 {v1} s {s} lo {lo} hi {hi}"
                        );
                        cases += 1;
                    }
                }
            }
        }
        assert!(cases > 500_000, "{cases}");
    }

    /// `widen` as it was written first, with branches.
    fn widen_reference(zlo: f64, zhi: f64, abs_margin: f64) -> (f32, f32) {
        let lo = zlo * (1.0 - DEPTH_REL_MARGIN) - abs_margin;
        let hi = zhi * (1.0 + DEPTH_REL_MARGIN) + abs_margin;
        let (mut l, mut h) = (lo as f32, hi as f32);
        if (l as f64) > lo {
            l = l.next_down();
        }
        if (h as f64) < hi {
            h = h.next_up();
        }
        (l.max(0.0), h)
    }

    /// The branch-free `widen` gives the same bits as the plain form on random depths, on
    /// f32 values and their neighbours in f64 (conversions exact or rounding either way), and
    /// on zeros, negatives, huge values, infinities and NaN.
    #[test]
    fn widen_equals_the_plain_form() {
        let mut rng = parallax_core::Rng::new(7, 3);
        let mut z: Vec<f64> = vec![
            0.0,
            -0.0,
            -1.0,
            1e-300,
            f32::MAX as f64,
            f32::MAX as f64 * 1.5,
            1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        for _ in 0..20_000 {
            let f = rng.next_f32() * [1e-3, 1.0, 100.0, 1e6][rng.next_u32() as usize % 4];
            let v = f as f64;
            z.extend([
                v,
                v * (1.0 + 1e-12),
                v * (1.0 - 1e-12),
                v.next_up(),
                v.next_down(),
            ]);
            z.push(rng.next_f32() as f64 * 50.0 + rng.next_f32() as f64 * 1e-9);
        }
        let margins = [0.0, 1e-7, 3.8e-6, 1.0];
        let mut stepped = [0u64; 2];
        for (i, &a) in z.iter().enumerate() {
            let b = z[(i * 7919 + 13) % z.len()];
            for &m in &margins {
                let (l, h) = widen(a, b, m);
                let (rl, rh) = widen_reference(a, b, m);
                assert_eq!(
                    (l.to_bits(), h.to_bits()),
                    (rl.to_bits(), rh.to_bits()),
                    "{a} {b} {m}"
                );
                let lo = a * (1.0 - DEPTH_REL_MARGIN) - m;
                stepped[((lo as f32) as f64 > lo) as usize] += 1;
            }
        }
        // Both roundings occur often (the case the branch-free form is for).
        assert!(stepped[0] > 50_000 && stepped[1] > 50_000, "{stepped:?}");
    }

    #[test]
    fn fast_bucket_index_and_mask_equal_the_shared_ones() {
        let mut rng = parallax_core::Rng::new(5, 2);
        for buckets in [1, 2, 7, 16, 31, 32, 33, 64, 1000, 1024] {
            for _ in 0..2000 {
                let zmin = rng.next_f32() * 10.0;
                let zmax = zmin + rng.next_f32() * [1e-6, 1.0, 100.0][rng.next_u32() as usize % 3];
                let scale = bucket_scale(zmin, zmax, buckets);
                let z = zmin - 1.0 + rng.next_f32() * (zmax - zmin + 2.0);
                for z in [
                    z,
                    zmin,
                    zmax,
                    zmax.next_up(),
                    zmin.next_down(),
                    f32::INFINITY,
                ] {
                    assert_eq!(
                        fast_bucket_index(zmin, scale, buckets, z),
                        bucket_index(zmin, scale, buckets, z),
                        "z {z} in [{zmin}, {zmax}], B {buckets}"
                    );
                }
            }
            for b0 in 0..buckets.min(40) {
                for b1 in b0..buckets.min(40) {
                    assert_eq!(
                        fast_bucket_mask(b0, b1, buckets),
                        bucket_mask(b0, b1, buckets)
                    );
                }
            }
        }
    }
}
