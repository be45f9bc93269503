//! The runs of merged nodes in a pair of rows (`fixpoint::merged_triggers`, Widmer et al.
//! 2015, §3.3: the pixels under a merged node are tested against the node's plane) with
//! their nodes' decoded planes: the row's effective levels are scanned for runs of level
//! >= 1 (eight bytes of level 0 or `NO_PLANE` skipped at once), then the planes are decoded
//! four runs at a time in SSE2 lanes (x86_64; the rest one by one by [`decode_plane`]).
//!
//! Every lane does [`decode_plane`]'s operations in its order, so the planes are the same
//! bits: the f16 increments by `f16x4` (the integer operations of `f16_bits_to_f32`), the
//! gradient's exact power-of-two scales `w 2^-l`, `h 2^-l` from the exponent bits, the
//! test normal's scale `2^-floor(log2 max(1, |g_x|, |g_y|))` (`maxps` is the definition's
//! compare-select), the footprint centre `((q + 0.5) 2^l) / w` (`2^l` from the exponent
//! bits, the same value as the integer's conversion) and `c = (n.x x_c + n.y y_c) + n.z
//! z_c`. The test below compares the lanes with [`decode_plane`].

use glam::Vec3;

use super::node::{NO_PLANE, decode_plane};
use super::tree::Level;

/// A run of row pixels `i .. end` under the merged node `(l, qx, row >> l)` with its
/// decoded plane `p`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Run {
    pub(super) i: usize,
    pub(super) end: usize,
    pub(super) l: u32,
    pub(super) qx: u32,
    pub(super) p: (Vec3, f32),
}

/// The runs of level >= 1 of row `j`'s effective levels `er` (ascending) into `out`
/// (cleared first), with their planes (module docs).
pub(super) fn runs(er: &[u8], j: u32, levels: &[Level], (wf, hf): (f32, f32), out: &mut Vec<Run>) {
    out.clear();
    let wu = er.len();
    let mut i = 0;
    while i < wu {
        let l = er[i];
        if l == NO_PLANE || l == 0 {
            // Eight levels of 0 or `NO_PLANE` at once (each byte `b` is `(b & 1) 255`
            // then), else one.
            if i % 8 == 0 && i + 8 <= wu {
                let v = u64::from_le_bytes(er[i..i + 8].try_into().unwrap());
                if (v & 0x0101_0101_0101_0101) * 255 == v {
                    i += 8;
                    continue;
                }
            }
            i += 1;
            continue;
        }
        let l = l as u32;
        let qx = i as u32 >> l;
        let end = (((qx + 1) << l) as usize).min(wu);
        let p = (Vec3::ZERO, 0.0);
        out.push(Run { i, end, l, qx, p });
        i = end;
    }
    let node = |r: &Run| {
        let lv = &levels[r.l as usize];
        lv.nodes[((j >> r.l) * lv.w + r.qx) as usize]
    };
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    while done + 4 <= out.len() {
        let g = &mut out[done..done + 4];
        let nodes = [node(&g[0]), node(&g[1]), node(&g[2]), node(&g[3])];
        let ls = [g[0].l, g[1].l, g[2].l, g[3].l];
        let qx = [g[0].qx, g[1].qx, g[2].qx, g[3].qx];
        let qy = ls.map(|l| j >> l);
        let planes = lanes::decode_planes4(nodes, ls, qx, qy, (wf, hf));
        for (r, p) in g.iter_mut().zip(planes) {
            r.p = p;
        }
        done += 4;
    }
    for r in &mut out[done..] {
        r.p = decode_plane(node(r), r.l, r.qx, j >> r.l, wf, hf);
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod lanes {
    use core::arch::x86_64::*;

    use glam::{Vec3, Vec4};

    use super::super::node::Node;
    use super::super::trigger_lanes::f16x4;

    /// [`super::decode_plane`] of four nodes `(node, level, qx, qy)` in lanes (module docs).
    #[inline]
    pub(in super::super) fn decode_planes4(
        nodes: [Node; 4],
        l: [u32; 4],
        qx: [u32; 4],
        qy: [u32; 4],
        (w, h): (f32, f32),
    ) -> [(Vec3, f32); 4] {
        let s = Vec4::splat;
        let words = |f: fn(&Node) -> u32| -> __m128i {
            let v = nodes.each_ref().map(f);
            // SAFETY: SSE2 baseline; four `u32`s.
            unsafe { _mm_loadu_si128(v.as_ptr() as *const __m128i) }
        };
        let (a, b) = (words(|n| n.a), words(|n| n.b));
        // SAFETY (all below): SSE2 is part of the x86_64 baseline; four-element arrays.
        let (lv, qxv, qyv) = unsafe {
            (
                _mm_loadu_si128(l.as_ptr() as *const __m128i),
                _mm_cvtepi32_ps(_mm_loadu_si128(qx.as_ptr() as *const __m128i)),
                _mm_cvtepi32_ps(_mm_loadu_si128(qy.as_ptr() as *const __m128i)),
            )
        };
        let (nx, ny, nz, c) = unsafe {
            // `w 2^-l`, `h 2^-l` by lowering the exponent (`Node::gradient`).
            let shift = _mm_slli_epi32::<23>(lv);
            let ws = Vec4::from(_mm_castsi128_ps(_mm_sub_epi32(
                _mm_set1_epi32(w.to_bits() as i32),
                shift,
            )));
            let hs = Vec4::from(_mm_castsi128_ps(_mm_sub_epi32(
                _mm_set1_epi32(h.to_bits() as i32),
                shift,
            )));
            let gx = f16x4(b) * ws;
            let gy = f16x4(_mm_srli_epi32::<16>(b)) * hs;
            // `Node::test_normal`.
            let m = _mm_max_ps(gx.abs().into(), gy.abs().into());
            let m = _mm_max_ps(m, _mm_set1_ps(1.0));
            let e = _mm_and_si128(_mm_castps_si128(m), _mm_set1_epi32(0x7f80_0000));
            let sc = Vec4::from(_mm_castsi128_ps(_mm_sub_epi32(
                _mm_set1_epi32(0x7f00_0000),
                e,
            )));
            let (nx, ny, nz) = (gx * sc, gy * sc, -sc);
            // `node_centre`: `2^l` as `(127 + l) << 23`.
            let size = Vec4::from(_mm_castsi128_ps(_mm_slli_epi32::<23>(_mm_add_epi32(
                lv,
                _mm_set1_epi32(127),
            ))));
            let xc = ((Vec4::from(qxv) + s(0.5)) * size) / s(w);
            let yc = ((Vec4::from(qyv) + s(0.5)) * size) / s(h);
            // `Node::zc`.
            let zc = Vec4::from(_mm_castsi128_ps(_mm_and_si128(
                a,
                _mm_set1_epi32(0x7fff_fffc),
            )));
            (nx, ny, nz, nx * xc + ny * yc + nz * zc)
        };
        let (nx, ny, nz, c) = (nx.to_array(), ny.to_array(), nz.to_array(), c.to_array());
        core::array::from_fn(|d| (Vec3::new(nx[d], ny[d], nz[d]), c[d]))
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::quadtree::node::Node;
    use crate::quadtree::test_rng::Rng;

    /// Four planes decoded in lanes equal [`decode_plane`] bit for bit: random plane nodes
    /// (ordinary, steep with clamped and f16-maximum slopes, subnormal halves, flagged) at
    /// levels 1-8 and positions over a 1600x900 image.
    #[test]
    fn lanes_equal_decode_plane() {
        let mut rng = Rng(0x0dec_0de5_fa11_4ee5);
        let (wf, hf) = (1600.0f32, 900.0f32);
        let mut checked = 0;
        for case in 0..4000u32 {
            let mut node = |l: u32| loop {
                let (a, b) = match rng.next() % 4 {
                    0 => (rng.f(-1e9, 1e9), rng.f(-5e-2, 5e-2)),
                    1 => (rng.f(-1e-6, 1e-6), rng.f(-1e-6, 1e-6)),
                    _ => (rng.f(-3.0, 3.0), rng.f(-3.0, 3.0)),
                };
                let flag = (rng.next() % 2) as u32;
                if let Some(n) = Node::plane_with_gradient(rng.f(0.0, 1.0), a, b, l, wf, hf, flag) {
                    return n;
                }
            };
            let l: [u32; 4] = core::array::from_fn(|_| 1 + (rng.next() % 8) as u32);
            let nodes = l.map(&mut node);
            let qx = l.map(|l| (rng.next() % ((1600 >> l) + 1)) as u32);
            let qy = l.map(|l| (rng.next() % ((900 >> l) + 1)) as u32);
            let got = lanes::decode_planes4(nodes, l, qx, qy, (wf, hf));
            for d in 0..4 {
                let want = decode_plane(nodes[d], l[d], qx[d], qy[d], wf, hf);
                let bits = |(n, c): (Vec3, f32)| (n.to_array().map(f32::to_bits), c.to_bits());
                assert_eq!(bits(got[d]), bits(want), "case {case} lane {d}");
                checked += 1;
            }
        }
        assert_eq!(checked, 16000);
    }
}
