//! The leaves of four pixels of a row at a time in AVX2 lanes (AVX2 and F16C, run-time
//! detection; Widmer et al. 2015, §3.2;
//! the map is `leaves.rs`'s, one pixel per lane): the four depths and the per-column
//! direction terms loaded as f32 vectors, the four normals transposed from their AoS `Vec3`s,
//! the sample points in f32 lanes, then the cube covector `q`, `|q.xyz|^2`, the `z`
//! division and the two gradient divisions in f64x4 lanes, and the slopes clamped and
//! f16-encoded in the eight lanes of one register (`vcvtps2ph`, round to nearest even: the
//! definition's rounding, compared for the whole domain by a test). Every lane does exactly the scalar
//! definition's operations in its order (`leaf_lanes.rs` lists them: the direction
//! `(col + row) + back`, `p = position + dir d`, glam's `DMat4 * DVec4` order
//! `((X n.x + Y n.y) + Z n.z) + W w`, `z = (1/near - 1/d) / (1/near - 1/far)`, the slopes
//! `q.x / -q.z`, `q.y / -q.z` rounded to f32 and times `1 / W`, `1 / H`): IEEE products,
//! sums, divisions and roundings are correctly rounded per lane and nothing is fused (no FMA
//! is enabled), so the nodes are the same bits. A pixel is empty under the same conditions,
//! evaluated for all four lanes and combined into one mask: depth not finite or `<= 0`,
//! normal zero, `|q.xyz|^2` not finite or `<= 0`, a NaN slope, `z` not finite or `< 0`.
//! The test below compares rows with the one-pixel SSE2 path (`leaf_lanes`) on random and
//! degenerate inputs; `tests/quadtree_build.rs` compares whole trees with the reference.

use core::arch::x86_64::*;

use glam::{DMat4, Vec3};

use super::node::{FLAG_CRACK, Node};

/// Largest finite f16.
pub(super) const F16_MAX: f32 = 65504.0;

/// The constants of the four-pixel leaf map of one layer (and of the eight-pixel one of
/// `leaf_avx512`); exists only on CPUs with AVX2 and F16C.
pub(super) struct LeafMap4 {
    /// `M^T`'s entries, `m[c][r]` = column `c`, row `r` (`x_axis` .. `w_axis`).
    pub(super) m: [[f64; 4]; 4],
    pub(super) position: Vec3,
    pub(super) back: Vec3,
    pub(super) inv_near: f64,
    pub(super) z_den: f64,
    /// `1 / W`, `1 / H`: [`Node::plane_with_gradient`]'s scale at level 0.
    pub(super) scale: [f32; 2],
    /// Whether the CPU runs `leaf_avx512` (checked once).
    pub(super) avx512: bool,
}

impl LeafMap4 {
    /// The map of the transposed inverse cube map `mt` for a `wf x hf` layer seen from
    /// `position` (`back` the direction terms' constant, `inv_near` / `z_den` those of
    /// `z_of_depth`); `None` without AVX2 and F16C.
    pub(super) fn new(
        mt: &DMat4,
        position: Vec3,
        back: Vec3,
        inv_near: f64,
        z_den: f64,
        wf: f32,
        hf: f32,
    ) -> Option<Self> {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c"))
        {
            return None;
        }
        let size = 1.0f32;
        Some(Self {
            m: [mt.x_axis, mt.y_axis, mt.z_axis, mt.w_axis].map(|c| c.to_array()),
            position,
            back,
            inv_near,
            z_den,
            scale: [size / wf, size / hf],
            avx512: super::avx512_available(),
        })
    }

    /// [`Self::row`] four pixels per step: the first `4 floor(W / 4)` pixels of the row
    /// (`W = out.len()`); returns how many pixels it wrote.
    #[target_feature(enable = "avx2,f16c")]
    pub(super) fn row_avx2(
        &self,
        col: [&[f32]; 3],
        rj: Vec3,
        depth: &[f32],
        normals: &[Vec3],
        flags: Option<&[bool]>,
        out: &mut [Node],
    ) -> usize {
        let w = out.len();
        let n4 = w & !3;
        assert!(
            depth.len() >= n4
                && normals.len() >= n4
                && col.iter().all(|c| c.len() >= n4)
                && flags.is_none_or(|f| f.len() >= n4)
        );
        let m = &self.m;
        let bc = |v: f64| _mm256_set1_pd(v);
        let (m0, m1, m2, m3) = (m[0].map(bc), m[1].map(bc), m[2].map(bc), m[3].map(bc));
        let s = |v: f32| _mm_set1_ps(v);
        let (ox, oy, oz) = (s(self.position.x), s(self.position.y), s(self.position.z));
        let (rx, ry, rz) = (s(rj.x), s(rj.y), s(rj.z));
        let (bx, by, bz) = (s(self.back.x), s(self.back.y), s(self.back.z));
        let (inv_near, z_den) = (bc(self.inv_near), bc(self.z_den));
        let one = bc(1.0);
        let neg = _mm256_set1_pd(-0.0);
        let zero_ps = _mm_setzero_ps();
        let inf_ps = _mm_set1_ps(f32::INFINITY);
        let zero_pd = _mm256_setzero_pd();
        let inf_pd = _mm256_set1_pd(f64::INFINITY);
        let scale = _mm256_setr_ps(
            self.scale[0],
            self.scale[0],
            self.scale[0],
            self.scale[0],
            self.scale[1],
            self.scale[1],
            self.scale[1],
            self.scale[1],
        );
        let (lo, hi) = (_mm256_set1_ps(-F16_MAX), _mm256_set1_ps(F16_MAX));
        let empty_a = _mm_set1_epi32(Node::EMPTY.a as i32);
        let empty_b = _mm_set1_epi32(Node::EMPTY.b as i32);
        let mut i = 0;
        while i < n4 {
            // SAFETY: `i + 4 <= n4` and every slice holds at least `n4` elements (asserted);
            // a `Vec3` is three `f32`s (`repr(C)`), so four of them are 12 floats; `Node`
            // is two `u32`s (`repr(C)`), so four of them are 32 bytes.
            let (d, v0, v1, v2, cx, cy, cz, fl) = unsafe {
                let np = normals.as_ptr().add(i) as *const f32;
                (
                    _mm_loadu_ps(depth.as_ptr().add(i)),
                    _mm_loadu_ps(np),
                    _mm_loadu_ps(np.add(4)),
                    _mm_loadu_ps(np.add(8)),
                    _mm_loadu_ps(col[0].as_ptr().add(i)),
                    _mm_loadu_ps(col[1].as_ptr().add(i)),
                    _mm_loadu_ps(col[2].as_ptr().add(i)),
                    flags.map(|f| (f.as_ptr().add(i) as *const u32).read_unaligned()),
                )
            };
            // AoS -> SoA: v0 = x0 y0 z0 x1, v1 = y1 z1 x2 y2, v2 = z2 x3 y3 z3.
            let t = _mm_blend_ps::<0b0010>(_mm_blend_ps::<0b0100>(v0, v1), v2);
            let nx = _mm_shuffle_ps::<0b01_10_11_00>(t, t);
            let t = _mm_blend_ps::<0b0100>(_mm_blend_ps::<0b0010>(v1, v0), v2);
            let ny = _mm_shuffle_ps::<0b10_11_00_01>(t, t);
            let t = _mm_blend_ps::<0b0010>(_mm_blend_ps::<0b0100>(v2, v0), v1);
            let nz = _mm_shuffle_ps::<0b11_00_01_10>(t, t);
            // Empty: depth not in (0, inf) or normal zero.
            let ok_d = _mm_and_ps(_mm_cmpgt_ps(d, zero_ps), _mm_cmplt_ps(d, inf_ps));
            let n_zero = _mm_and_ps(
                _mm_and_ps(_mm_cmpeq_ps(nx, zero_ps), _mm_cmpeq_ps(ny, zero_ps)),
                _mm_cmpeq_ps(nz, zero_ps),
            );
            let ok32 = _mm_andnot_ps(n_zero, ok_d);
            // `dir = (col + rj) + back`, `p = position + dir d`, in f32.
            let px = _mm_add_ps(ox, _mm_mul_ps(_mm_add_ps(_mm_add_ps(cx, rx), bx), d));
            let py = _mm_add_ps(oy, _mm_mul_ps(_mm_add_ps(_mm_add_ps(cy, ry), by), d));
            let pz = _mm_add_ps(oz, _mm_mul_ps(_mm_add_ps(_mm_add_ps(cz, rz), bz), d));
            let (px, py, pz) = (
                _mm256_cvtps_pd(px),
                _mm256_cvtps_pd(py),
                _mm256_cvtps_pd(pz),
            );
            let (nx, ny, nz) = (
                _mm256_cvtps_pd(nx),
                _mm256_cvtps_pd(ny),
                _mm256_cvtps_pd(nz),
            );
            // `w = -n·p`, `q = M^T (n, w)`.
            let dot = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(nx, px), _mm256_mul_pd(ny, py)),
                _mm256_mul_pd(nz, pz),
            );
            let ww = _mm256_xor_pd(dot, neg);
            let q = |r: usize| {
                _mm256_add_pd(
                    _mm256_add_pd(
                        _mm256_add_pd(_mm256_mul_pd(m0[r], nx), _mm256_mul_pd(m1[r], ny)),
                        _mm256_mul_pd(m2[r], nz),
                    ),
                    _mm256_mul_pd(m3[r], ww),
                )
            };
            let (qx, qy, qz) = (q(0), q(1), q(2));
            let len2 = _mm256_add_pd(
                _mm256_add_pd(_mm256_mul_pd(qx, qx), _mm256_mul_pd(qy, qy)),
                _mm256_mul_pd(qz, qz),
            );
            let nqz = _mm256_xor_pd(qz, neg);
            let gx = _mm256_div_pd(qx, nqz);
            let gy = _mm256_div_pd(qy, nqz);
            // `z = (1/near - 1/d) / (1/near - 1/far)`, rounded to f32.
            let zc = _mm256_cvtpd_ps(_mm256_div_pd(
                _mm256_sub_pd(inv_near, _mm256_div_pd(one, _mm256_cvtps_pd(d))),
                z_den,
            ));
            // Empty: `|q|^2` not in (0, inf), a NaN slope, `z` not in [0, inf).
            let ok64 = _mm256_andnot_pd(
                _mm256_or_pd(
                    _mm256_cmp_pd::<_CMP_UNORD_Q>(gx, gx),
                    _mm256_cmp_pd::<_CMP_UNORD_Q>(gy, gy),
                ),
                _mm256_and_pd(
                    _mm256_cmp_pd::<_CMP_GT_OQ>(len2, zero_pd),
                    _mm256_cmp_pd::<_CMP_LT_OQ>(len2, inf_pd),
                ),
            );
            // The f64 mask's lanes narrowed to 32 bits (each lane is all ones or zeros).
            let ok64 = _mm256_castps256_ps128(_mm256_permutevar8x32_ps(
                _mm256_castpd_ps(ok64),
                _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6),
            ));
            let ok_z = _mm_and_ps(_mm_cmpge_ps(zc, zero_ps), _mm_cmplt_ps(zc, inf_ps));
            let ok = _mm_castps_si128(_mm_and_ps(_mm_and_ps(ok32, ok64), ok_z));
            // The slopes: f32, scaled, clamped, f16.
            let e = _mm256_set_m128(_mm256_cvtpd_ps(gy), _mm256_cvtpd_ps(gx));
            let e = _mm256_min_ps(_mm256_max_ps(_mm256_mul_ps(e, scale), lo), hi);
            // Halves `x0..x3, y0..y3`, interleaved into the words `x | y << 16`.
            let h = f16x8(e);
            let b = _mm_unpacklo_epi16(h, _mm_unpackhi_epi64(h, h));
            let bits = _mm_and_si128(
                _mm_add_epi32(_mm_castps_si128(zc), _mm_set1_epi32(2)),
                _mm_set1_epi32(!3),
            );
            let mut a = _mm_or_si128(_mm_set1_epi32(0x8000_0000u32 as i32), bits);
            if let Some(f) = fl {
                // Four `bool`s (0 or 1): flag `O` where set.
                let set = _mm_cmpgt_epi32(
                    _mm_cvtepu8_epi32(_mm_cvtsi32_si128(f as i32)),
                    _mm_setzero_si128(),
                );
                a = _mm_or_si128(a, _mm_and_si128(set, _mm_set1_epi32(FLAG_CRACK as i32)));
            }
            let a = _mm_blendv_epi8(empty_a, a, ok);
            let b = _mm_blendv_epi8(empty_b, b, ok);
            // SAFETY: `out[i..i + 4]` is 32 bytes in bounds (above).
            unsafe {
                let op = out.as_mut_ptr().add(i) as *mut __m128i;
                _mm_storeu_si128(op, _mm_unpacklo_epi32(a, b));
                _mm_storeu_si128(op.add(1), _mm_unpackhi_epi32(a, b));
            }
            i += 4;
        }
        n4
    }
}

/// [`super::node::f32_to_f16_bits`] of eight lanes (values not NaN, at most 65504 in
/// magnitude), by F16C's `vcvtps2ph` with rounding to nearest even: the definition is that
/// rounding (normal halves by the rebiased exponent and the round-to-even carry,
/// subnormal halves by the exact magic-number addition), and the test below compares the
/// two for every non-negative value of the domain and a set of negative ones. The halves
/// in the eight 16-bit lanes of the result.
#[target_feature(enable = "avx2,f16c")]
pub(super) fn f16x8(v: __m256) -> __m128i {
    _mm256_cvtps_ph::<_MM_FROUND_TO_NEAREST_INT>(v)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::quadtree::leaf_lanes::LeafMap;
    use crate::quadtree::node::{f16_bits_to_f32, f32_to_f16_bits};
    use crate::quadtree::test_rng::Rng;
    use glam::DVec4;

    /// `vcvtps2ph` equals `f32_to_f16_bits` for every non-negative f32 up to 65504 (all
    /// of them), and for their negatives on a spread of values and the subnormal and
    /// rounding boundaries.
    #[test]
    fn f16c_encodes_as_the_definition() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c"))
        {
            eprintln!("no AVX2 and F16C: nothing to compare");
            return;
        }
        #[target_feature(enable = "avx2,f16c")]
        fn cvt8(v: [f32; 8]) -> [u16; 8] {
            let mut out = [0u16; 8];
            // SAFETY: reads and writes eight-element arrays.
            unsafe {
                let h = f16x8(_mm256_loadu_ps(v.as_ptr()));
                _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, h);
            }
            out
        }
        let check = |v: [f32; 8]| {
            // SAFETY: the CPU has AVX2 and F16C (checked).
            let got = unsafe { cvt8(v) };
            for (x, h) in v.iter().zip(got) {
                assert_eq!(h, f32_to_f16_bits(*x), "{x:e} ({:#x})", x.to_bits());
            }
        };
        let top = F16_MAX.to_bits();
        let mut k = 0u32;
        while k <= top {
            check(core::array::from_fn(|d| {
                f32::from_bits((k + d as u32).min(top))
            }));
            k += 8;
        }
        // Negative values: a spread, and around every half and every midpoint of halves.
        let mut neg: Vec<f32> = (0..(1u32 << 20))
            .map(|k| -f32::from_bits(k.wrapping_mul(4099) % (top + 1)))
            .collect();
        for h in 0..0x7bffu16 {
            let (a, b) = (f16_bits_to_f32(h), f16_bits_to_f32(h + 1));
            let m = 0.5 * (a + b);
            for v in [a, m, b] {
                for d in [-1i32, 0, 1] {
                    let x = f32::from_bits((v.to_bits() as i32 + d).max(0) as u32).min(F16_MAX);
                    neg.push(-x);
                }
            }
        }
        for c in neg.chunks(8) {
            check(core::array::from_fn(|d| c.get(d).copied().unwrap_or(-0.0)));
        }
    }

    /// A random row of the leaf map: the map and the row's inputs, and what the expected
    /// leaves are computed from (`map`, `position`, `back`, `inv_near`, `z_den`, `cols`).
    pub(in crate::quadtree) struct Case {
        pub(in crate::quadtree) map4: LeafMap4,
        map: LeafMap,
        position: Vec3,
        back: Vec3,
        pub(in crate::quadtree) rj: Vec3,
        inv_near: f64,
        z_den: f64,
        cols: Vec<Vec3>,
        pub(in crate::quadtree) soa: [Vec<f32>; 3],
        pub(in crate::quadtree) depth: Vec<f32>,
        pub(in crate::quadtree) normals: Vec<Vec3>,
        pub(in crate::quadtree) flags: Vec<bool>,
    }

    /// 64 random rows (widths 256 to 263, so that the eight- and four-pixel kernels share
    /// rows): random pixels, and depths / normals that are zero, negative, infinite, NaN,
    /// tiny or huge, normals perpendicular to the view (infinite and 0/0 slopes), flags.
    pub(in crate::quadtree) fn random_cases() -> Vec<Case> {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        (0..64)
            .map(|case| {
                // A random invertible-ish affine-projective `M^T`, camera, and row terms.
                let mut col4 = || {
                    DVec4::new(
                        rng.f(-2.0, 2.0) as f64,
                        rng.f(-2.0, 2.0) as f64,
                        rng.f(-2.0, 2.0) as f64,
                        rng.f(-2.0, 2.0) as f64,
                    )
                };
                let mt = DMat4::from_cols(col4(), col4(), col4(), col4());
                let v3 =
                    |rng: &mut Rng, s: f32| Vec3::new(rng.f(-s, s), rng.f(-s, s), rng.f(-s, s));
                let (position, back, rj) =
                    (v3(&mut rng, 10.0), v3(&mut rng, 1.0), v3(&mut rng, 1.0));
                let (near, far) = (0.05f64 + case as f64 * 0.01, 100.0f64);
                let (inv_near, z_den) = (1.0 / near, 1.0 / near - 1.0 / far);
                let w = 4 * 64 + (case % 8);
                let (wf, hf) = (w as f32, 37.0f32);
                let map4 = LeafMap4::new(&mt, position, back, inv_near, z_den, wf, hf).unwrap();
                let map = LeafMap::new(&mt, wf, hf);
                let cols: Vec<Vec3> = (0..w).map(|_| v3(&mut rng, 1.0)).collect();
                let special = [0.0, -0.0, -1.0, f32::INFINITY, f32::NAN, 1e-30, 1e30, 0.01];
                let depth: Vec<f32> = (0..w)
                    .map(|_| match rng.next() % 8 {
                        0 => special[(rng.next() % 8) as usize],
                        _ => rng.f(0.01, 50.0),
                    })
                    .collect();
                let normals: Vec<Vec3> = (0..w)
                    .map(|i| match rng.next() % 8 {
                        0 => Vec3::ZERO,
                        1 => Vec3::new(-0.0, 0.0, -0.0),
                        2 => Vec3::new(0.0, 0.0, f32::NAN),
                        // Perpendicular to the pixel's view direction.
                        3 => ((cols[i] + rj) + back).cross(Vec3::X),
                        _ => v3(&mut rng, 1.0).normalize_or_zero(),
                    })
                    .collect();
                let flags: Vec<bool> = (0..w).map(|_| rng.next().is_multiple_of(3)).collect();
                let soa = [
                    cols.iter().map(|c| c.x).collect(),
                    cols.iter().map(|c| c.y).collect(),
                    cols.iter().map(|c| c.z).collect(),
                ];
                Case {
                    map4,
                    map,
                    position,
                    back,
                    rj,
                    inv_near,
                    z_den,
                    cols,
                    soa,
                    depth,
                    normals,
                    flags,
                }
            })
            .collect()
    }

    /// Rows of the leaf kernels (`LeafMap4::row`: eight pixels per step where the CPU has
    /// AVX-512, then four) equal the one-pixel SSE2 path (`leaf_lanes`, with the same
    /// direction, sample point and `z` as `leaves.rs`) bit for bit, on [`random_cases`], flags
    /// on and off.
    #[test]
    fn rows_equal_the_one_pixel_path() {
        if !(std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c"))
        {
            eprintln!("no AVX2 and F16C: nothing to compare");
            return;
        }
        let mut checked = 0usize;
        for (case, c) in random_cases().iter().enumerate() {
            let w = c.depth.len();
            for fl in [None, Some(&c.flags[..])] {
                let mut out = vec![Node { a: 1, b: 1 }; w];
                // SAFETY: the CPU has AVX2 and F16C (checked).
                let n = unsafe {
                    c.map4.row(
                        [&c.soa[0], &c.soa[1], &c.soa[2]],
                        c.rj,
                        &c.depth,
                        &c.normals,
                        fl,
                        &mut out,
                    )
                };
                assert_eq!(n, w & !3);
                for i in 0..n {
                    let (d, nn) = (c.depth[i], c.normals[i]);
                    let want = if !(d.is_finite() && d > 0.0) || nn == Vec3::ZERO {
                        Node::EMPTY
                    } else {
                        let p = c.position + ((c.cols[i] + c.rj) + c.back) * d;
                        let z = ((c.inv_near - 1.0 / d as f64) / c.z_den) as f32;
                        let f = if fl.is_some_and(|f| f[i]) {
                            FLAG_CRACK
                        } else {
                            0
                        };
                        c.map.leaf(p, nn, z, f)
                    };
                    assert_eq!(out[i], want, "case {case} pixel {i}: d {d:e}, n {nn}");
                    checked += usize::from(want != Node::EMPTY);
                }
                assert!(out[n..].iter().all(|o| *o == Node { a: 1, b: 1 }));
            }
        }
        assert!(checked > 10_000, "{checked} plane leaves compared");
    }
}
