//! The leaves of eight pixels of a row at a time in AVX-512 lanes (Widmer et al. 2015, §3.2;
//! run-time detection of AVX-512 F, BW, DQ, VL and F16C): `leaf_avx2`'s kernel with twice the
//! lanes, and [`LeafMap4::row`], which runs it first where the CPU has them (the four-lane
//! kernel does the rest of the row, the one-pixel path of `leaves.rs` the tail).
//!
//! **Same bits.** Every lane does the four-lane kernel's operations on the same operands in
//! the same order (its module docs list them: the direction `(col + row) + back`, `p =
//! position + dir d` in f32, then in f64 `w = -n·p`, `q = M^T (n, w)` in glam's order,
//! `|q.xyz|^2`, the slopes `q.x / -q.z`, `q.y / -q.z`, `z = (1/near - 1/d) / (1/near -
//! 1/far)`, each rounded to f32 by `vcvtpd2ps`, the slopes scaled, clamped and encoded by
//! `vcvtps2ph` with rounding to nearest even). IEEE products, sums, divisions and roundings
//! are correctly rounded per lane whatever the vector width and nothing is fused (no FMA
//! contraction), so the nodes are the same bits. The empty conditions are the same compares
//! (ordered, so a NaN fails each as there) into `__mmask8` bits instead of vector masks.
//! The eight normals are transposed from their `Vec3`s by one `vpermt2ps` per coordinate.
//!
//! Why a second kernel: the leaf pass is compute-bound (a second pass over cached rows costs
//! as much as the first, `docs/notes/quadtree.md`), and a 512-bit `vdivpd` does eight lanes in
//! the time a 256-bit one does four on cores with full-width AVX-512.
//!
//! | parameter | value |
//! |---|---|
//! | pixels per step | 8 (the row's first `8 floor(W / 8)`) |
//! | target features | `avx512f,avx512bw,avx512dq,avx512vl,f16c` |

use core::arch::x86_64::*;

use glam::Vec3;

use super::leaf_avx2::{F16_MAX, LeafMap4};
use super::node::{FLAG_CRACK, Node};

#[cfg(test)]
use super::avx512_available as available;

/// `vpermt2ps` indices of coordinate `c` of eight `Vec3`s held in `v0` (floats 0-15) and
/// `v1` (floats 16-23): lane `i` takes float `3 i + c` (an index of 16 or more picks from
/// `v1`); lanes 8-15 unused.
const fn soa_idx(c: usize) -> [i32; 16] {
    let mut r = [0i32; 16];
    let mut i = 0;
    while i < 8 {
        r[i] = (3 * i + c) as i32;
        i += 1;
    }
    r
}

const SOA_IDX: [[i32; 16]; 3] = [soa_idx(0), soa_idx(1), soa_idx(2)];

/// `vpermt2d` indices interleaving the `a` words (lanes 0-7 of the first operand) and the
/// `b` words (lanes 0-7 of the second) into eight nodes `a0 b0 a1 b1 ..`.
const NODE_IDX: [i32; 16] = [0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23];

impl LeafMap4 {
    /// The leaves of the first `4 floor(W / 4)` pixels of a row of `W = out.len()` pixels
    /// (`col` the per-column direction terms as x, y, z columns, `rj` the row's term,
    /// `depth`, `normals`, `flags` the row's pixels); returns how many pixels it wrote.
    /// Eight pixels per step where the CPU has AVX-512 (`leaf_avx512`, the same bits), then
    /// four.
    ///
    /// # Safety
    /// The CPU must have AVX2 and F16C (`self` exists only then).
    pub(super) unsafe fn row(
        &self,
        col: [&[f32]; 3],
        rj: Vec3,
        depth: &[f32],
        normals: &[Vec3],
        flags: Option<&[bool]>,
        out: &mut [Node],
    ) -> usize {
        let done = if self.avx512 {
            // SAFETY: the CPU has AVX-512 (checked in `new`).
            unsafe { self.row_avx512(col, rj, depth, normals, flags, out) }
        } else {
            0
        };
        // SAFETY: AVX2 and F16C by the caller's contract.
        done + unsafe {
            self.row_avx2(
                col.map(|c| &c[done..]),
                rj,
                &depth[done..],
                &normals[done..],
                flags.map(|f| &f[done..]),
                &mut out[done..],
            )
        }
    }

    /// [`LeafMap4::row`]'s leaves eight pixels per step: the first `8 floor(W / 8)` pixels of
    /// the row (`W = out.len()`); returns how many pixels it wrote.
    ///
    /// # Safety
    /// The CPU must have what `quadtree::avx512_available` checks.
    #[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,f16c")]
    pub(super) unsafe fn row_avx512(
        &self,
        col: [&[f32]; 3],
        rj: Vec3,
        depth: &[f32],
        normals: &[Vec3],
        flags: Option<&[bool]>,
        out: &mut [Node],
    ) -> usize {
        let w = out.len();
        let n8 = w & !7;
        assert!(
            depth.len() >= n8
                && normals.len() >= n8
                && col.iter().all(|c| c.len() >= n8)
                && flags.is_none_or(|f| f.len() >= n8)
        );
        let m = &self.m;
        let bc = |v: f64| _mm512_set1_pd(v);
        let (m0, m1, m2, m3) = (m[0].map(bc), m[1].map(bc), m[2].map(bc), m[3].map(bc));
        let s = |v: f32| _mm256_set1_ps(v);
        let (ox, oy, oz) = (s(self.position.x), s(self.position.y), s(self.position.z));
        let (rx, ry, rz) = (s(rj.x), s(rj.y), s(rj.z));
        let (bx, by, bz) = (s(self.back.x), s(self.back.y), s(self.back.z));
        let (inv_near, z_den) = (bc(self.inv_near), bc(self.z_den));
        let one = bc(1.0);
        let neg = _mm512_set1_pd(-0.0);
        let zero_ps = _mm256_setzero_ps();
        let inf_ps = s(f32::INFINITY);
        let zero_pd = _mm512_setzero_pd();
        let inf_pd = bc(f64::INFINITY);
        // Lanes 0-7 the `x` slopes (scale `1 / W`), lanes 8-15 the `y` slopes (`1 / H`).
        let scale =
            _mm512_insertf32x8::<1>(_mm512_castps256_ps512(s(self.scale[0])), s(self.scale[1]));
        let (lo, hi) = (_mm512_set1_ps(-F16_MAX), _mm512_set1_ps(F16_MAX));
        let empty_a = _mm256_set1_epi32(Node::EMPTY.a as i32);
        let empty_b = _mm256_set1_epi32(Node::EMPTY.b as i32);
        let plane_bit = _mm256_set1_epi32(0x8000_0000u32 as i32);
        let crack = _mm256_set1_epi32(FLAG_CRACK as i32);
        // SAFETY: the index tables are 16 `i32`s each.
        let (ix, iy, iz, inode) = unsafe {
            (
                _mm512_loadu_si512(SOA_IDX[0].as_ptr() as *const _),
                _mm512_loadu_si512(SOA_IDX[1].as_ptr() as *const _),
                _mm512_loadu_si512(SOA_IDX[2].as_ptr() as *const _),
                _mm512_loadu_si512(NODE_IDX.as_ptr() as *const _),
            )
        };
        let mut i = 0;
        while i < n8 {
            // SAFETY: `i + 8 <= n8` and every slice holds at least `n8` elements (asserted);
            // a `Vec3` is three `f32`s (`repr(C)`), so eight of them are 24 floats (16 + 8
            // loaded); `Node` is two `u32`s (`repr(C)`), so eight of them are 64 bytes.
            let (d, v0, v1, cx, cy, cz, fl) = unsafe {
                let np = normals.as_ptr().add(i) as *const f32;
                (
                    _mm256_loadu_ps(depth.as_ptr().add(i)),
                    _mm512_loadu_ps(np),
                    _mm512_castps256_ps512(_mm256_loadu_ps(np.add(16))),
                    _mm256_loadu_ps(col[0].as_ptr().add(i)),
                    _mm256_loadu_ps(col[1].as_ptr().add(i)),
                    _mm256_loadu_ps(col[2].as_ptr().add(i)),
                    flags.map(|f| (f.as_ptr().add(i) as *const u64).read_unaligned()),
                )
            };
            // AoS -> SoA: lane `i` of coordinate `c` is float `3 i + c`.
            let nx = _mm512_castps512_ps256(_mm512_permutex2var_ps(v0, ix, v1));
            let ny = _mm512_castps512_ps256(_mm512_permutex2var_ps(v0, iy, v1));
            let nz = _mm512_castps512_ps256(_mm512_permutex2var_ps(v0, iz, v1));
            // Empty: depth not in (0, inf) or normal zero.
            let ok_d = _mm256_cmp_ps_mask::<_CMP_GT_OQ>(d, zero_ps)
                & _mm256_cmp_ps_mask::<_CMP_LT_OQ>(d, inf_ps);
            let n_zero = _mm256_cmp_ps_mask::<_CMP_EQ_OQ>(nx, zero_ps)
                & _mm256_cmp_ps_mask::<_CMP_EQ_OQ>(ny, zero_ps)
                & _mm256_cmp_ps_mask::<_CMP_EQ_OQ>(nz, zero_ps);
            let ok32 = ok_d & !n_zero;
            // `dir = (col + rj) + back`, `p = position + dir d`, in f32.
            let px = _mm256_add_ps(
                ox,
                _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(cx, rx), bx), d),
            );
            let py = _mm256_add_ps(
                oy,
                _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(cy, ry), by), d),
            );
            let pz = _mm256_add_ps(
                oz,
                _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(cz, rz), bz), d),
            );
            let (px, py, pz) = (
                _mm512_cvtps_pd(px),
                _mm512_cvtps_pd(py),
                _mm512_cvtps_pd(pz),
            );
            let (nx, ny, nz) = (
                _mm512_cvtps_pd(nx),
                _mm512_cvtps_pd(ny),
                _mm512_cvtps_pd(nz),
            );
            // `w = -n·p`, `q = M^T (n, w)`.
            let dot = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(nx, px), _mm512_mul_pd(ny, py)),
                _mm512_mul_pd(nz, pz),
            );
            let ww = _mm512_castsi512_pd(_mm512_xor_si512(
                _mm512_castpd_si512(dot),
                _mm512_castpd_si512(neg),
            ));
            let q = |r: usize| {
                _mm512_add_pd(
                    _mm512_add_pd(
                        _mm512_add_pd(_mm512_mul_pd(m0[r], nx), _mm512_mul_pd(m1[r], ny)),
                        _mm512_mul_pd(m2[r], nz),
                    ),
                    _mm512_mul_pd(m3[r], ww),
                )
            };
            let (qx, qy, qz) = (q(0), q(1), q(2));
            let len2 = _mm512_add_pd(
                _mm512_add_pd(_mm512_mul_pd(qx, qx), _mm512_mul_pd(qy, qy)),
                _mm512_mul_pd(qz, qz),
            );
            let nqz = _mm512_castsi512_pd(_mm512_xor_si512(
                _mm512_castpd_si512(qz),
                _mm512_castpd_si512(neg),
            ));
            let gx = _mm512_div_pd(qx, nqz);
            let gy = _mm512_div_pd(qy, nqz);
            // `z = (1/near - 1/d) / (1/near - 1/far)`, rounded to f32.
            let zc = _mm512_cvtpd_ps(_mm512_div_pd(
                _mm512_sub_pd(inv_near, _mm512_div_pd(one, _mm512_cvtps_pd(d))),
                z_den,
            ));
            // Empty: `|q|^2` not in (0, inf), a NaN slope, `z` not in [0, inf).
            let nan_g = _mm512_cmp_pd_mask::<_CMP_UNORD_Q>(gx, gx)
                | _mm512_cmp_pd_mask::<_CMP_UNORD_Q>(gy, gy);
            let ok64 = !nan_g
                & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(len2, zero_pd)
                & _mm512_cmp_pd_mask::<_CMP_LT_OQ>(len2, inf_pd);
            let ok_z = _mm256_cmp_ps_mask::<_CMP_GE_OQ>(zc, zero_ps)
                & _mm256_cmp_ps_mask::<_CMP_LT_OQ>(zc, inf_ps);
            let ok: __mmask8 = ok32 & ok64 & ok_z;
            // The slopes: f32, scaled, clamped, f16 (lanes 0-7 `x`, 8-15 `y`).
            let e = _mm512_insertf32x8::<1>(
                _mm512_castps256_ps512(_mm512_cvtpd_ps(gx)),
                _mm512_cvtpd_ps(gy),
            );
            let e = _mm512_min_ps(_mm512_max_ps(_mm512_mul_ps(e, scale), lo), hi);
            let h = _mm512_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(e);
            // The words `x | y << 16`.
            let b = _mm256_or_si256(
                _mm256_cvtepu16_epi32(_mm256_castsi256_si128(h)),
                _mm256_slli_epi32::<16>(_mm256_cvtepu16_epi32(_mm256_extracti128_si256::<1>(h))),
            );
            let bits = _mm256_and_si256(
                _mm256_add_epi32(_mm256_castps_si256(zc), _mm256_set1_epi32(2)),
                _mm256_set1_epi32(!3),
            );
            let mut a = _mm256_or_si256(plane_bit, bits);
            if let Some(f) = fl {
                // Eight `bool`s (0 or 1): flag `O` where set.
                let set = _mm256_cmpgt_epi32_mask(
                    _mm256_cvtepu8_epi32(_mm_cvtsi64_si128(f as i64)),
                    _mm256_setzero_si256(),
                );
                a = _mm256_mask_or_epi32(a, set, a, crack);
            }
            let a = _mm256_mask_blend_epi32(ok, empty_a, a);
            let b = _mm256_mask_blend_epi32(ok, empty_b, b);
            let nodes = _mm512_permutex2var_epi32(
                _mm512_castsi256_si512(a),
                inode,
                _mm512_castsi256_si512(b),
            );
            // SAFETY: `out[i..i + 8]` is 64 bytes in bounds (above).
            unsafe { _mm512_storeu_si512(out.as_mut_ptr().add(i) as *mut _, nodes) };
            i += 8;
        }
        n8
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::leaf_avx2::tests::random_cases;

    /// Rows of the eight-lane kernel equal the four-lane kernel's bit for bit (whose own
    /// test compares them with the one-pixel path) on its random and degenerate rows, flags
    /// on and off; widths 256 to 263, so rows end past the last eight-pixel step.
    #[test]
    fn rows_equal_the_four_lane_kernel() {
        if !available() {
            eprintln!("no AVX-512: nothing to compare");
            return;
        }
        let mut compared = 0usize;
        for c in random_cases() {
            let w = c.depth.len();
            let cols = [&c.soa[0][..], &c.soa[1][..], &c.soa[2][..]];
            for fl in [None, Some(&c.flags[..])] {
                let mut want = vec![Node { a: 1, b: 1 }; w];
                let mut got = vec![Node { a: 2, b: 2 }; w];
                // SAFETY: the CPU has AVX2 and F16C (`map4` exists) and AVX-512 (checked).
                let (n4, n8) = unsafe {
                    (
                        c.map4
                            .row_avx2(cols, c.rj, &c.depth, &c.normals, fl, &mut want),
                        c.map4
                            .row_avx512(cols, c.rj, &c.depth, &c.normals, fl, &mut got),
                    )
                };
                assert_eq!(n8, w & !7);
                assert!(n8 <= n4);
                assert_eq!(got[..n8], want[..n8]);
                assert!(got[n8..].iter().all(|n| *n == Node { a: 2, b: 2 }));
                compared += n8;
            }
        }
        assert!(compared > 10_000, "{compared} leaves compared");
    }
}
