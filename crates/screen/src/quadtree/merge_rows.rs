//! One row of a pruning level (Widmer et al. 2015, §3.3) with four *parents* in the lanes of
//! `Vec4`s: the build's fast path over whole levels (level 1 alone has `W H / 4` parents).
//!
//! The children of four neighbouring parents are read straight from the two child rows
//! below them (no per-node index arithmetic); for each child position (0,0), (1,0), (0,1),
//! (1,1) a `Vec4` holds that child of the four parents. Every lane does exactly the operations
//! of the scalar definition ([`MergeCtx::parent`] with `lanes == false`: `merge` and
//! `proxy` in [`super::merge`]) in its order — IEEE square root, division, products and sums
//! are correctly rounded per lane, there is no fused multiply-add — so the nodes are the same
//! bits (`tests/quadtree_build.rs` compares whole trees with the reference build):
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
//! Parents that do not merge get the union of their children's conservative ranges by the
//! definition's own [`union`] (its `f32::min` / `f32::max` folds, in child order), with the
//! plane children's spreads computed in lanes as [`MergeCtx::zrange`] does.

use glam::{BVec4A, Vec4};

use super::merge::{MergeCtx, plane_range, union};
use super::node::{FLAG_CRACK, Node};
use super::tree::Level;

/// Lane-wise IEEE square root (`sqrtps`).
#[inline(always)]
fn sqrt4(v: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    #[allow(unused_unsafe)]
    {
        // SAFETY: SSE is part of the x86_64 baseline.
        unsafe { Vec4::from(core::arch::x86_64::_mm_sqrt_ps(v.into())) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        Vec4::from_array(v.to_array().map(f32::sqrt))
    }
}

/// `Vec4` from four values computed per lane.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> Vec4 {
    Vec4::new(f(0), f(1), f(2), f(3))
}

/// Child offsets `(dx, dy)` of the child positions, in the definition's order.
const KID: [(usize, usize); 4] = [(0, 0), (1, 0), (0, 1), (1, 1)];
/// Footprint corner signs, in the definition's order.
const CORNER: [(f32, f32); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

impl MergeCtx {
    /// Row `qy` of level `l` (`out`: the row's nodes) from level `l - 1` (`child`), equal
    /// node for node to [`MergeCtx::parent`] of each parent's four children; `allow(qx)`:
    /// whether parent `qx` may merge (contains no blocked pixel).
    pub(super) fn parent_row(
        &self,
        child: &Level,
        l: u32,
        qy: u32,
        out: &mut [Node],
        allow: impl Fn(u32) -> bool,
    ) {
        let cw = child.w as usize;
        let y0 = 2 * qy as usize;
        let r0 = &child.nodes[y0 * cw..(y0 + 1) * cw];
        let r1 = &child.nodes[(y0 + 1) * cw..(y0 + 2) * cw];
        for (g, outs) in out.chunks_mut(4).enumerate() {
            let qx0 = 4 * g;
            // kids[k][p]: child k of parent qx0 + p (empty beyond the row).
            let mut kids = [[Node::EMPTY; 4]; 4];
            let mut any_plane = false;
            for p in 0..outs.len() {
                let x = 2 * (qx0 + p);
                let ks = [r0[x], r0[x + 1], r1[x], r1[x + 1]];
                for (k, n) in ks.into_iter().enumerate() {
                    kids[k][p] = n;
                    any_plane |= n.is_plane();
                }
            }
            if !any_plane {
                // Only AABB children: their stored ranges.
                for (p, o) in outs.iter_mut().enumerate() {
                    *o = union((0..4).map(|k| kids[k][p].zrange()));
                }
                continue;
            }
            self.parents4(l, qx0 as u32, qy, &kids, outs, &allow);
        }
    }

    /// Parents `qx0 .. qx0 + out.len()` of row `qy`, level `l`, from their children
    /// `kids[k][p]` (module docs).
    #[inline]
    fn parents4(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &[[Node; 4]; 4],
        out: &mut [Node],
        allow: &impl Fn(u32) -> bool,
    ) {
        let s = Vec4::splat;
        let cl = l - 1;
        // The gradients as `Node::gradient` computes them (garbage in lanes of AABB
        // children, which nothing below reads).
        let (ws, hs) = (
            f32::from_bits(self.wf.to_bits() - (cl << 23)),
            f32::from_bits(self.hf.to_bits() - (cl << 23)),
        );
        let mut gx = [Vec4::ZERO; 4];
        let mut gy = [Vec4::ZERO; 4];
        for k in 0..4 {
            let (mut ex, mut ey) = ([0.0f32; 4], [0.0f32; 4]);
            for p in 0..4 {
                (ex[p], ey[p]) = kids[k][p].increments();
            }
            gx[k] = Vec4::from(ex) * s(ws);
            gy[k] = Vec4::from(ey) * s(hs);
        }
        let n = out.len();
        let cand = |p: usize| {
            p < n && !self.never && (0..4).all(|k| kids[k][p].is_plane()) && allow(qx0 + p as u32)
        };
        let cand = [cand(0), cand(1), cand(2), cand(3)];
        let mut merged = [None; 4];
        if cand.iter().any(|&c| c) {
            merged = self.merge4(l, qx0, qy, kids, cand, &gx, &gy);
        }
        if merged[..n].iter().all(|m| m.is_some()) {
            for (o, m) in out.iter_mut().zip(merged) {
                *o = m.expect("checked");
            }
            return;
        }
        // `MergeCtx::zrange` per child: the spread's divisions in lanes.
        let size = (1u32 << cl) as f32;
        let mut spread = [[0.0f32; 4]; 4];
        for k in 0..4 {
            let half = lanes(|p| {
                let dil = if kids[k][p].flags() & FLAG_CRACK != 0 {
                    self.crack_px
                } else {
                    0.0
                };
                0.5 * size + dil
            });
            spread[k] =
                ((gx[k].abs() * half) / s(self.wf) + (gy[k].abs() * half) / s(self.hf)).to_array();
        }
        for (p, o) in out.iter_mut().enumerate() {
            *o = merged[p].unwrap_or_else(|| {
                union((0..4).map(|k| {
                    let kid = kids[k][p];
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
    #[inline]
    fn merge4(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &[[Node; 4]; 4],
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
            let xc = ((lanes(|p| (2 * (qx0 + p as u32) + kx as u32) as f32) + s(0.5)) * s(size))
                / s(self.wf);
            let yc = s((((2 * qy + ky as u32) as f32 + 0.5) * size) / self.hf);
            let zc = lanes(|p| kids[k][p].zc());
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
            dm = Vec4::select(d.cmpgt(dm), d, dm);
        }
        let dmax = (dm / -nnz).to_array();
        let psize = (1u32 << l) as f32;
        let xc = ((lanes(|p| (qx0 + p as u32) as f32) + s(0.5)) * s(psize)) / s(self.wf);
        let yc = s(((qy as f32 + 0.5) * psize) / self.hf);
        let zc = ((c - nnx * xc - nny * yc) / nnz).to_array();
        let inv = s(-1.0) / nnz;
        let (gxp, gyp) = ((nnx * inv).to_array(), (nny * inv).to_array());
        let min_cos = min_cos.to_array();
        let valid = valid.bitmask();
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
                let flags = (0..4).fold(0, |f, k| f | (kids[k][p].flags() & FLAG_CRACK));
                *r = Node::plane_with_gradient(zc[p], gxp[p], gyp[p], l, self.wf, self.hf, flags);
            }
        }
        res
    }
}
