//! The pixel planes' cascade trigger depths ([`super::cascade`], `pixel_trigger`) of a row,
//! sixteen pixels per step in AVX-512 lanes, one pixel per lane (run-time detection of
//! AVX-512 F, BW, DQ, VL and F16C): `trigger_avx2::pixel_triggers_row8` in sixteen lanes,
//! the path the leaf pass takes first where the CPU has them (`fixpoint::pixel_triggers_row`;
//! the eight-lane kernel does the rest of the row, the four-lane and scalar ones the tail).
//!
//! **Same bits.** Every lane does the eight-lane kernel's operations on the same operands in
//! the same order (its module docs list them: the own leaf's plane decoded as
//! `decode_plane_at` at level 0, per deeper layer the covered and edge-on lanes, per
//! footprint corner the deeper plane's `z` by a division, the running minimum by the same
//! compare-select, the own plane's signed distance against `-SAFE_MARGIN`, the trigger depth
//! `max(front - margin, +0)` of unsafe lanes). IEEE products, sums and divisions are
//! correctly rounded per lane whatever the vector width, `vmaxps` picks the same operand in
//! 16 lanes as in 8, nothing is fused (no FMA contraction), and the vector masks of the
//! AVX2 kernel are `__mmask16` bits here (a compare sets the same lanes; a masked blend
//! selects as `vblendvps` did). The f16 slopes are the low and high halves of each node's
//! `b` word, narrowed by `vpmovdw` and decoded by `vcvtph2ps` (equal to
//! `node::f16_bits_to_f32` for every finite half; plane nodes hold only finite halves, and
//! lanes of other nodes are masked out as in the AVX2 kernel). The deeper layers' normals
//! are transposed from their `Vec3`s sixteen at a time by two `vpermt2ps` per coordinate.
//!
//! Valgrind does not run AVX-512, so the instruction counts of the notes are of the AVX2
//! twin; the test below compares rows with it bit for bit.
//!
//! | parameter | value |
//! |---|---|
//! | pixels per step | 16 (the row's first `16 floor(W / 16)`) |
//! | target features | `avx512f,avx512bw,avx512dq,avx512vl,f16c` |

use core::arch::x86_64::*;
use core::mem::MaybeUninit;

use glam::Vec3;

use super::cascade::SAFE_MARGIN;
use super::node::Node;
use crate::LayerPlanes;

/// Whether this CPU runs [`pixel_triggers_row16`] (the build's AVX-512 kernels' one check).
pub(super) use super::avx512_available as available;

/// `vpermt2ps` indices of the transpose (`soa16`): `[first; second]` per coordinate.
const fn soa_idx(c: usize) -> [[i32; 16]; 2] {
    let mut r = [[0i32; 16]; 2];
    let mut i = 0;
    while i < 16 {
        let e = 3 * i + c;
        if e < 32 {
            // From `v0 || v1` in the first step, kept in the second.
            r[0][i] = e as i32;
            r[1][i] = i as i32;
        } else {
            // From `v2` in the second step.
            r[1][i] = 16 + (e - 32) as i32;
        }
        i += 1;
    }
    r
}

const SOA_IDX: [[[i32; 16]; 2]; 3] = [soa_idx(0), soa_idx(1), soa_idx(2)];

/// Sixteen `Vec3`s at `p` as `(x, y, z)` lanes: element `3 i + c` of the 48 floats is lane
/// `i` of coordinate `c`, picked from the three 512-bit rows by two permutes.
///
/// # Safety
/// `p` must point to sixteen readable `Vec3`s (48 `f32`s); the CPU must have AVX-512 F.
#[inline]
#[target_feature(enable = "avx512f")]
unsafe fn soa16(p: *const Vec3) -> (__m512, __m512, __m512) {
    let p = p as *const f32;
    // SAFETY: 48 readable floats (the caller's contract); the index tables are 16 `i32`s.
    unsafe {
        let (v0, v1, v2) = (
            _mm512_loadu_ps(p),
            _mm512_loadu_ps(p.add(16)),
            _mm512_loadu_ps(p.add(32)),
        );
        (
            pick(v0, v1, v2, &SOA_IDX[0]),
            pick(v0, v1, v2, &SOA_IDX[1]),
            pick(v0, v1, v2, &SOA_IDX[2]),
        )
    }
}

/// One coordinate of `soa16`: lanes from `v0 || v1` by `idx[0]`, then from `v2` by `idx[1]`.
#[inline]
#[target_feature(enable = "avx512f")]
fn pick(v0: __m512, v1: __m512, v2: __m512, idx: &[[i32; 16]; 2]) -> __m512 {
    // SAFETY: two tables of 16 `i32`s.
    let (i0, i1) = unsafe {
        (
            _mm512_loadu_si512(idx[0].as_ptr() as *const _),
            _mm512_loadu_si512(idx[1].as_ptr() as *const _),
        )
    };
    _mm512_permutex2var_ps(_mm512_permutex2var_ps(v0, i0, v1), i1, v2)
}

/// `trigger_avx2::pixel_triggers_row8` sixteen pixels per step: the trigger depths of the
/// first `16 floor(W / 16)` pixels of row `j` into `tz` (`W = tz.len()`; only written, so
/// they may be uninitialised) and their deeper fronts into `fronts`, from the row's leaves
/// `nodes`, the footprint edges `xe` (`W + 1` values), the pixel centres `xc`, the row's
/// edges and centre `y = (y0, y1, yc)`, pixel `k0 + i` of the deeper layers; pushes the
/// pixels (`k0 + i`) with a finite trigger depth on `listed`, ascending; returns how many
/// pixels it did.
///
/// # Safety
/// The CPU must have what [`available`] checks.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx512f,avx512bw,avx512dq,avx512vl,f16c")]
pub(super) unsafe fn pixel_triggers_row16(
    tz: &mut [MaybeUninit<f32>],
    fronts: &mut [MaybeUninit<f32>],
    nodes: &[Node],
    k0: usize,
    xe: &[f32],
    xc: &[f32],
    (y0, y1, yc): (f32, f32, f32),
    (wf, hf): (f32, f32),
    deeper: &[LayerPlanes],
    listed: &mut Vec<u32>,
) -> usize {
    let w = tz.len();
    let n16 = w & !15;
    assert!(nodes.len() >= n16 && xe.len() > n16 && xc.len() >= n16 && fronts.len() >= n16);
    assert!(
        deeper
            .iter()
            .all(|pj| pj.normal.len() >= k0 + n16 && pj.offset.len() >= k0 + n16)
    );
    let s = _mm512_set1_ps;
    let si = _mm512_set1_epi32;
    let evens: [i32; 16] = core::array::from_fn(|d| 2 * d as i32);
    let odds: [i32; 16] = core::array::from_fn(|d| 2 * d as i32 + 1);
    let ramp: [i32; 16] = core::array::from_fn(|d| d as i32);
    // SAFETY: 16 `i32`s each.
    let (evens, odds, lane_ids) = unsafe {
        (
            _mm512_loadu_si512(evens.as_ptr() as *const _),
            _mm512_loadu_si512(odds.as_ptr() as *const _),
            _mm512_loadu_si512(ramp.as_ptr() as *const _),
        )
    };
    let neg0 = si(i32::MIN);
    let (sy0, sy1, syc) = (s(y0), s(y1), s(yc));
    let margin = s(-SAFE_MARGIN);
    let z0 = _mm512_setzero_ps();
    let mut i = 0;
    while i < n16 {
        let k = k0 + i;
        // SAFETY: `i + 16 <= n16` and the slices hold `n16` (`xe`: `n16 + 1`) elements
        // (asserted); `Node` is two `u32`s (`repr(C)`), so 16 nodes are 32 `u32`s.
        let (v0, v1, xcv, x0, x1) = unsafe {
            let np = nodes.as_ptr().add(i) as *const u32;
            (
                _mm512_loadu_si512(np as *const _),
                _mm512_loadu_si512(np.add(16) as *const _),
                _mm512_loadu_ps(xc.as_ptr().add(i)),
                _mm512_loadu_ps(xe.as_ptr().add(i)),
                _mm512_loadu_ps(xe.as_ptr().add(i + 1)),
            )
        };
        // The own planes (`decode_plane_at`, level 0): `a` and `b` words of the 16 nodes.
        let a = _mm512_permutex2var_epi32(v0, evens, v1);
        let b = _mm512_permutex2var_epi32(v0, odds, v1);
        // The f16 slopes: `b`'s low half is `gx`, its high half `gy`.
        let gxh = _mm512_cvtepi32_epi16(b);
        let gyh = _mm512_cvtepi32_epi16(_mm512_srli_epi32::<16>(b));
        let gx = _mm512_mul_ps(_mm512_cvtph_ps(gxh), s(wf));
        let gy = _mm512_mul_ps(_mm512_cvtph_ps(gyh), s(hf));
        let m = _mm512_max_ps(_mm512_abs_ps(gx), _mm512_abs_ps(gy));
        let m = _mm512_max_ps(m, s(1.0));
        let e = _mm512_and_si512(_mm512_castps_si512(m), si(0x7f80_0000));
        let sc = _mm512_castsi512_ps(_mm512_sub_epi32(si(0x7f00_0000), e));
        let (pnx, pny, pnz) = (
            _mm512_mul_ps(gx, sc),
            _mm512_mul_ps(gy, sc),
            _mm512_castsi512_ps(_mm512_xor_si512(neg0, _mm512_castps_si512(sc))),
        );
        let zc = _mm512_castsi512_ps(_mm512_and_si512(a, si(0x7fff_fffc)));
        let pc = _mm512_add_ps(
            _mm512_add_ps(_mm512_mul_ps(pnx, xcv), _mm512_mul_ps(pny, syc)),
            _mm512_mul_ps(pnz, zc),
        );
        let plane: __mmask16 = _mm512_cmplt_epi32_mask(a, _mm512_setzero_si512());
        // The deeper layers, the four footprint corners `(x0, y0), (x1, y0), (x0, y1),
        // (x1, y1)` in that order, shared products once (as the AVX2 kernel).
        let (px0, px1) = (_mm512_mul_ps(pnx, x0), _mm512_mul_ps(pnx, x1));
        let (py0, py1) = (_mm512_mul_ps(pny, sy0), _mm512_mul_ps(pny, sy1));
        let q = [
            _mm512_add_ps(px0, py0),
            _mm512_add_ps(px1, py0),
            _mm512_add_ps(px0, py1),
            _mm512_add_ps(px1, py1),
        ];
        let mut front = s(f32::INFINITY);
        let mut bad: __mmask16 = 0;
        // Lanes with an edge-on deeper plane or a NaN corner `z`: deeper front `-inf`.
        let mut void: __mmask16 = 0;
        for pj in deeper {
            // SAFETY: pixels `k .. k + 16` of the deeper layer exist (asserted).
            let ((nx, ny, nz), cj) = unsafe {
                (
                    soa16(pj.normal.as_ptr().add(k)),
                    _mm512_loadu_ps(pj.offset.as_ptr().add(k)),
                )
            };
            let covered = _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(nx, z0)
                | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(ny, z0)
                | _mm512_cmp_ps_mask::<_CMP_NEQ_UQ>(nz, z0);
            let edge = !_mm512_cmp_ps_mask::<_CMP_LT_OS>(nz, s(-1e-6)) & covered;
            bad |= edge;
            void |= edge;
            front = _mm512_mask_blend_ps(edge, front, z0);
            let live = covered & !edge;
            if live == 0 {
                continue;
            }
            // `z = (cj - nx x - ny y) / nz` per corner, left to right.
            let (c0, c1) = (
                _mm512_sub_ps(cj, _mm512_mul_ps(nx, x0)),
                _mm512_sub_ps(cj, _mm512_mul_ps(nx, x1)),
            );
            let (ny0, ny1) = (_mm512_mul_ps(ny, sy0), _mm512_mul_ps(ny, sy1));
            let z = [
                _mm512_div_ps(_mm512_sub_ps(c0, ny0), nz),
                _mm512_div_ps(_mm512_sub_ps(c1, ny0), nz),
                _mm512_div_ps(_mm512_sub_ps(c0, ny1), nz),
                _mm512_div_ps(_mm512_sub_ps(c1, ny1), nz),
            ];
            let nan = _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(z[0], z[1])
                | _mm512_cmp_ps_mask::<_CMP_UNORD_Q>(z[2], z[3]);
            void |= live & nan;
            // A live lane is bad where its own leaf is no plane or some corner's
            // `f <= -margin` fails (NaN included).
            let mut unsafe_any = !plane;
            for c in 0..4 {
                let lower = live & _mm512_cmp_ps_mask::<_CMP_LT_OS>(z[c], front);
                front = _mm512_mask_blend_ps(lower, front, z[c]);
                let f = _mm512_sub_ps(_mm512_add_ps(q[c], _mm512_mul_ps(pnz, z[c])), pc);
                unsafe_any |= _mm512_cmp_ps_mask::<_CMP_NLE_UQ>(f, margin);
            }
            bad |= live & unsafe_any;
        }
        let t = _mm512_sub_ps(front, s(SAFE_MARGIN));
        let t = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask::<_CMP_GT_OS>(t, z0), t);
        let t = _mm512_mask_blend_ps(bad, s(f32::INFINITY), t);
        // SAFETY: `tz[i..i + 16]` and `fronts[i..i + 16]` are in bounds (`i + 16 <= n16
        // <= W`, asserted).
        unsafe {
            _mm512_storeu_ps(tz.as_mut_ptr().add(i) as *mut f32, t);
            _mm512_storeu_ps(
                fronts.as_mut_ptr().add(i) as *mut f32,
                _mm512_mask_blend_ps(void, front, s(f32::NEG_INFINITY)),
            );
        }
        // The finite ones: `|t| < inf`.
        let bits = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(_mm512_abs_ps(t), s(f32::INFINITY));
        // Their indices `k + d` appended in lane order by one compressing store (no branch
        // per listed pixel: the listed pixels of a row come in irregular runs).
        listed.reserve(16);
        let len = listed.len();
        // SAFETY: room for 16 more `u32`s (reserved); the store writes `popcnt(bits)` of
        // them, which `set_len` then covers.
        unsafe {
            let ids = _mm512_add_epi32(si(k as i32), lane_ids);
            _mm512_mask_compressstoreu_epi32(listed.as_mut_ptr().add(len) as *mut _, bits, ids);
            listed.set_len(len + bits.count_ones() as usize);
        }
        i += 16;
    }
    n16
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::test_rng::Rng;
    use crate::quadtree::trigger_avx2::pixel_triggers_row8;

    /// A random row `j` of width `w` (of `rows`) over `nd` deeper layers: own leaves (planes
    /// with ordinary, clamped and f16-subnormal slopes, empty, AABB, flagged), deeper pixels
    /// covered, uncovered, edge-on or NaN; the footprint edges, centres and `y`s.
    #[allow(clippy::type_complexity)]
    fn random_row(
        rng: &mut Rng,
        w: usize,
        j: u32,
        rows: u32,
        nd: u32,
    ) -> (
        Vec<Node>,
        Vec<LayerPlanes>,
        Vec<f32>,
        Vec<f32>,
        (f32, f32, f32),
    ) {
        let (wf, hf) = (1600.0f32, 900.0f32);
        let plane = |rng: &mut Rng, g: f32, h: f32| {
            Node::plane_with_gradient(
                rng.f(0.0, 1.0),
                rng.f(-g, g),
                rng.f(-h, h),
                0,
                wf,
                hf,
                (rng.next() % 2) as u32,
            )
            .unwrap_or(Node::EMPTY)
        };
        let nodes: Vec<Node> = (0..w)
            .map(|_| match rng.next() % 8 {
                0 => Node::EMPTY,
                1 => Node::aabb(rng.f(0.0, 0.5), rng.f(0.5, 1.0)),
                2 => plane(rng, 1e9, 5e-2),
                _ => plane(rng, 3.0, 3.0),
            })
            .collect();
        let deeper: Vec<LayerPlanes> = (0..nd)
            .map(|_| {
                let n = w * rows as usize;
                let normal: Vec<Vec3> = (0..n)
                    .map(|_| match rng.next() % 8 {
                        0 => Vec3::ZERO,
                        1 => Vec3::new(1.0, 0.0, 0.0),
                        2 => Vec3::new(0.6, 0.8, -1e-7),
                        3 => Vec3::new(0.0, 0.0, f32::NAN),
                        _ => Vec3::new(rng.f(-0.5, 0.5), rng.f(-0.5, 0.5), -1.0).normalize(),
                    })
                    .collect();
                let offset = (0..n).map(|_| rng.f(-1.2, 0.2)).collect();
                LayerPlanes {
                    width: w as u32,
                    height: rows,
                    normal,
                    offset,
                    flag: vec![false; n],
                }
            })
            .collect();
        let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
        let xc: Vec<f32> = (0..w).map(|i| ((i as f32 + 0.5) * 1.0) / wf).collect();
        let y = (
            (j as f32) / hf,
            ((j + 1) as f32) / hf,
            ((j as f32 + 0.5) * 1.0) / hf,
        );
        (nodes, deeper, xe, xc, y)
    }

    /// Rows of the sixteen-lane kernel equal the eight-lane kernel's (whose own test ties it
    /// to the four-lane kernel and the definition) bit for bit, trigger depths and deeper
    /// fronts, and list the same pixels: random own leaves (planes with ordinary, clamped and
    /// f16-subnormal slopes, empty, AABB, flagged) over one or two deeper layers with
    /// covered, uncovered and edge-on pixels.
    #[test]
    fn rows_equal_the_eight_lane_rows() {
        if !(available() && std::arch::is_x86_feature_detected!("avx2")) {
            eprintln!("no AVX-512: nothing to compare");
            return;
        }
        let mut rng = Rng(0x5eed_0f16_1a4e_5eed);
        let (wf, hf) = (1600.0f32, 900.0f32);
        let (mut finite, mut total) = (0usize, 0usize);
        for case in 0..64u32 {
            let w = 16 * (1 + case as usize % 7) + (case as usize % 16);
            let (j, rows) = (case % 3, 3u32);
            let k0 = j as usize * w;
            let (nodes, deeper, xe, xc, y) = random_row(&mut rng, w, j, rows, 1 + case % 2);
            let run = |sixteen: bool| {
                let mut tz = vec![MaybeUninit::new(0.0f32); w];
                let mut fronts = vec![MaybeUninit::new(0.0f32); w];
                let mut listed = Vec::new();
                let kernel = if sixteen {
                    pixel_triggers_row16
                } else {
                    pixel_triggers_row8
                };
                // SAFETY: AVX-512 and AVX2 + F16C (checked above).
                let n = unsafe {
                    kernel(
                        &mut tz,
                        &mut fronts,
                        &nodes,
                        k0,
                        &xe,
                        &xc,
                        y,
                        (wf, hf),
                        &deeper,
                        &mut listed,
                    )
                };
                // SAFETY: initialised above (and written by the kernel).
                let bits = |v: &[MaybeUninit<f32>]| -> Vec<u32> {
                    v.iter()
                        .map(|x| unsafe { x.assume_init() }.to_bits())
                        .collect()
                };
                (n, bits(&tz), bits(&fronts), listed)
            };
            let (n16, tz16, fr16, l16) = run(true);
            let (n8, tz8, fr8, l8) = run(false);
            assert_eq!(n16, w & !15);
            assert!(n8 >= n16);
            assert_eq!(tz16[..n16], tz8[..n16], "case {case} (trigger depths)");
            assert_eq!(fr16[..n16], fr8[..n16], "case {case} (deeper fronts)");
            let want: Vec<u32> = l8
                .into_iter()
                .filter(|&p| (p as usize) < k0 + n16)
                .collect();
            assert_eq!(l16, want, "case {case}");
            finite += want.len();
            total += n16;
        }
        assert!(
            finite > total / 10 && finite < total,
            "{finite} of {total} finite"
        );
    }

    /// Not a test of speed (it asserts nothing about time): prints the thread CPU time of
    /// the sixteen- and eight-lane kernels over the same 1600-pixel rows, one deeper layer,
    /// interleaved (`cargo test --release -p parallax-screen --lib trigger_avx512 --
    /// --ignored --nocapture`): valgrind cannot run AVX-512, so this is how the notes
    /// compare the two.
    #[test]
    #[ignore]
    fn print_kernel_times() {
        if !(available() && std::arch::is_x86_feature_detected!("avx2")) {
            return;
        }
        use parallax_core::cpu_time::{ms_between, thread_cpu_ns};
        let mut rng = Rng(7);
        let (w, rows) = (1600usize, 32u32);
        let cases: Vec<_> = (0..rows)
            .map(|j| (j, random_row(&mut rng, w, j, rows, 1)))
            .collect();
        let mut tz = vec![MaybeUninit::new(0.0f32); w];
        let mut fronts = vec![MaybeUninit::new(0.0f32); w];
        let mut listed = Vec::with_capacity(w);
        let (mut t16, mut t8) = (Vec::new(), Vec::new());
        for _ in 0..15 {
            for sixteen in [true, false] {
                let c = thread_cpu_ns();
                for _ in 0..20 {
                    for (j, (nodes, deeper, xe, xc, y)) in &cases {
                        listed.clear();
                        let k0 = *j as usize * w;
                        // SAFETY: AVX-512 and AVX2 + F16C (checked above).
                        unsafe {
                            if sixteen {
                                pixel_triggers_row16(
                                    &mut tz,
                                    &mut fronts,
                                    nodes,
                                    k0,
                                    xe,
                                    xc,
                                    *y,
                                    (1600.0, 900.0),
                                    deeper,
                                    &mut listed,
                                );
                            } else {
                                pixel_triggers_row8(
                                    &mut tz,
                                    &mut fronts,
                                    nodes,
                                    k0,
                                    xe,
                                    xc,
                                    *y,
                                    (1600.0, 900.0),
                                    deeper,
                                    &mut listed,
                                );
                            }
                        }
                    }
                }
                let ms = ms_between(c, thread_cpu_ns());
                if sixteen { t16.push(ms) } else { t8.push(ms) }
            }
        }
        let per_px = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2] * 1e6 / (20.0 * rows as f64 * w as f64)
        };
        let (a, b) = (per_px(&mut t16), per_px(&mut t8));
        eprintln!(
            "median ns per pixel: 16 lanes {a:.3}, 8 lanes {b:.3}, ratio {:.3}",
            a / b
        );
    }
}
