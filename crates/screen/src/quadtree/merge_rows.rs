//! One row of a pruning level (Widmer et al. 2015, §3.3) with four *parents* in the lanes of
//! `Vec4`s: the build's fast path over whole levels (level 1 alone has `W H / 4` parents).
//!
//! The children of four neighbouring parents are read straight from the two child rows below
//! them (no per-node index arithmetic): two SSE2 loads of two nodes per parent and a 4x4
//! transpose give, for each child position (0,0), (1,0), (0,1), (1,1), that child's `a` and `b`
//! words of the four parents in lanes; the tags, `z_c`, flags and the f16 slopes are decoded in
//! those lanes (the same integer operations as [`super::node`]'s scalar decode). Every lane
//! does exactly the operations of the scalar definition ([`MergeCtx::parent`] with `lanes ==
//! false`: `merge` and `proxy` in [`super::merge`]) in its order — IEEE square root, division,
//! products and sums are correctly rounded per lane, there is no fused multiply-add — so the
//! nodes are the same bits (`tests/quadtree_build.rs` compares whole trees with the reference
//! build):
//!
//! - the child normals `(g_x, g_y, -1) / sqrt(1 + g_x^2 + g_y^2)`, their sum from `+0` in
//!   child order and glam's `normalize_or_zero` (`1 / sqrt(dot)`, kept if finite and `> 0`);
//! - the smallest child cosine as `minps`: the cosines of a lane that can merge are finite,
//!   and the definition only compares the minimum with thresholds, so the sign a tie of
//!   zeros might take does not matter;
//! - the 16 corner projections summed in the definition's order (child-major) from the
//!   same initial value as `f32`'s `Sum`, and their largest deviation by compare-select
//!   (the definition's fold skips NaN the same way);
//! - the proxy's centre `z`, slopes and the thresholds per lane; the node itself is encoded
//!   per merged lane by the same [`Node::plane_with_gradient`].
//!
//! Parents that do not merge get the union of their children's conservative ranges
//! (§3.3's AABB nodes), in lanes: the plane children's spreads as [`MergeCtx::zrange`]
//! computes them, their ranges as `plane_range` (the clamp by `maxps` / `minps`), an AABB
//! child's stored range, then `merge_kids::union_lanes` (`minps` / `maxps` folds, the emptiness test and
//! [`Node::aabb`]). No range holds a NaN or `-0` (a plane range is a clamped sum of a finite
//! `z_c`, a finite spread and `±Z_EPS`; a group with an AABB word that is NaN or `-0` takes
//! the definition's own [`union`]), and then `minps` / `maxps` equal the definition's
//! `f32::min` / `f32::max` folds in child order, so the nodes are the same bits (tests below:
//! rows against the scalar [`MergeCtx::parent`], the lane union against [`union`]).

use core::arch::x86_64::*;

use glam::{BVec4A, Vec4};

use super::merge::{MergeCtx, plane_range, union};
use super::merge_kids::{CORNER, KID, Kids, union_lanes};
use super::node::{FLAG_CRACK, Node};
use super::tree::Z_EPS;

/// Lane-wise IEEE square root (`sqrtps`).
#[inline(always)]
fn sqrt4(v: Vec4) -> Vec4 {
    // SAFETY: SSE is part of the x86_64 baseline.
    unsafe { Vec4::from(_mm_sqrt_ps(v.into())) }
}

impl MergeCtx {
    /// [`Self::parent_row_of`] with the child rows read from level `l - 1` (`child`).
    #[cfg(test)]
    pub(super) fn parent_row(
        &self,
        child: &super::tree::Level,
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: super::prune::Allow,
    ) {
        let (cw, y0) = (child.w as usize, 2 * qy as usize);
        let rows = &child.nodes[y0 * cw..(y0 + 2) * cw];
        self.parent_row_of(rows.split_at(cw), l, qy, out, allow);
    }

    /// Row `qy` of level `l` (`out`: the row's nodes) from rows `2 qy`, `2 qy + 1` of level
    /// `l - 1` (`r0`, `r1`, of one length), equal node for node to [`MergeCtx::parent`] of
    /// each parent's four children; `allow`: which parents may merge (contain no blocked
    /// pixel).
    pub(super) fn parent_row_of(
        &self,
        (r0, r1): (&[Node], &[Node]),
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: super::prune::Allow,
    ) {
        let r1 = &r1[..r0.len()];
        for (g, outs) in out.chunks_mut(4).enumerate() {
            let qx0 = 4 * g;
            let kids = Kids::gather(r0, r1, qx0, outs.len());
            self.group4(l, qx0 as u32, qy, &kids, outs, allow, None);
        }
    }

    /// Parents `qx0 .. qx0 + out.len()` (at most four) of row `qy`, level `l`, from their
    /// children `kids`; `pre`: the merges of the candidate parents if already computed
    /// (`merge_rows8`; `None` in the lanes of parents that are not candidates or do not
    /// merge), else computed here.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn group4(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &Kids,
        out: &mut [Node],
        allow: super::prune::Allow,
        pre: Option<[Option<Node>; 4]>,
    ) {
        let any_plane = (0..4).fold(0, |m, k| m | kids.planes(k));
        if any_plane == 0 {
            // Only AABB children: their stored ranges.
            if kids.all_empty() {
                out.fill(Node::EMPTY);
                return;
            }
            if kids.aabb_union(out) {
                return;
            }
            let ks = [kids.nodes(0), kids.nodes(1), kids.nodes(2), kids.nodes(3)];
            for (p, o) in out.iter_mut().enumerate() {
                *o = union((0..4).map(|k| ks[k][p].zrange()));
            }
            return;
        }
        self.parents4(l, qx0, qy, kids, out, allow, pre);
    }

    /// Parents `qx0 .. qx0 + out.len()` of row `qy`, level `l`, from their children
    /// `kids` (module docs).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn parents4(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &Kids,
        out: &mut [Node],
        allow: super::prune::Allow,
        pre: Option<[Option<Node>; 4]>,
    ) {
        let s = Vec4::splat;
        let cl = l - 1;
        // The gradients as `Node::gradient` computes them (garbage in lanes of AABB
        // children, which nothing below reads).
        let (ws, hs) = (
            f32::from_bits(self.wf.to_bits() - (cl << 23)),
            f32::from_bits(self.hf.to_bits() - (cl << 23)),
        );
        // Decoded only where needed: not for a group whose merges `pre` brings and which
        // all merged.
        let grads = || {
            let mut gx = [Vec4::ZERO; 4];
            let mut gy = [Vec4::ZERO; 4];
            for k in 0..4 {
                let (ex, ey) = kids.increments(k);
                gx[k] = ex * s(ws);
                gy[k] = ey * s(hs);
            }
            (gx, gy)
        };
        let n = out.len();
        let mut g = None;
        let merged = match pre {
            Some(m) => m,
            None => {
                let all_planes = (0..4).fold(0xf, |m, k| m & kids.planes(k));
                let cand = |p: usize| {
                    p < n && !self.never && all_planes & (1 << p) != 0 && allow.get(qx0 + p as u32)
                };
                let cand = [cand(0), cand(1), cand(2), cand(3)];
                let (gx, gy) = g.insert(grads());
                if cand.iter().any(|&c| c) {
                    self.merge4(l, qx0, qy, kids, cand, gx, gy)
                } else {
                    [None; 4]
                }
            }
        };
        if merged[..n].iter().all(|m| m.is_some()) {
            for (o, m) in out.iter_mut().zip(merged) {
                *o = m.expect("checked");
            }
            return;
        }
        let (gx, gy) = g.unwrap_or_else(grads);
        // `MergeCtx::zrange` per child: the spread's divisions in lanes.
        let size = (1u32 << cl) as f32;
        let mut spread = [Vec4::ZERO; 4];
        for k in 0..4 {
            // SAFETY: SSE baseline.
            let half = Vec4::from(unsafe {
                let m = kids.crack(k);
                let (dil, none) = (s(0.5 * size + self.crack_px), s(0.5 * size + 0.0));
                _mm_or_ps(_mm_and_ps(m, dil.into()), _mm_andnot_ps(m, none.into()))
            });
            spread[k] = (gx[k].abs() * half) / s(self.wf) + (gy[k].abs() * half) / s(self.hf);
        }
        let special = (0..4).fold(0, |m, k| m | kids.special(k));
        if special == 0 {
            // Per child, `plane_range(z_c, spread)` of a plane child (`[0, 1]` for a spread
            // that is not finite; `z_c` and a finite spread give finite values, and neither
            // `lo - Z_EPS` nor `hi + Z_EPS` is `-0`, so `maxps` / `minps` are the clamp) or
            // an AABB child's stored range, then their union in lanes.
            let range = |k: usize| {
                // SAFETY: SSE2 baseline.
                unsafe {
                    let plane = _mm_castsi128_ps(_mm_srai_epi32::<31>(kids.words_a()[k]));
                    let (zc, sp): (__m128, __m128) = (kids.zc(k).into(), spread[k].into());
                    let finite = _mm_cmplt_ps(
                        _mm_andnot_ps(_mm_set1_ps(-0.0), sp),
                        _mm_set1_ps(f32::INFINITY),
                    );
                    let (zero, one, eps) = (_mm_setzero_ps(), _mm_set1_ps(1.0), _mm_set1_ps(Z_EPS));
                    let clamp = |v: __m128| _mm_min_ps(_mm_max_ps(v, zero), one);
                    let lo = clamp(_mm_sub_ps(_mm_sub_ps(zc, sp), eps));
                    let hi = clamp(_mm_add_ps(_mm_add_ps(zc, sp), eps));
                    let sel = |m: __m128, a: __m128, b: __m128| {
                        _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b))
                    };
                    let (lo, hi) = (sel(finite, lo, zero), sel(finite, hi, one));
                    (
                        sel(plane, lo, _mm_castsi128_ps(kids.words_a()[k])),
                        sel(plane, hi, _mm_castsi128_ps(kids.word_b(k))),
                    )
                }
            };
            let ranges = [range(0), range(1), range(2), range(3)];
            let (a, b) = union_lanes(ranges);
            for (p, o) in out.iter_mut().enumerate() {
                *o = merged[p].unwrap_or(Node { a: a[p], b: b[p] });
            }
            return;
        }
        let spread = spread.map(|v| v.to_array());
        let ks = [kids.nodes(0), kids.nodes(1), kids.nodes(2), kids.nodes(3)];
        for (p, o) in out.iter_mut().enumerate() {
            *o = merged[p].unwrap_or_else(|| {
                union((0..4).map(|k| {
                    let kid = ks[k][p];
                    if kid.is_plane() {
                        plane_range(kid.zc(), spread[k][p])
                    } else {
                        kid.zrange()
                    }
                }))
            });
        }
    }

    /// `MergeCtx::merge` and `MergeCtx::proxy` of the candidate parents (`cand`: four
    /// plane children, allowed to merge) in lanes; `gx`, `gy`: the children's gradients.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn merge4(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &Kids,
        cand: [bool; 4],
        gx: &[Vec4; 4],
        gy: &[Vec4; 4],
    ) -> [Option<Node>; 4] {
        let s = Vec4::splat;
        let cl = l - 1;
        // `Node::normal` per child, and their sum from `+0` in child order.
        let (mut nx, mut ny, mut nz) = ([Vec4::ZERO; 4], [Vec4::ZERO; 4], [Vec4::ZERO; 4]);
        let (mut sx, mut sy, mut sz) = (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO);
        for k in 0..4 {
            let r = s(1.0) / sqrt4(s(1.0) + gx[k] * gx[k] + gy[k] * gy[k]);
            (nx[k], ny[k], nz[k]) = (gx[k] * r, gy[k] * r, -r);
            sx += nx[k];
            sy += ny[k];
            sz += nz[k];
        }
        // `Vec3::normalize_or_zero`.
        let rcp = s(1.0) / sqrt4(sx * sx + sy * sy + sz * sz);
        let ok = rcp.is_finite_mask() & rcp.cmpgt(Vec4::ZERO);
        let (nnx, nny, nnz) = (
            Vec4::select(ok, sx * rcp, Vec4::ZERO),
            Vec4::select(ok, sy * rcp, Vec4::ZERO),
            Vec4::select(ok, sz * rcp, Vec4::ZERO),
        );
        let mut min_cos = s(f32::INFINITY);
        for k in 0..4 {
            min_cos = min_cos.min(nx[k] * nnx + ny[k] * nny + nz[k] * nnz);
        }
        let valid = BVec4A::new(cand[0], cand[1], cand[2], cand[3])
            & nnz.cmplt(s(-1e-6))
            & min_cos.cmpgt(s(self.loosest_cos()));
        if !valid.any() {
            return [None; 4];
        }
        // The 16 child corners projected on the proxy normal, child-major.
        let size = (1u32 << cl) as f32;
        let half = 0.5 * size;
        let (hx, hy) = (half / self.wf, half / self.hf);
        let init: f32 = core::iter::empty::<f32>().sum();
        let mut acc = s(init);
        let mut proj = [Vec4::ZERO; 16];
        for (k, &(kx, ky)) in KID.iter().enumerate() {
            // The children's columns `2 (qx0 + p) + kx` as floats: sums of small integers,
            // exact, so the same values as the conversions of `node_centre`.
            let cx = s((2 * qx0 + kx as u32) as f32) + Vec4::new(0.0, 2.0, 4.0, 6.0);
            let xc = ((cx + s(0.5)) * s(size)) / s(self.wf);
            let yc = s((((2 * qy + ky as u32) as f32 + 0.5) * size) / self.hf);
            let zc = kids.zc(k);
            for (m, &(cx, cy)) in CORNER.iter().enumerate() {
                let (dx, dy) = (cx * hx, cy * hy);
                let (px, py, pz) = (xc + s(dx), yc + s(dy), zc + gx[k] * s(dx) + gy[k] * s(dy));
                let v = nnx * px + nny * py + nnz * pz;
                proj[4 * k + m] = v;
                acc += v;
            }
        }
        // `MergeCtx::proxy`.
        let c = acc / s(16.0);
        let mut dm = Vec4::ZERO;
        for v in proj {
            let d = (v - c).abs();
            // SAFETY: SSE baseline. `maxps(d, dm)` is `d > dm ? d : dm` per lane (a NaN `d`
            // keeps `dm`): the definition's compare-select.
            dm = Vec4::from(unsafe { _mm_max_ps(d.into(), dm.into()) });
        }
        let dmax = (dm / -nnz).to_array();
        let psize = (1u32 << l) as f32;
        let xc = ((s(qx0 as f32) + Vec4::new(0.0, 1.0, 2.0, 3.0) + s(0.5)) * s(psize)) / s(self.wf);
        let yc = s(((qy as f32 + 0.5) * psize) / self.hf);
        let zc = ((c - nnx * xc - nny * yc) / nnz).to_array();
        let inv = s(-1.0) / nnz;
        let (gxp, gyp) = ((nnx * inv).to_array(), (nny * inv).to_array());
        let min_cos = min_cos.to_array();
        let valid = valid.bitmask();
        // SAFETY: SSE baseline.
        let crack = unsafe {
            let m = _mm_or_ps(
                _mm_or_ps(kids.crack(0), kids.crack(1)),
                _mm_or_ps(kids.crack(2), kids.crack(3)),
            );
            _mm_movemask_ps(m) as u32
        };
        let mut res = [None; 4];
        for (p, r) in res.iter_mut().enumerate() {
            if valid & (1 << p) == 0 {
                continue;
            }
            let u = if self.adaptive {
                self.depth_fraction(zc[p])
            } else {
                0.0
            };
            if min_cos[p] > self.cos_thr(u) && dmax[p] < self.dist_thr(u) {
                let flags = if (crack >> p) & 1 != 0 { FLAG_CRACK } else { 0 };
                *r = Node::plane_with_gradient(zc[p], gxp[p], gyp[p], l, self.wf, self.hf, flags);
            }
        }
        res
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadtree::prune::{Allow, parent_of};
    use crate::quadtree::test_rng::Rng;

    /// Rows of four parents in lanes equal the scalar definition ([`MergeCtx::parent`] with
    /// `lanes == false`) node for node, with the unions of the parents that do not merge in
    /// lanes: random child levels 0-3 mixing plane children (near-coplanar, clamped and
    /// f16-maximum slopes, flagged) with empty and AABB children (some inverted, from `0`, up
    /// to `+inf`), blocked parents, odd widths.
    #[test]
    fn rows_equal_the_definition() {
        let mut rng = Rng(0x0dd5_eed5_1234_4321);
        let (mut planes, mut boxes) = (0usize, 0usize);
        for case in 0..64u32 {
            let ctx = MergeCtx::test_case(case);
            let (wf, hf) = (ctx.wf, ctx.hf);
            let def = MergeCtx {
                lanes: false,
                ..ctx
            };
            let cl = case % 4;
            let l = cl + 1;
            let pw = 1 + (rng.next() % 40) as u32;
            let ph = 3u32;
            let (cw, ch) = (2 * pw, 2 * ph);
            let (z0, ax, ay) = (rng.f(0.2, 0.8), rng.f(-2.0, 2.0), rng.f(-2.0, 2.0));
            let nodes: Vec<Node> = (0..cw * ch)
                .map(|k| {
                    let (x, y) = (k % cw, k / cw);
                    let size = (1u32 << cl) as f32;
                    let (xc, yc) = ((x as f32 + 0.5) * size / wf, (y as f32 + 0.5) * size / hf);
                    let flags = if rng.next().is_multiple_of(8) {
                        FLAG_CRACK
                    } else {
                        0
                    };
                    let g = rng.f(-1e9, 1e9);
                    match rng.next() % 10 {
                        0 => Node::EMPTY,
                        1 => Node::aabb(rng.f(0.0, 0.5), rng.f(0.5, 1.0)),
                        2 => Node::aabb(rng.f(0.5, 1.0), rng.f(0.0, 0.5)),
                        3 => Node::aabb(0.0, f32::INFINITY),
                        4 => Node::plane_with_gradient(rng.f(0.0, 1.0), g, -g, cl, wf, hf, flags)
                            .unwrap_or(Node::EMPTY),
                        // The f16 maximum as both increments.
                        5 => Node::plane(rng.f(0.0, 1.0), 65504.0, 65504.0, flags)
                            .unwrap_or(Node::EMPTY),
                        _ => Node::plane_with_gradient(
                            z0 + ax * xc + ay * yc + rng.f(-1e-4, 1e-4),
                            ax + rng.f(-1e-2, 1e-2),
                            ay + rng.f(-1e-2, 1e-2),
                            cl,
                            wf,
                            hf,
                            flags,
                        )
                        .unwrap_or(Node::EMPTY),
                    }
                })
                .collect();
            let child = crate::quadtree::tree::Level {
                w: cw,
                h: ch,
                nodes,
            };
            let blocked: Vec<bool> = (0..pw * ph)
                .map(|_| rng.next().is_multiple_of(10))
                .collect();
            for qy in 0..ph {
                let allow = Allow(Some(&blocked[(qy * pw) as usize..((qy + 1) * pw) as usize]));
                let mut row = vec![Node { a: 1, b: 1 }; pw as usize];
                ctx.parent_row(&child, l, qy, &mut row, allow);
                for (qx, got) in row.iter().enumerate() {
                    let qx = qx as u32;
                    let want = parent_of(&def, &child, l, qx, qy, allow.get(qx));
                    assert_eq!(*got, want, "case {case}, level {l}, parent ({qx}, {qy})");
                    planes += usize::from(want.is_plane());
                    boxes += usize::from(!want.is_plane() && want != Node::EMPTY);
                }
            }
        }
        assert!(
            planes > 50 && boxes > 500,
            "{planes} plane and {boxes} AABB parents"
        );
    }

    /// The lane union of AABB children equals the definition's [`union`] node for node:
    /// random ranges (empty, inverted, zero-width, from `0`, up to `+inf`), rows of one to
    /// four parents; groups holding a NaN or `-0` word are left to the definition.
    #[test]
    fn aabb_union_equals_the_definition() {
        let mut rng = Rng(0x5eed_0abb_0c0d_e001);
        let (mut done, mut left) = (0usize, 0usize);
        for case in 0..4000u32 {
            let n = 1 + (case % 4) as usize;
            let kid = |rng: &mut Rng| match rng.next() % 8 {
                0 => Node::EMPTY,
                1 => Node::aabb(0.0, rng.f(0.0, 1.0)),
                2 => {
                    let z = rng.f(0.0, 1.0);
                    Node::aabb(z, z)
                }
                3 => Node::aabb(rng.f(0.5, 1.0), rng.f(0.0, 0.5)),
                4 if case % 50 == 0 => Node {
                    a: 0x7fc0_0000,
                    b: 0x3f00_0000,
                },
                5 if case % 50 == 1 => Node {
                    a: 0x3e00_0000,
                    b: 0x8000_0000,
                },
                6 => Node::aabb(rng.f(0.0, 1.0), f32::INFINITY),
                _ => Node::aabb(rng.f(0.0, 0.6), rng.f(0.4, 1.0)),
            };
            // Two child rows of eight nodes (four parents), all AABB children.
            let r0: Vec<Node> = (0..8).map(|_| kid(&mut rng)).collect();
            let r1: Vec<Node> = (0..8).map(|_| kid(&mut rng)).collect();
            let kids = Kids::gather(&r0, &r1, 0, n);
            let mut out = vec![Node { a: 1, b: 1 }; n];
            if !kids.aabb_union(&mut out) {
                left += 1;
                continue;
            }
            for (p, o) in out.iter().enumerate() {
                let want = union(
                    [r0[2 * p], r0[2 * p + 1], r1[2 * p], r1[2 * p + 1]]
                        .iter()
                        .map(|c| c.zrange()),
                );
                assert_eq!(*o, want, "case {case}, parent {p}");
                done += 1;
            }
        }
        assert!(
            done > 5000 && left > 0,
            "{done} parents compared, {left} groups left"
        );
    }
}
