//! The pixel planes' cascade trigger depths ([`super::cascade`], `pixel_trigger`) of a row,
//! eight pixels per step in AVX2 lanes, one pixel per lane (run-time detection): the
//! fast path of `fixpoint::pixel_triggers_row`, `trigger_lanes::pixel_triggers4` with
//! eight lanes. Every lane does that kernel's operations in its order (its module docs list
//! them: the own leaf's plane decoded as `decode_plane_at` at level 0, per deeper layer the
//! covered and edge-on lanes, per footprint corner the deeper plane's `z`, the running
//! minimum by the same compare-select, the own plane's signed distance against
//! `-SAFE_MARGIN`, the trigger depth `max(front - margin, +0)` of unsafe lanes): IEEE
//! products, sums and divisions are correctly rounded per lane, `maxps` picks the same
//! operand in 8 lanes as in 4, nothing is fused (no FMA is enabled), so the trigger depths
//! are the same bits. The f16 slopes are decoded eight lanes at a time by F16C's
//! `vcvtph2ps`, which equals `f16x4` (and `node::f16_bits_to_f32`) for every finite half,
//! subnormals included; plane nodes hold only finite halves (the slopes are clamped to
//! `±65504` before encoding), and lanes whose leaf is not a plane (whose `b` word is no
//! pair of halves) are masked out of the safety test and do not enter the deeper front. The
//! deeper layers' normals are transposed from their `Vec3`s eight at a time (`soa8`). The
//! test below compares rows with the four-lane kernel.
//!
//! **The bounded step.** Per deeper layer the definition divides four numerators `N_c = (cj -
//! nx x_c) - ny y_c` by `nz` (`< -1e-6` in live lanes) and tests every corner. Where a group of
//! eight allows it, one division does: IEEE rounding is monotone (`a <= b` implies `rnd(a op y)
//! <= rnd(b op y)` for `+`, `-`, and for `*`, `/` by a positive operand, reversed by a negative
//! one), so `N_c <= N_max = max_c N_c` gives `z_c = N_c / nz >= N_max / nz = z_min` at every
//! corner, and `z_min` is the smallest corner `z`. The definition's running minimum (a strict
//! `<` compare-select, NaN never enters) then ends at `z_min`'s value, with `z_min`'s bits
//! wherever equal values have equal bits: every value but zero, so lanes whose `z_min` is `±0`
//! (whose corners may hold both zeros, the first one kept) take the exact step, as do lanes
//! with a NaN numerator (`maxps` would drop it). A non-zero non-NaN `z_min` also means `nz` is
//! finite (`N / ±inf` is `±0` or NaN), so then no `z_c` is NaN, as the definition's NaN test
//! finds. The safety test: the own plane's `pnz` is `-2^k < 0`, so `pnz z_c <= pnz z_min`, and
//! `f_c = (q_c + pnz z_c) - pc <= (q_max + pnz z_min) - pc = g` with `q_max` the largest of the
//! four `q_c`. In a plane lane the four `q_c` are finite, so `maxps` finds their largest: the
//! halves are finite, so `gx`, `gy` and `m = max(|gx|, |gy|, 1)` are, the scale `sc` is the
//! power of two with `m sc` in `[1, 2)` (so `|pnx|, |pny| < 2`) and the corners lie in `[0,
//! 1]`; `g <= -margin` (an ordered compare: false for NaN) proves every corner safe, as the
//! definition's `f_c <= -margin` would find. Lanes whose own leaf is not a plane are bad
//! whatever the corners say, so they need no bound. A group takes the bounded step when every
//! live lane has ordered numerators, a non-zero non-NaN `z_min` and (a plane) `g <= -margin`;
//! otherwise the group's four exact divisions and corner tests (the test below asserts that
//! rows take both steps).

use core::arch::x86_64::*;
use core::mem::MaybeUninit;

use glam::Vec3;

use super::cascade::SAFE_MARGIN;
use super::node::Node;
use crate::LayerPlanes;

/// Per-thread counts of the deeper layers' groups of eight that took the bounded step and
/// the exact one (module docs), for the tests to check that both are exercised.
#[cfg(test)]
pub(super) mod tally {
    use std::cell::Cell;
    thread_local! {
        pub(crate) static BOUNDED: Cell<usize> = const { Cell::new(0) };
        pub(crate) static EXACT: Cell<usize> = const { Cell::new(0) };
    }
}

/// Eight `Vec3`s at `p` as `(x, y, z)` lanes, pixels `0..4` in the low halves: the
/// 128-bit rows `v0 = x0 y0 z0 x1`, `v1 = y1 z1 x2 y2`, `v2 = z2 x3 y3 z3` of the first four
/// and the same of the last four are loaded as the two halves of three 256-bit registers
/// and transposed together (six blends, three shuffles).
///
/// # Safety
/// `p` must point to eight readable `Vec3`s (24 `f32`s).
#[inline]
#[target_feature(enable = "avx2")]
unsafe fn soa8(p: *const Vec3) -> (__m256, __m256, __m256) {
    let p = p as *const f32;
    // SAFETY: 24 readable floats (the caller's contract).
    let (v0, v1, v2) = unsafe {
        (
            _mm256_loadu2_m128(p.add(12), p),
            _mm256_loadu2_m128(p.add(16), p.add(4)),
            _mm256_loadu2_m128(p.add(20), p.add(8)),
        )
    };
    let t = _mm256_blend_ps::<0b0010_0010>(_mm256_blend_ps::<0b0100_0100>(v0, v1), v2);
    let x = _mm256_shuffle_ps::<0b01_10_11_00>(t, t);
    let t = _mm256_blend_ps::<0b0100_0100>(_mm256_blend_ps::<0b0010_0010>(v1, v0), v2);
    let y = _mm256_shuffle_ps::<0b10_11_00_01>(t, t);
    let t = _mm256_blend_ps::<0b0010_0010>(_mm256_blend_ps::<0b0100_0100>(v2, v0), v1);
    let z = _mm256_shuffle_ps::<0b11_00_01_10>(t, t);
    (x, y, z)
}

/// The trigger depths of the first `8 floor(W / 8)` pixels of row `j` into `tz` (`W =
/// tz.len()`; the kernel only writes `tz` and `fronts`, so they may be uninitialised), from the row's leaves `nodes`, the footprint edges `xe` (`i / W`, `W + 1`
/// values), the pixel centres `xc`, the row's edges and centre `y = (y0, y1, yc)`, pixel
/// `k0 + i` of the deeper layers; pushes the pixels (`k0 + i`) with a finite trigger depth
/// on `listed`; writes the pixels' deeper fronts (`cascade::deeper_front`, as
/// `trigger_lanes::pixel_triggers4` computes them) into `fronts`; returns how many pixels it
/// did.
///
/// # Safety
/// The CPU must have AVX2 and F16C.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2,f16c")]
pub(super) unsafe fn pixel_triggers_row8(
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
    // One deeper layer (the fixed point's case) in its own copy: a known trip count.
    // SAFETY: the same CPU features; the caller's contract.
    unsafe {
        if deeper.len() == 1 {
            row8::<true>(
                tz,
                fronts,
                nodes,
                k0,
                xe,
                xc,
                (y0, y1, yc),
                (wf, hf),
                deeper,
                listed,
            )
        } else {
            row8::<false>(
                tz,
                fronts,
                nodes,
                k0,
                xe,
                xc,
                (y0, y1, yc),
                (wf, hf),
                deeper,
                listed,
            )
        }
    }
}

/// [`pixel_triggers_row8`], for exactly one deeper layer if `ONE`.
///
/// # Safety
/// The CPU must have AVX2 and F16C.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2,f16c")]
unsafe fn row8<const ONE: bool>(
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
    let n8 = w & !7;
    assert!(nodes.len() >= n8 && xe.len() > n8 && xc.len() >= n8 && fronts.len() >= n8);
    assert!(
        deeper
            .iter()
            .all(|pj| pj.normal.len() >= k0 + n8 && pj.offset.len() >= k0 + n8)
    );
    let s = _mm256_set1_ps;
    let mut halves = _mm256_setr_epi8(
        0, 1, 4, 5, 8, 9, 12, 13, 2, 3, 6, 7, 10, 11, 14, 15, 0, 1, 4, 5, 8, 9, 12, 13, 2, 3, 6, 7,
        10, 11, 14, 15,
    );
    let mut order = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    // Both controls opaque to the compiler (an empty `asm!` that may change them), so that
    // the byte shuffle and the word permute stay two instructions: with constants LLVM
    // rewrites the chain of shuffles into a dozen.
    // SAFETY: the empty template changes nothing.
    unsafe {
        core::arch::asm!(
            "/* {h} {o} */",
            h = inout(ymm_reg) halves,
            o = inout(ymm_reg) order,
            options(pure, nomem, nostack, preserves_flags)
        );
    }
    let neg0 = s(-0.0);
    let (sy0, sy1, syc) = (s(y0), s(y1), s(yc));
    let margin = s(-SAFE_MARGIN);
    let mut i = 0;
    while i < n8 {
        let k = k0 + i;
        // SAFETY: `i + 8 <= n8` and the slices hold `n8` (`xe`: `n8 + 1`) elements
        // (asserted); `Node` is two `u32`s (`repr(C)`).
        let (l0, l1, xcv, x0, x1) = unsafe {
            let np = nodes.as_ptr().add(i) as *const f32;
            (
                _mm256_loadu_ps(np),
                _mm256_loadu_ps(np.add(8)),
                _mm256_loadu_ps(xc.as_ptr().add(i)),
                _mm256_loadu_ps(xe.as_ptr().add(i)),
                _mm256_loadu_ps(xe.as_ptr().add(i + 1)),
            )
        };
        // The own planes (`decode_plane_at`, level 0). The nodes' words `a b` of pixels
        // `0..4` in `l0` and `4..8` in `l1`: the in-lane shuffles take the `a` (`b`) words
        // in the lane order `0 1 4 5 | 2 3 6 7`, a 64-bit permute puts `a` in pixel order.
        let a = _mm256_castpd_si256(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(
            _mm256_shuffle_ps::<0b10_00_10_00>(l0, l1),
        )));
        let b = _mm256_castps_si256(_mm256_shuffle_ps::<0b11_01_11_01>(l0, l1));
        // The f16 slopes, eight lanes at a time by F16C (the same values as `f16x4` for
        // every finite half, module docs): per node, `b`'s low half is `gx`, its high half
        // `gy`; the byte shuffle puts each lane's `gx` halves in its low eight bytes and its
        // `gy` halves in the high eight (32-bit words `gx0gx1 gx4gx5 gy0gy1 gy4gy5 |
        // gx2gx3 gx6gx7 gy2gy3 gy6gy7`), the word permute the eight `gx` in pixel order in
        // the low 128 bits and the eight `gy` in the high 128.
        let t = _mm256_permutevar8x32_epi32(_mm256_shuffle_epi8(b, halves), order);
        let gx = _mm256_mul_ps(_mm256_cvtph_ps(_mm256_castsi256_si128(t)), s(wf));
        let gy = _mm256_mul_ps(_mm256_cvtph_ps(_mm256_extracti128_si256::<1>(t)), s(hf));
        let m = _mm256_max_ps(_mm256_andnot_ps(neg0, gx), _mm256_andnot_ps(neg0, gy));
        let m = _mm256_max_ps(m, s(1.0));
        let e = _mm256_and_si256(_mm256_castps_si256(m), _mm256_set1_epi32(0x7f80_0000));
        let sc = _mm256_castsi256_ps(_mm256_sub_epi32(_mm256_set1_epi32(0x7f00_0000), e));
        let (pnx, pny, pnz) = (
            _mm256_mul_ps(gx, sc),
            _mm256_mul_ps(gy, sc),
            _mm256_xor_ps(neg0, sc),
        );
        let zc = _mm256_castsi256_ps(_mm256_and_si256(a, _mm256_set1_epi32(0x7fff_fffc)));
        let pc = _mm256_add_ps(
            _mm256_add_ps(_mm256_mul_ps(pnx, xcv), _mm256_mul_ps(pny, syc)),
            _mm256_mul_ps(pnz, zc),
        );
        let plane = _mm256_castsi256_ps(_mm256_srai_epi32::<31>(a));
        // The deeper layers (`trigger_lanes::triggers4`), the four footprint corners
        // `(x0, y0), (x1, y0), (x0, y1), (x1, y1)` in that order. The products and
        // differences two corners share are computed once (the same operations on the
        // same operands, so the same bits), and the own plane's `pnx x + pny y` of each
        // corner once for all deeper layers.
        let (px0, px1) = (_mm256_mul_ps(pnx, x0), _mm256_mul_ps(pnx, x1));
        let (py0, py1) = (_mm256_mul_ps(pny, sy0), _mm256_mul_ps(pny, sy1));
        let q = [
            _mm256_add_ps(px0, py0),
            _mm256_add_ps(px1, py0),
            _mm256_add_ps(px0, py1),
            _mm256_add_ps(px1, py1),
        ];
        // The largest of the own plane's corner terms, for the bounded step (finite in
        // plane lanes, module docs).
        let qmax = _mm256_max_ps(_mm256_max_ps(q[0], q[1]), _mm256_max_ps(q[2], q[3]));
        let mut front = s(f32::INFINITY);
        let mut bad = _mm256_setzero_ps();
        // Lanes with an edge-on deeper plane or a NaN corner `z`: deeper front `-inf`.
        let mut void = _mm256_setzero_ps();
        // Lanes where the own plane is not a plane: every live lane is unsafe.
        let not_plane = _mm256_xor_ps(plane, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
        for pj in if ONE { &deeper[..1] } else { deeper } {
            // SAFETY: pixels `k .. k + 8` of the deeper layer exist (asserted).
            let ((nx, ny, nz), cj) = unsafe {
                (
                    soa8(pj.normal.as_ptr().add(k)),
                    _mm256_loadu_ps(pj.offset.as_ptr().add(k)),
                )
            };
            let z0 = _mm256_setzero_ps();
            let covered = _mm256_or_ps(
                _mm256_or_ps(
                    _mm256_cmp_ps::<_CMP_NEQ_UQ>(nx, z0),
                    _mm256_cmp_ps::<_CMP_NEQ_UQ>(ny, z0),
                ),
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(nz, z0),
            );
            let edge = _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_LT_OS>(nz, s(-1e-6)), covered);
            bad = _mm256_or_ps(bad, edge);
            void = _mm256_or_ps(void, edge);
            front = _mm256_blendv_ps(front, z0, edge);
            let live = _mm256_andnot_ps(edge, covered);
            if _mm256_movemask_ps(live) == 0 {
                continue;
            }
            // The numerators `cj - nx x - ny y` per corner, left to right.
            let (c0, c1) = (
                _mm256_sub_ps(cj, _mm256_mul_ps(nx, x0)),
                _mm256_sub_ps(cj, _mm256_mul_ps(nx, x1)),
            );
            let (ny0, ny1) = (_mm256_mul_ps(ny, sy0), _mm256_mul_ps(ny, sy1));
            let num = [
                _mm256_sub_ps(c0, ny0),
                _mm256_sub_ps(c1, ny0),
                _mm256_sub_ps(c0, ny1),
                _mm256_sub_ps(c1, ny1),
            ];
            // The bounded step (module docs): the corners' smallest `z` by one division,
            // that of the largest numerator, and the safety test bounded from it.
            let nmax = _mm256_max_ps(_mm256_max_ps(num[0], num[1]), _mm256_max_ps(num[2], num[3]));
            let zmin = _mm256_div_ps(nmax, nz);
            let ordered = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_ORD_Q>(num[0], num[1]),
                _mm256_cmp_ps::<_CMP_ORD_Q>(num[2], num[3]),
            );
            let nonzero = _mm256_cmp_ps::<_CMP_NEQ_OQ>(zmin, z0);
            let g = _mm256_sub_ps(_mm256_add_ps(qmax, _mm256_mul_ps(pnz, zmin)), pc);
            let safe = _mm256_cmp_ps::<_CMP_LE_OQ>(g, margin);
            let ok = _mm256_and_ps(
                _mm256_and_ps(ordered, nonzero),
                _mm256_or_ps(safe, not_plane),
            );
            if _mm256_movemask_ps(_mm256_andnot_ps(ok, live)) == 0 {
                #[cfg(test)]
                tally::BOUNDED.with(|c| c.set(c.get() + 1));
                let lower = _mm256_and_ps(live, _mm256_cmp_ps::<_CMP_LT_OS>(zmin, front));
                front = _mm256_blendv_ps(front, zmin, lower);
                bad = _mm256_or_ps(bad, _mm256_and_ps(live, not_plane));
                continue;
            }
            #[cfg(test)]
            tally::EXACT.with(|c| c.set(c.get() + 1));
            // The exact step: `z = (cj - nx x - ny y) / nz` per corner.
            let z = [
                _mm256_div_ps(num[0], nz),
                _mm256_div_ps(num[1], nz),
                _mm256_div_ps(num[2], nz),
                _mm256_div_ps(num[3], nz),
            ];
            // A NaN at any corner (`unord` of two operands: either is NaN).
            let nan = _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_UNORD_Q>(z[0], z[1]),
                _mm256_cmp_ps::<_CMP_UNORD_Q>(z[2], z[3]),
            );
            void = _mm256_or_ps(void, _mm256_and_ps(live, nan));
            // A corner is unsafe where `f <= -margin` fails (NaN included); a live lane is
            // bad where its own leaf is no plane or some corner is unsafe: `live & !(le &
            // plane)` ORed over the corners.
            let mut unsafe_any = not_plane;
            for c in 0..4 {
                let lower = _mm256_and_ps(live, _mm256_cmp_ps::<_CMP_LT_OS>(z[c], front));
                front = _mm256_blendv_ps(front, z[c], lower);
                let f = _mm256_sub_ps(_mm256_add_ps(q[c], _mm256_mul_ps(pnz, z[c])), pc);
                unsafe_any = _mm256_or_ps(unsafe_any, _mm256_cmp_ps::<_CMP_NLE_UQ>(f, margin));
            }
            bad = _mm256_or_ps(bad, _mm256_and_ps(live, unsafe_any));
        }
        let t = _mm256_sub_ps(front, s(SAFE_MARGIN));
        let t = _mm256_and_ps(_mm256_cmp_ps::<_CMP_GT_OS>(t, _mm256_setzero_ps()), t);
        // `bad` is a full-lane mask (compares and their ANDs / ORs): select by bitwise
        // operations, which LLVM keeps as they are (a `blendv` made it narrow the mask to
        // 16-bit lanes and widen it back).
        let t = _mm256_or_ps(
            _mm256_and_ps(bad, t),
            _mm256_andnot_ps(bad, s(f32::INFINITY)),
        );
        // SAFETY: `tz[i..i + 8]` and `fronts[i..i + 8]` are in bounds (`i + 8 <= n8 <= W`,
        // asserted).
        unsafe {
            _mm256_storeu_ps(tz.as_mut_ptr().add(i) as *mut f32, t);
            _mm256_storeu_ps(
                fronts.as_mut_ptr().add(i) as *mut f32,
                _mm256_blendv_ps(front, s(f32::NEG_INFINITY), void),
            );
        }
        // The finite ones: `|t| < inf`.
        let fin = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LT_OQ>(
            _mm256_andnot_ps(neg0, t),
            s(f32::INFINITY),
        ));
        let mut bits = fin as u32;
        while bits != 0 {
            let d = bits.trailing_zeros() as usize;
            listed.push((k + d) as u32);
            bits &= bits - 1;
        }
        i += 8;
    }
    n8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::test_rng::Rng;
    use crate::quadtree::trigger_lanes::pixel_triggers4;

    /// Whether this CPU runs the kernels under test (says so when it does not).
    fn avx2_f16c() -> bool {
        let ok = std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("f16c");
        if !ok {
            eprintln!("no AVX2 and F16C: nothing to compare");
        }
        ok
    }

    /// F16C's conversion equals `f16_bits_to_f32` (and `f16x4`) for every finite half.
    #[test]
    fn f16c_decodes_every_finite_half_as_the_definition() {
        if !avx2_f16c() {
            return;
        }
        #[target_feature(enable = "avx2,f16c")]
        fn cvt8(h: [u16; 8]) -> [f32; 8] {
            // SAFETY: reads and writes eight-element arrays.
            unsafe {
                let mut out = [0.0f32; 8];
                let v = _mm_loadu_si128(h.as_ptr() as *const __m128i);
                _mm256_storeu_ps(out.as_mut_ptr(), _mm256_cvtph_ps(v));
                out
            }
        }
        for h0 in (0..=u16::MAX).step_by(8) {
            let h: [u16; 8] = core::array::from_fn(|d| h0 + d as u16);
            // SAFETY: the CPU has AVX2 and F16C (checked).
            let got = unsafe { cvt8(h) };
            for d in 0..8 {
                if h[d] & 0x7c00 != 0x7c00 {
                    let want = crate::quadtree::node::f16_bits_to_f32(h[d]);
                    assert_eq!(got[d].to_bits(), want.to_bits(), "{:#x}", h[d]);
                }
            }
        }
    }

    /// Rows of the eight-lane kernel equal the four-lane kernel (`trigger_lanes`) bit for
    /// bit, and list the same pixels: random own leaves (planes, empty, AABB, flagged) over
    /// one or two deeper layers with covered, uncovered and edge-on pixels and planes in
    /// front of and behind the own ones.
    #[test]
    fn rows_equal_the_four_lane_rows() {
        if !avx2_f16c() {
            return;
        }
        let mut rng = Rng(0x0bad_cafe_dead_beef);
        let tally0 = (
            tally::BOUNDED.with(|c| c.get()),
            tally::EXACT.with(|c| c.get()),
        );
        let (wf, hf) = (1600.0f32, 900.0f32);
        let (mut finite, mut total) = (0usize, 0usize);
        for case in 0..64u32 {
            let w = 8 * (1 + case as usize % 9) + (case as usize % 8);
            let (j, rows) = (case % 3, 3u32);
            let k0 = j as usize * w;
            // Half the cases coherent: own planes of moderate slopes and deeper planes
            // mostly far behind them, so that whole groups of eight are provably safe.
            let coherent = case % 4 >= 2;
            let nodes: Vec<Node> = (0..w)
                .map(|_| match rng.next() % 8 {
                    2 if coherent => Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        rng.f(-3.0, 3.0),
                        rng.f(-3.0, 3.0),
                        0,
                        wf,
                        hf,
                        0,
                    )
                    .unwrap_or(Node::EMPTY),
                    0 => Node::EMPTY,
                    1 => Node::aabb(rng.f(0.0, 0.5), rng.f(0.5, 1.0)),
                    // Slopes clamped to the f16 maximum, subnormal halves, ordinary ones.
                    2 => Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        rng.f(-1e9, 1e9),
                        rng.f(-5e-2, 5e-2),
                        0,
                        wf,
                        hf,
                        (rng.next() % 2) as u32,
                    )
                    .unwrap_or(Node::EMPTY),
                    _ => Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        rng.f(-3.0, 3.0),
                        rng.f(-3.0, 3.0),
                        0,
                        wf,
                        hf,
                        (rng.next() % 2) as u32,
                    )
                    .unwrap_or(Node::EMPTY),
                })
                .collect();
            let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
            let deeper: Vec<LayerPlanes> = (0..1 + case % 2)
                .map(|_| {
                    let n = w * rows as usize;
                    // Some planes through `z = 0` at the footprint's left corners (`cj =
                    // nx x0`, `ny = 0`: zero numerators there), for the exact step's zero
                    // guard; some far behind or in front, for the bounded step.
                    let (normal, offset): (Vec<Vec3>, Vec<f32>) = (0..n)
                        .map(|p| match rng.next() % 10 {
                            _ if coherent && !rng.next().is_multiple_of(16) => {
                                let nv = Vec3::new(rng.f(-0.5, 0.5), rng.f(-0.5, 0.5), -1.0);
                                (nv.normalize(), rng.f(-8.0, -2.0))
                            }
                            0 => (Vec3::ZERO, rng.f(-1.2, 0.2)),
                            1 => (Vec3::new(1.0, 0.0, 0.0), rng.f(-1.2, 0.2)),
                            2 => (Vec3::new(0.6, 0.8, -1e-7), rng.f(-1.2, 0.2)),
                            3 => {
                                let nv = Vec3::new(rng.f(-0.5, 0.5), 0.0, -1.0).normalize();
                                (nv, nv.x * xe[p % w])
                            }
                            4 => {
                                let nv = Vec3::new(rng.f(-0.5, 0.5), rng.f(-0.5, 0.5), -1.0);
                                (nv.normalize(), rng.f(-8.0, 8.0))
                            }
                            _ => {
                                let nv = Vec3::new(rng.f(-0.5, 0.5), rng.f(-0.5, 0.5), -1.0);
                                (nv.normalize(), rng.f(-1.2, 0.2))
                            }
                        })
                        .unzip();
                    LayerPlanes {
                        width: w as u32,
                        height: rows,
                        normal,
                        offset,
                        flag: vec![false; n],
                    }
                })
                .collect();
            let xc: Vec<f32> = (0..w).map(|i| ((i as f32 + 0.5) * 1.0) / wf).collect();
            let y = (
                (j as f32) / hf,
                ((j + 1) as f32) / hf,
                ((j as f32 + 0.5) * 1.0) / hf,
            );
            let mut tz = vec![MaybeUninit::new(0.0f32); w];
            let mut fronts = vec![MaybeUninit::new(0.0f32); w];
            let mut listed = Vec::new();
            // SAFETY: AVX2 (checked above).
            let n = unsafe {
                pixel_triggers_row8(
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
            assert_eq!(n, w & !7);
            // SAFETY: initialised above (and written by the kernel).
            let (tz, fronts): (Vec<f32>, Vec<f32>) = unsafe {
                (
                    tz.iter().map(|v| v.assume_init()).collect(),
                    fronts.iter().map(|v| v.assume_init()).collect(),
                )
            };
            let mut want = Vec::new();
            for i in (0..n).step_by(4) {
                let (t, f) = pixel_triggers4(
                    k0 + i,
                    &nodes[i..],
                    &xe[i..],
                    &xc[i..],
                    y,
                    (wf, hf),
                    &deeper,
                );
                let (t, f) = (t.to_array(), f.to_array());
                for d in 0..4 {
                    assert_eq!(
                        fronts[i + d].to_bits(),
                        f[d].to_bits(),
                        "case {case} pixel {} (deeper front)",
                        i + d
                    );
                    let def = crate::quadtree::cascade::deeper_front(
                        k0 + i + d,
                        (xe[i + d], xe[i + d + 1], y.0, y.1),
                        &deeper,
                    );
                    assert_eq!(f[d].to_bits(), def.to_bits(), "case {case} pixel {}", i + d);
                    assert_eq!(
                        tz[i + d].to_bits(),
                        t[d].to_bits(),
                        "case {case} pixel {}",
                        i + d
                    );
                    if t[d].is_finite() {
                        want.push((k0 + i + d) as u32);
                    }
                }
            }
            assert_eq!(listed, want, "case {case}");
            finite += want.len();
            total += n;
        }
        assert!(
            finite > total / 10 && finite < total,
            "{finite} of {total} finite"
        );
        // Both steps ran, each on a fair share of the groups.
        let bounded = tally::BOUNDED.with(|c| c.get()) - tally0.0;
        let exact = tally::EXACT.with(|c| c.get()) - tally0.1;
        assert!(
            bounded > (bounded + exact) / 10 && exact > (bounded + exact) / 10,
            "{bounded} bounded and {exact} exact steps"
        );
    }
}
