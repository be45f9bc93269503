//! The merged runs' pair certificate of `fixpoint::merged_triggers` (Widmer et al. 2015,
//! §3.3, the cascade of [`super::cascade`]) for eight neighbouring nodes of one level at
//! once, in AVX2 lanes (run-time detection; the scalar certificate in `merged_triggers` is
//! the path without AVX2 and the definition the test below compares with).
//!
//! Per merged node `(L, qx, qy)` and pair of rows, `merged_triggers` decodes the node's plane
//! ([`decode_plane`]), takes the threshold [`proxy_safe_front`] over the node's columns and
//! the pair's rows, and certifies the run when every deeper front of both rows reaches it.
//! Here eight nodes `qx0 .. qx0 + 8` of level `L` (1 to 3: runs of 2 to 8 pixels, a chunk
//! of `8 << L` pixels per row) do that in lanes, each lane the scalar operations in their
//! order, so every threshold and answer is the same:
//!
//! - the decode at level `L` as [`super::node::Node::test_normal`] and [`decode_plane`]: the
//!   f16 increments by F16C's `vcvtph2ps` (equal to `f16_bits_to_f32` for every finite half,
//!   `trigger_avx2`'s test; a plane node's halves are finite), times `W 2^-L`, `H 2^-L`
//!   (exact exponent shifts, as `gradient`), the scale `2^-e` from `max(|gx|, |gy|, 1)` by
//!   `maxps` (the definition's compare-selects), `c = (n.x x_c + n.y y_c) + n.z z_c` with the
//!   centres of `node_centre` (tabulated per column with its expression);
//! - the threshold in f64 lanes, `proxy_safe_front`'s operations: `maxpd` for `f64::max`
//!   (the products are finite, so only the sign of a zero could differ, and a zero `m` or
//!   `max(t, 0)` is then added to a positive term: the same sum), `vcvtpd2ps` for `as f32`
//!   (round to nearest even), `+inf` where `n.z` is not negative or `t` is not finite;
//! - the fronts compared by `>=` (ordered: a NaN front fails, as in `certified`).
//!
//! Lanes whose node is not a plane compute garbage that the caller ignores (it asks only
//! about runs of level `L`, whose nodes are planes).
//!
//! The scan of `merged_triggers` then goes by windows of 64 pixels of the pair
//! ([`uncertified64`]): the window's effective levels compared bytewise give the pixels under
//! merged nodes and those of each level 1 to 3; each chunk holding a run of a level is
//! certified in lanes, a run counts as certified where all its pixels' bits are (ANDs of
//! shifted bits per node), and the scan visits only the rest, one `trailing_zeros` per run:
//! the runs of levels 1 to 3 whose certificate fails (done as before: the scalar
//! certificate, then `merged_run`) and the runs of higher levels. The certified runs are
//! skipped as the scalar scan skips them, so the trigger depths are the same.

use core::arch::x86_64::*;

use super::node::Node;
use super::tree::Level;

/// The highest level whose runs are certified in lanes (a chunk of `8 << L` pixels fits
/// the returned `u64`).
pub(super) const MAX_LEVEL: u32 = 3;

/// Per level `1..=MAX_LEVEL` (index `L - 1`), the columns' node edges `x = (q 2^L) / W` (the
/// values of `Columns::xe` at the node boundaries, clipped to `W`) and the node centres of
/// `node_centre`'s expression.
pub(super) struct LevelCols {
    pub(super) edge: Vec<Vec<f32>>,
    pub(super) centre: Vec<Vec<f32>>,
}

impl LevelCols {
    /// The tables of a `W`-pixel row (`xe`: `W + 1` edges `i / W`).
    pub(super) fn new(xe: &[f32], wf: f32, hf: f32) -> Self {
        let w = xe.len() - 1;
        let (mut edge, mut centre) = (Vec::new(), Vec::new());
        for l in 1..=MAX_LEVEL {
            let n = w.div_ceil(1 << l);
            edge.push((0..=n).map(|q| xe[(q << l).min(w)]).collect());
            centre.push(
                (0..n)
                    .map(|q| super::node::node_centre(l, q as u32, 0, wf, hf).0)
                    .collect(),
            );
        }
        Self { edge, centre }
    }
}

/// Whether the CPU runs [`certify8`].
pub(super) fn available() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("f16c")
}

/// The pair certificate of the eight level-`L` nodes at `nodes` (columns `qx0 .. qx0 +
/// 8` of one row of level `L`, plane nodes where the caller asks): `edge[..9]` their column
/// edges, `centre[..8]` their centres' `x`, `yc` their row's centre `y`, `y_pair` the pair's
/// top and bottom edge, `fr0`, `fr1` the two rows' deeper fronts from the chunk's first
/// pixel (`8 << L` each). Bit `p` of the result is set where pixel `p`'s fronts in both
/// rows reach its node's threshold (`proxy_safe_front` of its decoded plane over the node's
/// columns and `y_pair`); a run is certified where all its bits are.
///
/// # Safety
/// The CPU must have AVX2 and F16C; `1 <= L <= MAX_LEVEL`; the pointers must point to
/// that many readable values.
#[allow(clippy::too_many_arguments)]
#[target_feature(enable = "avx2,f16c")]
pub(super) unsafe fn certify8<const L: u32>(
    nodes: *const Node,
    edge: *const f32,
    centre: *const f32,
    yc: f32,
    (y_lo, y_hi): (f32, f32),
    (wf, hf): (f32, f32),
    fr0: *const f32,
    fr1: *const f32,
) -> u64 {
    let px = 8usize << L;
    let s = _mm256_set1_ps;
    // SAFETY: eight nodes (two `u32` words each, `repr(C)`), nine edges, eight centres
    // (the caller's contract).
    let (l0, l1, xlo, xhi, xc) = unsafe {
        let np = nodes as *const f32;
        (
            _mm256_loadu_ps(np),
            _mm256_loadu_ps(np.add(8)),
            _mm256_loadu_ps(edge),
            _mm256_loadu_ps(edge.add(1)),
            _mm256_loadu_ps(centre),
        )
    };
    // The words `a` and `b` in node order (as `trigger_avx2`'s decode).
    let a = _mm256_castpd_si256(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(
        _mm256_shuffle_ps::<0b10_00_10_00>(l0, l1),
    )));
    let b = _mm256_castpd_si256(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_castps_pd(
        _mm256_shuffle_ps::<0b11_01_11_01>(l0, l1),
    )));
    // The increments: `b`'s low half (`dz_x`) and high half (`dz_y`) of each node.
    let lo16 = _mm256_set1_epi32(0xffff);
    let hx = _mm256_and_si256(b, lo16);
    let hy = _mm256_srli_epi32::<16>(b);
    // Sixteen-bit halves packed in node order (`packus` of values < 2^16 is exact; the
    // in-lane pack interleaves the 128-bit halves, the 64-bit permute restores the order).
    let h = _mm256_permute4x64_epi64::<0b11_01_10_00>(_mm256_packus_epi32(hx, hy));
    let ex = _mm256_cvtph_ps(_mm256_castsi256_si128(h));
    let ey = _mm256_cvtph_ps(_mm256_extracti128_si256::<1>(h));
    // `W 2^-L`, `H 2^-L` (exponent shifts, as `Node::gradient`).
    let ws = f32::from_bits(wf.to_bits() - (L << 23));
    let hs = f32::from_bits(hf.to_bits() - (L << 23));
    let gx = _mm256_mul_ps(ex, s(ws));
    let gy = _mm256_mul_ps(ey, s(hs));
    let neg0 = s(-0.0);
    let m = _mm256_max_ps(_mm256_andnot_ps(neg0, gx), _mm256_andnot_ps(neg0, gy));
    let m = _mm256_max_ps(m, s(1.0));
    let e = _mm256_and_si256(_mm256_castps_si256(m), _mm256_set1_epi32(0x7f80_0000));
    let sc = _mm256_castsi256_ps(_mm256_sub_epi32(_mm256_set1_epi32(0x7f00_0000), e));
    let (nx, ny, nz) = (
        _mm256_mul_ps(gx, sc),
        _mm256_mul_ps(gy, sc),
        _mm256_xor_ps(neg0, sc),
    );
    let zc = _mm256_castsi256_ps(_mm256_and_si256(a, _mm256_set1_epi32(0x7fff_fffc)));
    let c = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(nx, xc), _mm256_mul_ps(ny, s(yc))),
        _mm256_mul_ps(nz, zc),
    );
    // `proxy_safe_front` per half, in f64 lanes.
    let d = _mm256_set1_pd;
    const G: f64 = 1e-6;
    let (ylo, yhi) = (d(y_lo as f64), d(y_hi as f64));
    let half = |h: usize| {
        let pick = |v: __m256| {
            if h == 0 {
                _mm256_cvtps_pd(_mm256_castps256_ps128(v))
            } else {
                _mm256_cvtps_pd(_mm256_extractf128_ps::<1>(v))
            }
        };
        let (nx, ny, nz, c, xlo, xhi) =
            (pick(nx), pick(ny), pick(nz), pick(c), pick(xlo), pick(xhi));
        let m = _mm256_sub_pd(
            _mm256_add_pd(
                _mm256_max_pd(_mm256_mul_pd(nx, xlo), _mm256_mul_pd(nx, xhi)),
                _mm256_max_pd(_mm256_mul_pd(ny, ylo), _mm256_mul_pd(ny, yhi)),
            ),
            c,
        );
        let abs = |v: __m256d| _mm256_andnot_pd(d(-0.0), v);
        let a = _mm256_add_pd(_mm256_add_pd(abs(nx), abs(ny)), abs(c));
        let t = _mm256_div_pd(
            _mm256_add_pd(_mm256_add_pd(m, _mm256_mul_pd(d(G), a)), d(2e-6)),
            _mm256_mul_pd(_mm256_xor_pd(d(-0.0), nz), d(1.0 - G)),
        );
        // `+inf` unless `n.z < 0` and `t` is finite.
        let ok = _mm256_and_pd(
            _mm256_cmp_pd::<_CMP_LT_OQ>(nz, _mm256_setzero_pd()),
            _mm256_cmp_pd::<_CMP_LT_OQ>(abs(t), d(f64::INFINITY)),
        );
        let t = _mm256_add_pd(
            _mm256_mul_pd(_mm256_max_pd(t, _mm256_setzero_pd()), d(1.0 + 1e-6)),
            d(1e-30),
        );
        // Where `t` is finite the rounded-up value is finite or `+inf` (never NaN), so its
        // f32 rounding is the result, `+inf` included (`as f32` overflows to `+inf`).
        _mm256_cvtpd_ps(_mm256_blendv_pd(d(f64::INFINITY), t, ok))
    };
    let t = _mm256_set_m128(half(1), half(0));
    // Per block of eight pixels, each pixel's node threshold (node `(8 b + p) >> L`).
    let iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let shift = _mm_cvtsi32_si128(L as i32);
    let mut bits = 0u64;
    for blk in 0..px / 8 {
        let idx = _mm256_srl_epi32(
            _mm256_add_epi32(_mm256_set1_epi32(8 * blk as i32), iota),
            shift,
        );
        let tb = _mm256_permutevar8x32_ps(t, idx);
        // SAFETY: `8 blk + 8 <= px` fronts per row (the caller's contract).
        let (f0, f1) = unsafe {
            (
                _mm256_loadu_ps(fr0.add(8 * blk)),
                _mm256_loadu_ps(fr1.add(8 * blk)),
            )
        };
        let ge = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(f0, tb),
            _mm256_cmp_ps::<_CMP_GE_OQ>(f1, tb),
        );
        bits |= (_mm256_movemask_ps(ge) as u32 as u64) << (8 * blk);
    }
    bits
}

/// What [`uncertified64`] reads of one pair of rows `j`, `j + 1` (`j` even): per level `L`
/// of `1..=MAX_LEVEL` (index `L - 1`) the row `j >> L` of its nodes, its column tables and
/// its centre's `y`; the pair's `y` range; the two rows' deeper fronts. Every window of 64
/// pixels up to `end` (the row's whole windows) lies inside all of them (checked by
/// [`Self::new`]).
pub(super) struct PairRows<'a> {
    nodes: [&'a [Node]; MAX_LEVEL as usize],
    edge: [&'a [f32]; MAX_LEVEL as usize],
    centre: [&'a [f32]; MAX_LEVEL as usize],
    yc: [f32; MAX_LEVEL as usize],
    y_pair: (f32, f32),
    wh: (f32, f32),
    fr0: &'a [f32],
    fr1: &'a [f32],
    /// The end of the row's whole windows (`W` rounded down to a multiple of 64).
    pub(super) end: usize,
}

impl<'a> PairRows<'a> {
    /// The pair `j`, `j + 1` of a `W`-pixel image (`fr0`, `fr1`: its two rows' fronts, `W`
    /// each) over `levels` (at least `MAX_LEVEL + 1`; `None` otherwise).
    pub(super) fn new(
        levels: &'a [Level],
        cols: &'a LevelCols,
        j: u32,
        y_pair: (f32, f32),
        wh: (f32, f32),
        (fr0, fr1): (&'a [f32], &'a [f32]),
    ) -> Option<Self> {
        let l_max = MAX_LEVEL as usize;
        if levels.len() <= l_max {
            return None;
        }
        let end = fr0.len() & !63;
        assert!(fr1.len() >= end);
        let mut nodes = [&levels[0].nodes[..0]; MAX_LEVEL as usize];
        let mut yc = [0.0; MAX_LEVEL as usize];
        for l in 1..=MAX_LEVEL {
            let lv = &levels[l as usize];
            let (qy, k) = ((j >> l) as usize, l as usize - 1);
            nodes[k] = &lv.nodes[qy * lv.w as usize..(qy + 1) * lv.w as usize];
            yc[k] = super::node::node_centre(l, 0, qy as u32, wh.0, wh.1).1;
            let n = end >> l;
            assert!(nodes[k].len() >= n && cols.edge[k].len() > n && cols.centre[k].len() >= n);
        }
        Some(Self {
            nodes,
            edge: core::array::from_fn(|k| &cols.edge[k][..]),
            centre: core::array::from_fn(|k| &cols.centre[k][..]),
            yc,
            y_pair,
            wh,
            fr0,
            fr1,
            end,
        })
    }

    /// The certified pixels of the runs of level `L` (`m`: the window's pixels of that
    /// level) of the window from `w0`: [`certify8`] per chunk with a pixel in `m`, a run's
    /// pixels kept where all its bits are.
    ///
    /// # Safety
    /// The CPU must have AVX2 and F16C; `w0 + 64 <= self.end`, `w0` a multiple of 64;
    /// `1 <= L <= MAX_LEVEL`.
    #[inline(always)]
    unsafe fn level<const L: u32>(&self, m: u64, w0: usize) -> u64 {
        let (span, n, k) = (8usize << L, 1u32 << L, L as usize - 1);
        let cm = if span == 64 {
            u64::MAX
        } else {
            (1u64 << span) - 1
        };
        // A node's first pixel in each group of `n`.
        let first = u64::MAX / ((1u64 << n) - 1);
        let mut cert = 0u64;
        let mut c = 0;
        while c < 64 {
            if (m >> c) & cm != 0 {
                let (x, q0) = (w0 + c, (w0 + c) >> L);
                // SAFETY: the chunk lies inside the row's whole windows, which `new`
                // checked against every table; the CPU's features (the caller's contract).
                let mut b = unsafe {
                    certify8::<L>(
                        self.nodes[k].as_ptr().add(q0),
                        self.edge[k].as_ptr().add(q0),
                        self.centre[k].as_ptr().add(q0),
                        self.yc[k],
                        self.y_pair,
                        self.wh,
                        self.fr0.as_ptr().add(x),
                        self.fr1.as_ptr().add(x),
                    )
                };
                // Bit `p` set where pixels `p .. p + n` all are (one AND per halving),
                // kept at the nodes' first pixels and spread over their `n` pixels (no
                // carries: the product's terms are `n` bits apart).
                let mut s = 1;
                while s < n {
                    b &= b >> s;
                    s *= 2;
                }
                cert |= ((b & first).wrapping_mul((1u64 << n) - 1) << c) & m;
            }
            c += span;
        }
        cert
    }
}

/// The pixels of the 64-pixel window `w0 .. w0 + 64` of the pair of rows `p` that the scan
/// of `merged_triggers` still has to visit (bit `i`: pixel `w0 + i`), from the window's
/// effective levels `er` (the pair's first row; its runs of level >= 1 are the second
/// row's): every pixel under a merged node (level >= 1, not `NO_PLANE`) except those of
/// the runs of levels 1 to `MAX_LEVEL` whose pair certificate holds ([`certify8`] per chunk
/// of the window with a run of that level; a run is certified where all its pixels' bits
/// are).
///
/// # Safety
/// The CPU must have AVX2 and F16C ([`available`]); `w0` a multiple of 64 and `w0 + 64 <=
/// p.end`.
#[target_feature(enable = "avx2,f16c")]
pub(super) unsafe fn uncertified64(er: &[u8], p: &PairRows, w0: usize) -> u64 {
    assert!(er.len() >= 64 && w0.is_multiple_of(64) && w0 + 64 <= p.end);
    // SAFETY: 64 readable bytes (asserted).
    let (v0, v1) = unsafe {
        (
            _mm256_loadu_si256(er.as_ptr() as *const __m256i),
            _mm256_loadu_si256(er.as_ptr().add(32) as *const __m256i),
        )
    };
    let eq = |b: u8| {
        let b = _mm256_set1_epi8(b as i8);
        let lo = _mm256_movemask_epi8(_mm256_cmpeq_epi8(v0, b)) as u32 as u64;
        let hi = _mm256_movemask_epi8(_mm256_cmpeq_epi8(v1, b)) as u32 as u64;
        lo | (hi << 32)
    };
    let merged = !(eq(0) | eq(super::node::NO_PLANE));
    if merged == 0 {
        return 0;
    }
    let (m1, m2, m3) = (eq(1), eq(2), eq(3));
    let mut cert = 0u64;
    // SAFETY: the caller's contract (`MAX_LEVEL` is 3).
    unsafe {
        if m1 != 0 {
            cert |= p.level::<1>(m1, w0);
        }
        if m2 != 0 {
            cert |= p.level::<2>(m2, w0);
        }
        if m3 != 0 {
            cert |= p.level::<3>(m3, w0);
        }
    }
    merged & !cert
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::cascade::proxy_safe_front;
    use crate::quadtree::node::decode_plane;
    use crate::quadtree::test_rng::Rng;

    /// The definition: per node its threshold, per pixel whether both rows' fronts reach it.
    #[allow(clippy::too_many_arguments)]
    fn scalar_bits(
        l: u32,
        nodes: &[Node],
        qx0: u32,
        qy: u32,
        xe: &[f32],
        y_pair: (f32, f32),
        (wf, hf): (f32, f32),
        fr0: &[f32],
        fr1: &[f32],
    ) -> u64 {
        let mut bits = 0u64;
        for q in 0..8u32 {
            let p = decode_plane(nodes[q as usize], l, qx0 + q, qy, wf, hf);
            let (i, end) = (((qx0 + q) << l) as usize, ((qx0 + q + 1) << l) as usize);
            let t = proxy_safe_front(p, (xe[i], xe[end]), y_pair);
            for k in i..end {
                let p = k - ((qx0 as usize) << l);
                if fr0[p] >= t && fr1[p] >= t {
                    bits |= 1 << p;
                }
            }
        }
        bits
    }

    /// Random plane nodes of levels 1 to 3 (steep, flat, subnormal and clamped slopes,
    /// flagged), fronts around their thresholds (and NaN, `±inf`): the lanes' bits equal
    /// the definition's, and both answers occur.
    #[test]
    fn lanes_equal_the_scalar_certificate() {
        if !available() {
            eprintln!("no AVX2 and F16C: nothing to compare");
            return;
        }
        let mut rng = Rng(0x5eed_cafe_f00d_0001);
        let (wf, hf) = (1600.0f32, 900.0f32);
        let xe: Vec<f32> = (0..=1600).map(|i| i as f32 / wf).collect();
        let cols = LevelCols::new(&xe, wf, hf);
        let (mut set, mut total) = (0u32, 0u32);
        for case in 0..3000u32 {
            let l = 1 + case % 3;
            let chunks = 1600 / (8usize << l);
            let c = (rng.next() as usize) % chunks;
            let qx0 = (c * 8) as u32;
            let qy = (rng.next() % (900 >> l)) as u32;
            let j = (qy << l) + 2 * (rng.next() % (1 << (l - 1))) as u32;
            let y_pair = (j as f32 / hf, (j + 2) as f32 / hf);
            let yc = super::super::node::node_centre(l, 0, qy, wf, hf).1;
            let nodes: Vec<Node> = (0..8)
                .map(|_| {
                    let (gx, gy) = match rng.next() % 5 {
                        0 => (rng.f(-1e9, 1e9), rng.f(-1e9, 1e9)),
                        1 => (rng.f(-1e-4, 1e-4), rng.f(-1e-4, 1e-4)),
                        2 => (0.0, -0.0),
                        _ => (rng.f(-30.0, 30.0), rng.f(-30.0, 30.0)),
                    };
                    Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        gx,
                        gy,
                        l,
                        wf,
                        hf,
                        (rng.next() % 4) as u32,
                    )
                    .unwrap()
                })
                .collect();
            let px = 8usize << l;
            let i0 = (qx0 as usize) << l;
            let ts: Vec<f32> = (0..8u32)
                .map(|q| {
                    let p = decode_plane(nodes[q as usize], l, qx0 + q, qy, wf, hf);
                    let (i, end) = (((qx0 + q) << l) as usize, ((qx0 + q + 1) << l) as usize);
                    proxy_safe_front(p, (xe[i], xe[end]), y_pair)
                })
                .collect();
            let mut front = |p: usize| {
                let t = ts[p >> l];
                match rng.next() % 16 {
                    0 => f32::NAN,
                    1 => f32::NEG_INFINITY,
                    2 => f32::INFINITY,
                    3 => t,
                    4 => f32::from_bits(t.to_bits().wrapping_sub(1)),
                    _ if case % 2 == 0 => t + rng.f(0.0, 0.5),
                    _ => t + rng.f(-0.05, 0.5),
                }
            };
            let fr0: Vec<f32> = (0..px).map(&mut front).collect();
            let fr1: Vec<f32> = (0..px).map(&mut front).collect();
            let want = scalar_bits(l, &nodes, qx0, qy, &xe, y_pair, (wf, hf), &fr0, &fr1);
            let (e, cx) = (&cols.edge[l as usize - 1], &cols.centre[l as usize - 1]);
            let q0 = qx0 as usize;
            assert!(e.len() >= q0 + 9 && cx.len() >= q0 + 8 && nodes.len() == 8);
            let args = (
                nodes.as_ptr(),
                e[q0..].as_ptr(),
                cx[q0..].as_ptr(),
                yc,
                y_pair,
            );
            let fr = (fr0.as_ptr(), fr1.as_ptr());
            // SAFETY: the CPU has AVX2 and F16C (checked); `l` is 1 to 3; eight nodes,
            // nine edges, eight centres (asserted) and `8 << l` fronts per row.
            let got = unsafe {
                match l {
                    1 => {
                        certify8::<1>(args.0, args.1, args.2, args.3, args.4, (wf, hf), fr.0, fr.1)
                    }
                    2 => {
                        certify8::<2>(args.0, args.1, args.2, args.3, args.4, (wf, hf), fr.0, fr.1)
                    }
                    _ => {
                        certify8::<3>(args.0, args.1, args.2, args.3, args.4, (wf, hf), fr.0, fr.1)
                    }
                }
            };
            assert_eq!(got, want, "case {case} level {l} pixel {i0}");
            set += want.count_ones();
            total += px as u32;
        }
        assert!(set > total / 5 && set < total * 4 / 5, "{set} of {total}");
    }

    /// Effective levels of one window of 64 pixels: runs aligned to their node (levels 1
    /// to 6), pixel pairs of level 0 or `NO_PLANE` elsewhere.
    fn fill(rng: &mut Rng, er: &mut [u8], l: u32) {
        let n = 1usize << l;
        let run = match l {
            1 => rng.next().is_multiple_of(2),
            6 => rng.next().is_multiple_of(4),
            _ => rng.next().is_multiple_of(3),
        };
        if run {
            er[..n].fill(l as u8);
        } else if l == 1 {
            let v = if rng.next().is_multiple_of(2) {
                0
            } else {
                super::super::node::NO_PLANE
            };
            er[..2].fill(v);
        } else {
            let (a, b) = er[..n].split_at_mut(n / 2);
            fill(rng, a, l - 1);
            fill(rng, b, l - 1);
        }
    }

    /// The windows' pixels left to scan equal the scalar scan's: every merged pixel except
    /// those of the runs of levels 1 to 3 whose pair certificate (`decode_plane`,
    /// `proxy_safe_front`, every front of both rows reaching it) holds; both answers occur.
    #[test]
    fn windows_equal_the_scalar_scan() {
        if !available() {
            eprintln!("no AVX2 and F16C: nothing to compare");
            return;
        }
        let mut rng = Rng(0x0dd_ba11_5eed_0002);
        let (w, h) = (1600usize, 900usize);
        let (wf, hf) = (w as f32, h as f32);
        let xe: Vec<f32> = (0..=w).map(|i| i as f32 / wf).collect();
        let cols = LevelCols::new(&xe, wf, hf);
        let mut levels: Vec<Level> = (0..5u32)
            .map(|l| {
                let (lw, lh) = (w.div_ceil(1 << l) as u32, h.div_ceil(1 << l) as u32);
                let n = if l == 0 { 0 } else { (lw * lh) as usize };
                Level {
                    w: lw,
                    h: lh,
                    nodes: vec![Node::EMPTY; n],
                }
            })
            .collect();
        let (mut kept, mut dropped) = (0u32, 0u32);
        for case in 0..400u32 {
            let j = 2 * (rng.next() % (h as u64 / 2)) as u32;
            let y_pair = (j as f32 / hf, (j + 2) as f32 / hf);
            // Random planes in the rows the pair reads, levels 1 to 4.
            for (l, lv) in levels.iter_mut().enumerate().skip(1) {
                let qy = (j >> l) as usize;
                for q in 0..lv.w as usize {
                    let g = if rng.next().is_multiple_of(4) {
                        1e-3
                    } else {
                        20.0
                    };
                    lv.nodes[qy * lv.w as usize + q] = Node::plane_with_gradient(
                        rng.f(0.0, 1.0),
                        rng.f(-g, g),
                        rng.f(-g, g),
                        l as u32,
                        wf,
                        hf,
                        (rng.next() % 4) as u32,
                    )
                    .unwrap();
                }
            }
            let mut er = vec![0u8; w];
            for x in (0..w).step_by(64) {
                fill(&mut rng, &mut er[x..x + 64], 6);
            }
            // The scalar certificate per run of level 1 to 3, and fronts around it.
            let thresholds: Vec<f32> = (0..w)
                .map(|i| {
                    let l = er[i] as u32;
                    if !(1..=3).contains(&l) {
                        return rng.f(0.0, 2.0);
                    }
                    let qx = (i >> l) as u32;
                    let lv = &levels[l as usize];
                    let node = lv.nodes[((j >> l) * lv.w + qx) as usize];
                    let p = decode_plane(node, l, qx, j >> l, wf, hf);
                    let (a, b) = ((qx << l) as usize, ((qx + 1) << l) as usize);
                    proxy_safe_front(p, (xe[a], xe[b]), y_pair)
                })
                .collect();
            let mut front = |t: f32| match rng.next() % 64 {
                0 => f32::NAN,
                1 => f32::NEG_INFINITY,
                2 => t,
                3 => f32::from_bits(t.to_bits().wrapping_sub(1)),
                4..=6 => t - rng.f(0.0, 0.1),
                _ => t + rng.f(0.0, 0.5),
            };
            let fr0: Vec<f32> = thresholds.iter().map(|&t| front(t)).collect();
            let fr1: Vec<f32> = thresholds.iter().map(|&t| front(t)).collect();
            let pair = PairRows::new(&levels, &cols, j, y_pair, (wf, hf), (&fr0, &fr1)).unwrap();
            assert_eq!(pair.end, w);
            for w0 in (0..w).step_by(64) {
                let mut want = 0u64;
                let mut i = w0;
                while i < w0 + 64 {
                    let l = er[i] as u32;
                    if l == 0 || l == 255 {
                        i += 1;
                        continue;
                    }
                    let end = i + (1 << l);
                    let t = thresholds[i];
                    let ok = (1..=3).contains(&l) && (i..end).all(|k| fr0[k] >= t && fr1[k] >= t);
                    if ok {
                        kept += 1;
                    } else {
                        dropped += 1;
                        for k in i..end {
                            want |= 1 << (k - w0);
                        }
                    }
                    i = end;
                }
                // SAFETY: the CPU has AVX2 and F16C (checked); `w0 + 64 <= pair.end`.
                let got = unsafe { uncertified64(&er[w0..], &pair, w0) };
                assert_eq!(got, want, "case {case} window {w0}");
            }
        }
        assert!(
            kept > (kept + dropped) / 5 && dropped > (kept + dropped) / 5,
            "{kept} certified, {dropped} left"
        );
    }
}
