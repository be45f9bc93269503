//! A row of the effective planes ([`super::QuadTree::effective_planes`], the brute-force
//! twin's per-pixel planes) sixteen pixels per step in AVX-512 lanes (run-time detection of
//! AVX-512 F, BW, DQ, VL and F16C), one pixel per lane: the pixel's effective level (from
//! `effective_levels`), its effective node gathered from that level (`vpgatherqq` of the
//! node words, one address per lane), and the node decoded as [`decode_plane`] does.
//!
//! **Same bits.** Every lane does [`decode_plane`]'s operations in its order:
//! [`Node::test_normal`] (the f16 increments by `vcvtph2ps`, equal to `f16_bits_to_f32` for
//! every finite half, and a plane node holds only finite halves; times `W 2^-L`, `H 2^-L` by
//! lowering the exponent; `max(|gx|, |gy|, 1)` by `vmaxps`, which picks the same operand as
//! the definition's compares for these non-NaN values; the scale `2^-e` from the exponent
//! field; `-s` as a sign flip), [`node_centre`]'s `((q + 0.5) 2^L) / W` (`q` and `2^L` exact
//! in f32), and the `Vec3` dot `(n.x x_c + n.y y_c) + n.z z_c`. Nothing is fused (no FMA
//! contraction). Pixels without a plane get a zero normal, offset 0 and no flag, as
//! [`super::tree::decoded_planes`] writes them. The test `tests/quadtree_build.rs` compares
//! the planes with the per-pixel climb's.
//!
//! | parameter | value |
//! |---|---|
//! | pixels per step | 16 (the row's first `16 floor(W / 16)`) |
//! | levels | at most 16 (more: the scalar path) |
//! | target features | `avx512f,avx512bw,avx512dq,avx512vl,f16c` |
//!
//! [`decode_plane`]: super::node::decode_plane
//! [`node_centre`]: super::node::node_centre
//! [`Node::test_normal`]: super::node::Node::test_normal

use core::arch::x86_64::*;
use core::mem::MaybeUninit;

use glam::Vec3;

use super::node::{FLAG_CRACK, NO_PLANE, Node};

/// Whether this CPU runs [`PlaneRows::row16`] (the build's AVX-512 kernels' one check).
pub(super) use super::avx512_available as available;

/// The levels' node arrays as the gather reads them: per level the byte offset of its first
/// node from level 0's and its width in nodes (lanes past the last level: 0).
pub(super) struct PlaneRows {
    base: *const u8,
    offsets: [i64; 16],
    widths: [i32; 16],
    wf: f32,
    hf: f32,
}

// SAFETY: `base` points into the levels, which the borrow of `new` keeps alive and unchanged
// while the rows are made (the struct is only used inside `effective_planes`).
unsafe impl Sync for PlaneRows {}

/// `vpermt2ps` indices of the AoS store: `(x, y, z)` lanes to the 48 floats of sixteen
/// `Vec3`s, as three 16-float rows; step 1 picks from `x || y`, step 2 adds `z`.
const fn aos_idx(row: usize) -> [[i32; 16]; 2] {
    let mut r = [[0i32; 16]; 2];
    let mut e = 0;
    while e < 16 {
        let f = 16 * row + e; // float index in the 48
        let (lane, c) = (f / 3, f % 3);
        // Step 1: `x` (0-15) or `y` (16-31); `z` elements get a placeholder.
        r[0][e] = match c {
            0 => lane as i32,
            1 => 16 + lane as i32,
            _ => 0,
        };
        // Step 2: keep the element of step 1 (0-15) or take `z` (16-31).
        r[1][e] = if c == 2 { 16 + lane as i32 } else { e as i32 };
        e += 1;
    }
    r
}

const AOS_IDX: [[[i32; 16]; 2]; 3] = [aos_idx(0), aos_idx(1), aos_idx(2)];

impl PlaneRows {
    /// The gather tables of the levels `levels` (per level its nodes and its width in
    /// nodes, level 0 first) of a `wf x hf` layer; `None` with more than 16 levels.
    pub(super) fn new(levels: &[(&[Node], u32)], wf: f32, hf: f32) -> Option<Self> {
        if levels.is_empty() || levels.len() > 16 {
            return None;
        }
        let base = levels[0].0.as_ptr() as *const u8;
        let (mut offsets, mut widths) = ([0i64; 16], [0i32; 16]);
        for (l, &(nodes, w)) in levels.iter().enumerate() {
            offsets[l] = (nodes.as_ptr() as isize).wrapping_sub(base as isize) as i64;
            widths[l] = w as i32;
        }
        Some(Self {
            base,
            offsets,
            widths,
            wf,
            hf,
        })
    }

    /// The planes of the first `16 floor(W / 16)` pixels of row `j` (`W = normal.len()`;
    /// `eff` the row's effective levels, at least `W`) into `normal`, `offset`, `flag`;
    /// returns how many pixels it wrote.
    ///
    /// # Safety
    /// The CPU must have what [`available`] checks; `eff` must be the effective levels of
    /// the levels `self` was made from (each level below their count, the node inside it).
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,f16c")]
    pub(super) unsafe fn row16(
        &self,
        j: u32,
        eff: &[u8],
        normal: &mut [MaybeUninit<Vec3>],
        offset: &mut [MaybeUninit<f32>],
        flag: &mut [MaybeUninit<bool>],
    ) -> usize {
        let w = normal.len();
        let n16 = w & !15;
        assert!(eff.len() >= n16 && offset.len() >= n16 && flag.len() >= n16);
        let si = _mm512_set1_epi32;
        let s = _mm512_set1_ps;
        // SAFETY: 16-element tables.
        let (offs_lo, offs_hi, widths, idx) = unsafe {
            (
                _mm512_loadu_si512(self.offsets.as_ptr() as *const _),
                _mm512_loadu_si512(self.offsets.as_ptr().add(8) as *const _),
                _mm512_loadu_si512(self.widths.as_ptr() as *const _),
                AOS_IDX.map(|t| t.map(|r| _mm512_loadu_si512(r.as_ptr() as *const _))),
            )
        };
        let lanes = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
        let evens = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
        let odds = _mm512_add_epi32(evens, si(1));
        let (wbits, hbits) = (si(self.wf.to_bits() as i32), si(self.hf.to_bits() as i32));
        let (wf, hf) = (s(self.wf), s(self.hf));
        let jv = si(j as i32);
        let mut i = 0;
        while i < n16 {
            // SAFETY: `i + 16 <= n16 <= eff.len()` (asserted).
            let l8 = unsafe { _mm_loadu_si128(eff.as_ptr().add(i) as *const __m128i) };
            let plane: __mmask16 = _mm_cmpneq_epi8_mask(l8, _mm_set1_epi8(NO_PLANE as i8));
            let l = _mm512_maskz_cvtepu8_epi32(plane, l8);
            // The node `(i >> L, j >> L)` of level `L`: its byte offset from level 0's first.
            let qx = _mm512_srlv_epi32(_mm512_add_epi32(si(i as i32), lanes), l);
            let qy = _mm512_srlv_epi32(jv, l);
            let k = _mm512_add_epi32(
                _mm512_mullo_epi32(qy, _mm512_permutexvar_epi32(l, widths)),
                qx,
            );
            let (l_lo, l_hi) = (_mm512_castsi512_si256(l), _mm512_extracti32x8_epi32::<1>(l));
            let (k_lo, k_hi) = (_mm512_castsi512_si256(k), _mm512_extracti32x8_epi32::<1>(k));
            let addr = |lh: __m256i, kh: __m256i| {
                _mm512_add_epi64(
                    _mm512_permutex2var_epi64(offs_lo, _mm512_cvtepu32_epi64(lh), offs_hi),
                    _mm512_slli_epi64::<3>(_mm512_cvtepu32_epi64(kh)),
                )
            };
            // SAFETY: the lanes with a plane address a node of their level (the caller's
            // contract); the others are not read (masked).
            let (g_lo, g_hi) = unsafe {
                (
                    _mm512_mask_i64gather_epi64::<1>(
                        _mm512_setzero_si512(),
                        plane as __mmask8,
                        addr(l_lo, k_lo),
                        self.base as *const _,
                    ),
                    _mm512_mask_i64gather_epi64::<1>(
                        _mm512_setzero_si512(),
                        (plane >> 8) as __mmask8,
                        addr(l_hi, k_hi),
                        self.base as *const _,
                    ),
                )
            };
            // The `a` and `b` words of the sixteen nodes.
            let a = _mm512_permutex2var_epi32(g_lo, evens, g_hi);
            let b = _mm512_permutex2var_epi32(g_lo, odds, g_hi);
            // `Node::gradient`: the increments times `W 2^-L`, `H 2^-L`.
            let l23 = _mm512_slli_epi32::<23>(l);
            let ws = _mm512_castsi512_ps(_mm512_sub_epi32(wbits, l23));
            let hs = _mm512_castsi512_ps(_mm512_sub_epi32(hbits, l23));
            let ex = _mm512_cvtph_ps(_mm512_cvtepi32_epi16(b));
            let ey = _mm512_cvtph_ps(_mm512_cvtepi32_epi16(_mm512_srli_epi32::<16>(b)));
            let (gx, gy) = (_mm512_mul_ps(ex, ws), _mm512_mul_ps(ey, hs));
            // `Node::test_normal`.
            let m = _mm512_max_ps(_mm512_abs_ps(gx), _mm512_abs_ps(gy));
            let m = _mm512_max_ps(m, s(1.0));
            let e = _mm512_and_si512(_mm512_castps_si512(m), si(0x7f80_0000));
            let sc = _mm512_castsi512_ps(_mm512_sub_epi32(si(0x7f00_0000), e));
            let nx = _mm512_mul_ps(gx, sc);
            let ny = _mm512_mul_ps(gy, sc);
            let nz = _mm512_castsi512_ps(_mm512_xor_si512(si(i32::MIN), _mm512_castps_si512(sc)));
            // `node_centre`: `((q + 0.5) 2^L) / W`, `2^L` from its exponent.
            let size = _mm512_castsi512_ps(_mm512_add_epi32(si(127 << 23), l23));
            let xc = _mm512_div_ps(
                _mm512_mul_ps(_mm512_add_ps(_mm512_cvtepi32_ps(qx), s(0.5)), size),
                wf,
            );
            let yc = _mm512_div_ps(
                _mm512_mul_ps(_mm512_add_ps(_mm512_cvtepi32_ps(qy), s(0.5)), size),
                hf,
            );
            let zc = _mm512_castsi512_ps(_mm512_and_si512(a, si(0x7fff_fffc)));
            let c = _mm512_add_ps(
                _mm512_add_ps(_mm512_mul_ps(nx, xc), _mm512_mul_ps(ny, yc)),
                _mm512_mul_ps(nz, zc),
            );
            // No plane: zero normal and offset.
            let (nx, ny, nz, c) = (
                _mm512_maskz_mov_ps(plane, nx),
                _mm512_maskz_mov_ps(plane, ny),
                _mm512_maskz_mov_ps(plane, nz),
                _mm512_maskz_mov_ps(plane, c),
            );
            let crack = plane & _mm512_test_epi32_mask(a, si(FLAG_CRACK as i32));
            // The sixteen `Vec3`s: x and y interleaved with a gap for z, then z.
            let aos = |r: usize| {
                let t = _mm512_permutex2var_ps(nx, idx[r][0], ny);
                _mm512_permutex2var_ps(t, idx[r][1], nz)
            };
            // SAFETY: pixels `i .. i + 16` are in bounds of the three rows (asserted; a
            // `Vec3` is three `f32`s, `repr(C)`; a `bool` one byte, written as 0 or 1).
            unsafe {
                let np = normal.as_mut_ptr().add(i) as *mut f32;
                _mm512_storeu_ps(np, aos(0));
                _mm512_storeu_ps(np.add(16), aos(1));
                _mm512_storeu_ps(np.add(32), aos(2));
                _mm512_storeu_ps(offset.as_mut_ptr().add(i) as *mut f32, c);
                _mm_storeu_si128(
                    flag.as_mut_ptr().add(i) as *mut __m128i,
                    _mm_maskz_set1_epi8(crack, 1),
                );
            }
            i += 16;
        }
        n16
    }
}
