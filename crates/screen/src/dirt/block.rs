//! The Hi-Z walk's descent from level 2 done as one step: the 4x4 level-0 cells under an
//! overlapping level-2 texel tested together, without branches, in the lanes of fixed-size
//! arrays (Vardis et al. 2017, §4.2.1 and Algorithm 1 lines 1-6: the min-max traversal;
//! here its last two levels are replaced by a test of the cells the ray crosses).
//!
//! The plain walk (`walk`) descends into an overlapping texel one level at a time and climbs
//! after every skip, so a level-2 texel costs a chain of dependent steps (level, texel index,
//! texel load, compare, branch) and data-dependent branches. This step instead computes, for
//! the block's 16 cells at once, the `λ` interval the ray spends in each — from the crossings
//! of the block's five column and five row boundaries, the very values `k inv + c` the walk
//! computes — and the ray's `w` at its ends, tests each interval against the cell's texel
//! (reciprocal bounds, then slabs, as the walk does) and returns the cells that overlap as
//! a mask in ray order. The walk traces them in that order and goes on from the level-2
//! texel's exit.
//!
//! **Same cells as the level-0 walk.** Column crossings are monotone in the boundary, so the
//! walk, which leaves a cell by the smaller of its two exit crossings (both on a tie), is in
//! cell `(i, j)` exactly over `[max(in_i, in_j), min(out_i, out_j)]` when that interval is
//! non-empty: its entry is the crossing it came through, which is the larger in-crossing,
//! and the cells beside a tie get an empty interval. The cell the walk is in (`i0`, `j0`) is
//! entered at the walk's `λ`, whatever the crossings say (a cell found by `refine` may lie a
//! rounding past its boundary's crossing), and is tested even over an empty interval, as the
//! walk tests it; cells behind it are not on the path. The ends are clamped to `1`, and the
//! `w` at an end is `w_a + λ dw`, the walk's formula on the same `λ`, so the interval tested
//! and the buckets traced are the walk's. On the path the order of the cells is the order of
//! `i' + j'` (`i'`, `j'`: the column and row counted in the ray's direction), which a step of
//! the walk increases by one or two: bit `4 (i' + j') + i'` of the mask holds cell `(i, j)`.
//!
//! The block must lie inside the grid (the caller falls back to the plain descent at the
//! grid's edge, where the walk may stop an axis).

#[cfg(test)]
use super::slabs::slab;
use super::slabs::{SLABS, Texel};

/// Cells a block side (the level whose texels are blocks: 2).
pub(crate) const SIDE: u32 = 4;
/// The mip level of a block's texel.
pub(crate) const LEVEL: usize = 2;

/// The outcome of a block: per cell (lane `4 j + i`, column `i` and row `j` in the block)
/// the `λ` where the ray leaves it and its `w` at entry and exit.
pub(crate) struct Block {
    pub exit: [f32; 16],
    pub w_in: [f32; 16],
    pub w_out: [f32; 16],
}

impl Block {
    pub const EMPTY: Block = Block {
        exit: [0.0; 16],
        w_in: [0.0; 16],
        w_out: [0.0; 16],
    };
}

/// The block's column (or row) and lane of mask bit `p` ([`test`]), for the ray's direction
/// on the two axes.
#[inline(always)]
pub(crate) fn cell_of<const UX: bool, const UY: bool>(p: u32) -> (u32, u32) {
    let ip = p & 3;
    let jp = (p >> 2) - ip;
    let i = if UX { ip } else { 3 - ip };
    let j = if UY { jp } else { 3 - jp };
    (i, j)
}

/// What [`test`] needs about the ray in the block.
pub(crate) struct Ray {
    /// The block's first column and row (cells), and the walk's axes: boundary `k` is crossed
    /// at `λ = k inv + c` (`walk`'s `Axis::cross`).
    pub bx: u32,
    pub by: u32,
    pub x_inv: f32,
    pub x_c: f32,
    pub y_inv: f32,
    pub y_c: f32,
    /// The cell the walk is in (column and row in the block) at `λ = l`, where its `w` is
    /// `w_l`.
    pub i0: u32,
    pub j0: u32,
    pub l: f32,
    pub w_l: f32,
    /// The segment's `w` at `λ = 0` and its slope in `λ`.
    pub w: f32,
    pub dw: f32,
    /// The ray's film direction (towards higher columns, rows) and whether `w` falls.
    pub ux: bool,
    pub uy: bool,
    pub w_falls: bool,
}

/// `min` / `max` as the walk computes them (plain comparisons).
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Lane of cell `(i, j)` (column and row in the block) in [`Block`]'s arrays: the order
/// in which [`test_avx2`] holds the cells after unpacking four rows of texels (two rows a
/// vector; in each, columns 0 and 2 of both rows, then columns 1 and 3).
#[inline(always)]
pub(crate) fn lane(i: u32, j: u32) -> usize {
    ((j >> 1) * 8 + (i & 1) * 4 + (j & 1) * 2 + (i >> 1)) as usize
}

/// Column and row of lane `k` (the inverse of [`lane`]).
#[inline(always)]
fn lane_cell(k: u32) -> (u32, u32) {
    (((k >> 2) & 1) + (k & 1) * 2, (k >> 3) * 2 + ((k >> 1) & 1))
}

/// Tests the 16 cells of the block whose rows of four texels start at `texels[row0 + j *
/// width]` (`j = 0..4`) against the ray `r`, for the ray's film direction (`UX`, `UY`) and
/// sign of `dw` (`W_FALLS`): fills `out` and returns the mask of the cells on the ray's path
/// that overlap (bit `4 (i' + j') + i'`, module docs). `AVX2`: run [`test_avx2`] (the CPU
/// must have AVX2); otherwise the portable twin [`test_lanes`], tested equal.
#[inline(always)]
pub(crate) fn test<const AVX2: bool>(
    texels: &[Texel],
    row0: usize,
    width: usize,
    r: &Ray,
    out: &mut Block,
) -> u32 {
    assert!(
        width >= 4 && row0 + 3 * width + 4 <= texels.len(),
        "a block inside the texels"
    );
    #[cfg(target_arch = "x86_64")]
    if AVX2 {
        // SAFETY: `AVX2` is set only by the walk's copies compiled for AVX2 (chosen by
        // `Isa::detect`); the rows are inside `texels` (asserted above).
        return unsafe { test_avx2(texels, row0, width, r, out) };
    }
    test_lanes(texels, row0, width, r, out)
}

/// The portable twin of [`test_avx2`]: one lane at a time, without branches. One copy for
/// every direction (the walk's copies call it; inlined into each, the code outgrows the
/// instruction cache).
#[inline(never)]
pub(crate) fn test_lanes(
    texels: &[Texel],
    row0: usize,
    width: usize,
    r: &Ray,
    out: &mut Block,
) -> u32 {
    let (ux, uy, w_falls) = (r.ux, r.uy, r.w_falls);
    let cols: [f32; 5] = std::array::from_fn(|k| (r.bx + k as u32) as f32 * r.x_inv + r.x_c);
    let rows: [f32; 5] = std::array::from_fn(|k| (r.by + k as u32) as f32 * r.y_inv + r.y_c);
    let mut m = 0u32;
    for k in 0..16u32 {
        let (i, j) = lane_cell(k);
        let t = &texels[row0 + j as usize * width + i as usize];
        let (ci, co) = if ux {
            (cols[i as usize], cols[i as usize + 1])
        } else {
            (cols[i as usize + 1], cols[i as usize])
        };
        let (ri, ro) = if uy {
            (rows[j as usize], rows[j as usize + 1])
        } else {
            (rows[j as usize + 1], rows[j as usize])
        };
        let (col_now, row_now) = (i == r.i0, j == r.j0);
        let ci = if col_now { f32::NEG_INFINITY } else { ci };
        let ri = if row_now { f32::NEG_INFINITY } else { ri };
        let ahead_i = if ux { i >= r.i0 } else { i <= r.i0 };
        let ahead_j = if uy { j >= r.j0 } else { j <= r.j0 };
        let first = col_now & row_now;
        let entry = fmax(fmax(r.l, ci), ri);
        let exit = fmin(fmin(co, ro), 1.0);
        let on_path = ahead_i & ahead_j & (first | (entry < exit));
        let exit = fmax(exit, entry);
        let w_in = if first { r.w_l } else { r.w + entry * r.dw };
        let w_out = r.w + exit * r.dw;
        let (w_lo, w_hi) = if w_falls {
            (w_out, w_in)
        } else {
            (w_in, w_out)
        };
        let bounds = (w_hi >= t.lo) & (w_lo <= t.hi);
        // The slab test of `Texel::meets`, with wrapping shifts (lanes off the path may
        // have `w_lo > w_hi`; their result is masked off).
        let s = (t.slabs >> 56) as u32;
        let base = t.lo.to_bits().wrapping_shr(s);
        let (a, b) = (slab_w(w_lo, s, base), slab_w(w_hi, s, base));
        let meets = t
            .slabs
            .wrapping_shr(a)
            .wrapping_shl(63u32.wrapping_sub(b.wrapping_sub(a)))
            != 0;
        let ip = if ux { i } else { 3 - i };
        let jp = if uy { j } else { 3 - j };
        m |= ((on_path & bounds & meets) as u32) << (4 * (ip + jp) + ip);
        out.exit[k as usize] = exit;
        out.w_in[k as usize] = w_in;
        out.w_out[k as usize] = w_out;
    }
    m
}

/// [`test_lanes`] on AVX2: the 16 cells in two vectors of eight lanes ([`lane`]); the slab
/// masks' two 32-bit halves tested separately (`vpsrlvd` / `vpsllvd` give 0 for shifts past
/// 31, which drops the bits outside a half's part of the slab range).
///
/// One copy for every direction, as [`test_lanes`].
///
/// # Safety
/// The CPU must have AVX2; rows `row0 + j width .. + 4` (`j < 4`) inside `texels`.
#[cfg(target_arch = "x86_64")]
#[inline(never)]
#[target_feature(enable = "avx2")]
unsafe fn test_avx2(texels: &[Texel], row0: usize, width: usize, r: &Ray, out: &mut Block) -> u32 {
    // SAFETY: the caller's (AVX2, the rows inside `texels`).
    unsafe {
        use std::arch::x86_64::*;
        let base = texels.as_ptr().add(row0) as *const f32;
        // Per lane of either vector: the column (`I`) and, in the first vector, the row (`J`).
        let i_of = _mm256_setr_epi32(0, 2, 0, 2, 1, 3, 1, 3);
        let j_of = _mm256_setr_epi32(0, 0, 1, 1, 0, 0, 1, 1);
        // The crossings of boundaries `0..=4` of each axis, as the walk computes them.
        // The crossings of boundaries `0..=4` of each axis (lanes 5-7 repeat 4), as the walk
        // computes them: `k as f32 * inv + c` (no FMA; `k < 2^31`, so the signed conversion).
        let ks = _mm256_setr_epi32(0, 1, 2, 3, 4, 4, 4, 4);
        let cross = |b: u32, inv: f32, c: f32| {
            let k = _mm256_cvtepi32_ps(_mm256_add_epi32(ks, _mm256_set1_epi32(b as i32)));
            _mm256_add_ps(_mm256_mul_ps(k, _mm256_set1_ps(inv)), _mm256_set1_ps(c))
        };
        let cols = cross(r.bx, r.x_inv, r.x_c);
        let rows = cross(r.by, r.y_inv, r.y_c);
        // The direction without branches (it changes from ray to ray): `3 - v = v ^ 3` on
        // 0-3 counts columns and rows in the ray's direction (`i'`, `j'`).
        let (nx, ny) = (!r.ux as i32, !r.uy as i32);
        let (d_in, d_out, e_in, e_out) = (nx, 1 - nx, ny, 1 - ny);
        let (fx, fy) = (_mm256_set1_epi32(3 * nx), _mm256_set1_epi32(3 * ny));
        let ip = _mm256_xor_si256(i_of, fx);
        let i0p = (r.i0 as i32) ^ (3 * nx);
        let j0p = (r.j0 as i32) ^ (3 * ny);
        let falls = _mm256_castsi256_ps(_mm256_set1_epi32(-(r.w_falls as i32)));
        let ci_v = _mm256_permutevar8x32_ps(cols, _mm256_add_epi32(i_of, _mm256_set1_epi32(d_in)));
        let co_v = _mm256_permutevar8x32_ps(cols, _mm256_add_epi32(i_of, _mm256_set1_epi32(d_out)));
        let i0 = _mm256_set1_epi32(i0p);
        let j0 = _mm256_set1_epi32(j0p);
        let col_now = _mm256_castsi256_ps(_mm256_cmpeq_epi32(ip, i0));
        let behind_i = _mm256_castsi256_ps(_mm256_cmpgt_epi32(i0, ip));
        let ninf = _mm256_set1_ps(f32::NEG_INFINITY);
        let ci_v = _mm256_blendv_ps(ci_v, ninf, col_now);
        let l = _mm256_set1_ps(r.l);
        let one = _mm256_set1_ps(1.0);
        let (w, dw, w_l) = (
            _mm256_set1_ps(r.w),
            _mm256_set1_ps(r.dw),
            _mm256_set1_ps(r.w_l),
        );
        let one_i = _mm256_set1_epi32(1);
        let mut acc = _mm256_setzero_si256();
        for h in 0..2usize {
            // Rows `2h` and `2h + 1`: [lo0 hi0 s0 | lo1 hi1 s1], [lo2 hi2 s2 | lo3 hi3 s3].
            let row = |j: usize, half: usize| _mm256_loadu_ps(base.add((j * width) * 4 + half * 8));
            let (a0, b0) = (row(2 * h, 0), row(2 * h, 1));
            let (a1, b1) = (row(2 * h + 1, 0), row(2 * h + 1, 1));
            // [lo0 lo2 hi0 hi2 | lo1 lo3 hi1 hi3], and the slab halves likewise.
            let (u0, v0) = (_mm256_unpacklo_ps(a0, b0), _mm256_unpackhi_ps(a0, b0));
            let (u1, v1) = (_mm256_unpacklo_ps(a1, b1), _mm256_unpackhi_ps(a1, b1));
            let lo = _mm256_shuffle_ps::<0b01_00_01_00>(u0, u1);
            let hi = _mm256_shuffle_ps::<0b11_10_11_10>(u0, u1);
            let s_lo = _mm256_castps_si256(_mm256_shuffle_ps::<0b01_00_01_00>(v0, v1));
            let s_hi = _mm256_castps_si256(_mm256_shuffle_ps::<0b11_10_11_10>(v0, v1));
            let j_v = _mm256_add_epi32(j_of, _mm256_set1_epi32(2 * h as i32));
            let ri_v =
                _mm256_permutevar8x32_ps(rows, _mm256_add_epi32(j_v, _mm256_set1_epi32(e_in)));
            let ro_v =
                _mm256_permutevar8x32_ps(rows, _mm256_add_epi32(j_v, _mm256_set1_epi32(e_out)));
            let jp = _mm256_xor_si256(j_v, fy);
            let row_now = _mm256_castsi256_ps(_mm256_cmpeq_epi32(jp, j0));
            let behind_j = _mm256_castsi256_ps(_mm256_cmpgt_epi32(j0, jp));
            let ri_v = _mm256_blendv_ps(ri_v, ninf, row_now);
            let first = _mm256_and_ps(col_now, row_now);
            let entry = _mm256_max_ps(_mm256_max_ps(l, ci_v), ri_v);
            let exit = _mm256_min_ps(_mm256_min_ps(co_v, ro_v), one);
            let inside = _mm256_or_ps(first, _mm256_cmp_ps::<_CMP_LT_OQ>(entry, exit));
            let on_path = _mm256_andnot_ps(_mm256_or_ps(behind_i, behind_j), inside);
            let exit = _mm256_max_ps(exit, entry);
            let w_in = _mm256_blendv_ps(_mm256_add_ps(w, _mm256_mul_ps(entry, dw)), w_l, first);
            let w_out = _mm256_add_ps(w, _mm256_mul_ps(exit, dw));
            let w_lo = _mm256_blendv_ps(w_in, w_out, falls);
            let w_hi = _mm256_blendv_ps(w_out, w_in, falls);
            let bounds = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GE_OQ>(w_hi, lo),
                _mm256_cmp_ps::<_CMP_LE_OQ>(w_lo, hi),
            );
            // Slabs: shift `s` in the top byte, `base = bits(lo) >> s`,
            // `slab(w) = min(max(max(bits(w), 0) >> s, base) - base, 55)`.
            let s = _mm256_srli_epi32::<24>(s_hi);
            let sbase = _mm256_srlv_epi32(_mm256_castps_si256(lo), s);
            let slab = |v: __m256| {
                let b = _mm256_max_epi32(_mm256_castps_si256(v), _mm256_setzero_si256());
                let q = _mm256_max_epu32(_mm256_srlv_epi32(b, s), sbase);
                _mm256_min_epu32(
                    _mm256_sub_epi32(q, sbase),
                    _mm256_set1_epi32(SLABS as i32 - 1),
                )
            };
            let (sa, sb) = (slab(w_lo), slab(w_hi));
            // Bits `sa..=sb` of the low half (`sb` cut to 31) and of the high half (its bits
            // 0-23: slabs 32-55).
            let c31 = _mm256_set1_epi32(31);
            let sb_lo = _mm256_min_epu32(sb, c31);
            let in_lo = _mm256_sllv_epi32(
                _mm256_srlv_epi32(s_lo, sa),
                _mm256_sub_epi32(c31, _mm256_sub_epi32(sb_lo, sa)),
            );
            let c32 = _mm256_set1_epi32(32);
            let ah = _mm256_sub_epi32(_mm256_max_epu32(sa, c32), c32);
            let h24 = _mm256_and_si256(s_hi, _mm256_set1_epi32(0x00ff_ffff));
            // `63 - sb + ah - ...`: `31 - ((sb - 32) - ah)`, past 31 (no bit) when `sb < 32`.
            let in_hi = _mm256_sllv_epi32(
                _mm256_srlv_epi32(h24, ah),
                _mm256_sub_epi32(_mm256_set1_epi32(63), _mm256_sub_epi32(sb, ah)),
            );
            let none = _mm256_cmpeq_epi32(_mm256_or_si256(in_lo, in_hi), _mm256_setzero_si256());
            let keep =
                _mm256_andnot_si256(none, _mm256_castps_si256(_mm256_and_ps(on_path, bounds)));
            // Each lane's bit in ray order: `4 (i' + j') + i'` (the lanes' bits are disjoint).
            let pos = _mm256_add_epi32(_mm256_slli_epi32::<2>(_mm256_add_epi32(ip, jp)), ip);
            acc = _mm256_or_si256(acc, _mm256_and_si256(_mm256_sllv_epi32(one_i, pos), keep));
            _mm256_storeu_ps(out.exit.as_mut_ptr().add(8 * h), exit);
            _mm256_storeu_ps(out.w_in.as_mut_ptr().add(8 * h), w_in);
            _mm256_storeu_ps(out.w_out.as_mut_ptr().add(8 * h), w_out);
        }
        let b4 = _mm_or_si128(
            _mm256_castsi256_si128(acc),
            _mm256_extracti128_si256::<1>(acc),
        );
        let b2 = _mm_or_si128(b4, _mm_unpackhi_epi64(b4, b4));
        let b1 = _mm_or_si128(b2, _mm_srli_epi64::<32>(b2));
        _mm_cvtsi128_si32(b1) as u32
    }
}

/// [`slab`] with its shift wrapped (a texel's shift is at most 31; the wrap only keeps the
/// arithmetic total).
#[inline(always)]
fn slab_w(w: f32, s: u32, base: u32) -> u32 {
    let b = (w.to_bits() as i32).max(0) as u32;
    (b.wrapping_shr(s).max(base) - base).min(SLABS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::sampling::Rng;

    /// The walk's own step at level 0 from cell `(i0, j0)` at `λ = l` until it leaves the
    /// block or the segment (as `walk_body` steps inside a level-2 texel): the overlapping
    /// cells in order, with the bits of their entry and exit `w` and exit `λ`.
    fn plain_walk(texels: &[Texel], row0: usize, width: usize, r: &Ray) -> Vec<[u32; 5]> {
        let (mut i, mut j, mut l, mut w_l) = (r.i0 as i64, r.j0 as i64, r.l, r.w_l);
        let mut out = Vec::new();
        loop {
            let kx = r.bx as i64 + i + r.ux as i64;
            let ky = r.by as i64 + j + r.uy as i64;
            let l_col = kx as u32 as f32 * r.x_inv + r.x_c;
            let l_row = ky as u32 as f32 * r.y_inv + r.y_c;
            let l_exit = fmax(fmin(fmin(l_col, l_row), 1.0), l);
            let w_exit = r.w + l_exit * r.dw;
            let (w_lo, w_hi) = if r.w_falls {
                (w_exit, w_l)
            } else {
                (w_l, w_exit)
            };
            let t = &texels[row0 + j as usize * width + i as usize];
            if w_hi >= t.lo && w_lo <= t.hi && t.meets(w_lo, w_hi) {
                let b = |x: f32| x.to_bits();
                out.push([i as u32, j as u32, b(w_l), b(w_exit), b(l_exit)]);
            }
            if l_exit >= 1.0 {
                return out;
            }
            let step = |c: &mut i64, up: bool| *c += if up { 1 } else { -1 };
            if l_col <= l_row {
                step(&mut i, r.ux);
                if l_row == l_col {
                    step(&mut j, r.uy);
                }
            } else {
                step(&mut j, r.uy);
            }
            if !(0..4).contains(&i) || !(0..4).contains(&j) {
                return out;
            }
            l = l_exit;
            w_l = w_exit;
        }
    }

    /// The cells a block returns, in mask order, as [`plain_walk`] lists them.
    fn block_cells(mask: u32, b: &Block, ux: bool, uy: bool) -> Vec<[u32; 5]> {
        let mut out = Vec::new();
        let mut m = mask;
        while m != 0 {
            let p = m.trailing_zeros();
            m &= m - 1;
            let (i, j) = match (ux, uy) {
                (false, false) => cell_of::<false, false>(p),
                (false, true) => cell_of::<false, true>(p),
                (true, false) => cell_of::<true, false>(p),
                (true, true) => cell_of::<true, true>(p),
            };
            let k = lane(i, j);
            out.push([
                i,
                j,
                b.w_in[k].to_bits(),
                b.w_out[k].to_bits(),
                b.exit[k].to_bits(),
            ]);
        }
        out
    }

    /// A block traces the cells the plain level-0 walk traces inside it, in its order, over
    /// the same `λ` and `w` bits; the AVX2 copy returns the portable twin's mask and lanes.
    /// Random segments (a quarter through cell corners, so crossings tie; some along an
    /// axis), start cells found by flooring as `refine` does, random texels and slab masks.
    #[test]
    fn block_equals_the_plain_walk() {
        let mut rng = Rng::new(0xb10c, 3);
        let width = 16usize;
        let mut f = || rng.next_f32();
        let mut cases = 0;
        let mut traced = 0usize;
        let mut ties = 0;
        for n in 0..40_000 {
            let texels: Vec<Texel> = (0..width * 16)
                .map(|_| {
                    let lo = f() * 2.0;
                    let hi = lo + f() * f() * 2.0;
                    let shift = (f() * 24.0) as u64;
                    // Half the texels with every slab occupied, the others sparse.
                    let bits = if f() < 0.5 {
                        u64::MAX
                    } else {
                        ((f() * 65536.0) as u64) << (f() * 40.0) as u32
                    };
                    let mut t = Texel {
                        lo,
                        hi,
                        slabs: (shift << 56) | (bits & ((1 << SLABS) - 1)),
                    };
                    if f() < 0.1 {
                        t.lo = f32::NAN;
                    }
                    t
                })
                .collect();
            let (bx, by) = (4 * (f() * 3.0) as u32, 4 * (f() * 3.0) as u32);
            let mut x_a = bx as f32 + f() * 6.0 - 1.0;
            let mut y_a = by as f32 + f() * 6.0 - 1.0;
            let (mut dx, mut dy) = (f() * 12.0 - 6.0, f() * 12.0 - 6.0);
            if n % 4 == 0 {
                // Through cell corners.
                x_a = x_a.floor();
                y_a = y_a.floor();
                let d = (f() * 6.0).floor() - 3.0;
                (dx, dy) = (d, d * if f() < 0.5 { 1.0 } else { -1.0 });
            }
            match n % 7 {
                0 => dx = 0.0,
                1 => dy = 0.0,
                _ => {}
            }
            let axis = |a: f32, d: f32| {
                if d.abs() <= 1e-30 {
                    (0.0, f32::INFINITY, d > 0.0)
                } else {
                    let inv = 1.0 / d;
                    (inv, -a * inv, d > 0.0)
                }
            };
            let (x_inv, x_c, ux) = axis(x_a, dx);
            let (y_inv, y_c, uy) = axis(y_a, dy);
            let l = if f() < 0.2 { 0.0 } else { f() * 0.9 };
            let cell = |a: f32, d: f32, b: u32| {
                let x = a + l * d;
                if x > 0.0 {
                    (x as u32).clamp(b, b + 3)
                } else {
                    b
                }
            };
            let (cx, cy) = (cell(x_a, dx, bx), cell(y_a, dy, by));
            let w = 0.2 + f() * 1.5;
            let dw = (f() - 0.5) * 2.0;
            let r = Ray {
                bx,
                by,
                x_inv,
                x_c,
                y_inv,
                y_c,
                i0: cx - bx,
                j0: cy - by,
                l,
                w_l: w + l * dw,
                w,
                dw,
                ux,
                uy,
                w_falls: dw < 0.0,
            };
            let row0 = by as usize * width + bx as usize;
            let mut b = Block::EMPTY;
            let m = test::<false>(&texels, row0, width, &r, &mut b);
            let want = plain_walk(&texels, row0, width, &r);
            assert_eq!(block_cells(m, &b, ux, uy), want, "case {n}");
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                let mut b2 = Block::EMPTY;
                let m2 = test::<true>(&texels, row0, width, &r, &mut b2);
                assert_eq!(m2, m, "case {n}");
                let bits = |b: &Block| [b.exit, b.w_in, b.w_out].map(|a| a.map(f32::to_bits));
                assert_eq!(bits(&b2), bits(&b), "case {n}");
            }
            cases += 1;
            traced += want.len();
            ties += (n % 4 == 0 && want.len() > 1) as usize;
        }
        assert!(
            cases == 40_000 && traced > 5_000 && ties > 20,
            "{traced} {ties}"
        );
    }

    #[test]
    fn slab_w_is_slab() {
        for s in 0..32u32 {
            for &(w, lo) in &[(0.5f32, 0.25f32), (1.0, 0.9), (3.0, 0.0), (-1.0, 0.1)] {
                let base = lo.to_bits() >> s;
                assert_eq!(slab_w(w, s, base), slab(w, s, base));
            }
        }
    }
}
