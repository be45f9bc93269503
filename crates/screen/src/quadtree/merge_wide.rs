//! The merge of candidate parents (Widmer et al. 2015, §3.3; `merge_rows`' `merge4`: the
//! child normals, their normalised sum, the cosines, the 16 corner projections and their
//! largest deviation, the proxy) for several parents at once, generic over the lanes
//! ([`MergeLanes`]): eight in AVX2 lanes (`merge_rows8`'s `F8`), sixteen in AVX-512 lanes
//! (`merge_rows16`'s `F16`). Each lane does `merge_rows`' four-lane operations in their
//! order (its module docs list them), so every width gives the same proxies bit for bit; the
//! callers encode the proxies' nodes at their width.

use core::ops::{Add, Div, Mul, Neg, Sub};

use super::leaf_avx2::F16_MAX;
use super::merge::MergeCtx;
use super::merge_kids::{CORNER, KID, Kids};

/// `Add`, `Sub`, `Mul`, `Div` of a lane type `$t` (a tuple struct of one register) by the
/// intrinsics given, one instruction each (SAFETY: the lane type's contract, its module
/// docs); `merge_rows8::F8` and `merge_rows16::F16`.
macro_rules! lane_ops {
    ($t:ident: $add:ident, $sub:ident, $mul:ident, $div:ident) => {
        lane_ops!(@one $t, Add, add, $add);
        lane_ops!(@one $t, Sub, sub, $sub);
        lane_ops!(@one $t, Mul, mul, $mul);
        lane_ops!(@one $t, Div, div, $div);
    };
    (@one $t:ident, $tr:ident, $f:ident, $i:ident) => {
        impl $tr for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
                // SAFETY: the lane type's contract (module docs).
                $t(unsafe { $i(self.0, o.0) })
            }
        }
    };
}
pub(super) use lane_ops;

/// The lanes of [`MergeCtx::merge_wide`]: eight parents (`F8`, AVX2) or sixteen
/// (`merge_rows16::F16`, AVX-512). Every method is one instruction (or a fixed sequence) of
/// the same IEEE operation per lane, so the generic merge does the same operations in the
/// same order at either width. The children come as consecutive [`Kids`], four parents each.
pub(super) trait MergeLanes:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    type M: MergeMask;
    /// Parents per step (8 or 16).
    const N: usize;
    fn splat(v: f32) -> Self;
    /// Lane `p` holds `p step` (small integers times `step`: exact).
    fn ramp(step: f32) -> Self;
    /// The first `N` lanes (the rest 0).
    fn to_array(self) -> [f32; 16];
    fn sqrt(self) -> Self;
    /// `minps(self, o)`, as glam's `Vec4::min`.
    fn min(self, o: Self) -> Self;
    /// `maxps(self, o)`: `self > o ? self : o` per lane.
    fn max_ps(self, o: Self) -> Self;
    /// `|self|` (sign bit cleared).
    fn abs(self) -> Self;
    fn gt(self, o: Self) -> Self::M;
    fn lt(self, o: Self) -> Self::M;
    fn ge(self, o: Self) -> Self::M;
    /// Lanes that are not NaN.
    fn ordered(self) -> Self::M;
    /// glam's `is_finite_mask`: `|self| < inf`.
    fn finite(self) -> Self::M;
    /// `a` where `m`, else `b`.
    fn select(m: Self::M, a: Self, b: Self) -> Self;
    /// Child `k`'s stored increments of the parents of `kids` ([`Kids::increments`] in lanes).
    fn increments(kids: &[Kids], k: usize) -> (Self, Self);
    /// Child `k`'s `z_c` of the parents of `kids` ([`Kids::zc`]).
    fn zc(kids: &[Kids], k: usize) -> Self;
}

/// A lane mask of a [`MergeLanes`].
pub(super) trait MergeMask: Copy {
    fn and(self, o: Self) -> Self;
    /// Bit `p` set iff lane `p` is.
    fn bits(self) -> u32;
}

/// The proxy of [`MergeCtx::merge_wide`] per lane: `z_c` and the increments `x`, `y`
/// (clamped to the f16 range, not yet encoded), and the lanes that merge (bits).
pub(super) struct Merged<F> {
    pub(super) mask: u32,
    pub(super) zc: F,
    pub(super) ex: F,
    pub(super) ey: F,
}

impl MergeCtx {
    /// `merge_rows`' `merge4` for `F::N` parents: lanes `4 i .. 4 i + 4` the parents of
    /// `kids[i]` (`cand`: bits of the parents with four plane children, allowed to merge).
    /// Returns the lanes that merged and their proxies (other lanes: garbage). Generic over
    /// the lane width ([`MergeLanes`]): eight parents in AVX2 lanes (`parent_row8`),
    /// sixteen in AVX-512 lanes (`merge_rows16`), the same operations per lane.
    #[inline(always)]
    pub(super) fn merge_wide<F: MergeLanes>(
        &self,
        l: u32,
        qx0: u32,
        qy: u32,
        kids: &[Kids],
        cand_bits: u32,
    ) -> Merged<F> {
        let s = F::splat;
        let cl = l - 1;
        let (ws, hs) = (
            f32::from_bits(self.wf.to_bits() - (cl << 23)),
            f32::from_bits(self.hf.to_bits() - (cl << 23)),
        );
        let (mut gx, mut gy) = ([s(0.0); 4], [s(0.0); 4]);
        // `Node::normal` per child, and their sum from `+0` in child order.
        let (mut nx, mut ny, mut nz) = ([s(0.0); 4], [s(0.0); 4], [s(0.0); 4]);
        let (mut sx, mut sy, mut sz) = (s(0.0), s(0.0), s(0.0));
        for k in 0..4 {
            let (ex, ey) = F::increments(kids, k);
            gx[k] = ex * s(ws);
            gy[k] = ey * s(hs);
            let r = s(1.0) / (s(1.0) + gx[k] * gx[k] + gy[k] * gy[k]).sqrt();
            (nx[k], ny[k], nz[k]) = (gx[k] * r, gy[k] * r, -r);
            sx = sx + nx[k];
            sy = sy + ny[k];
            sz = sz + nz[k];
        }
        // `Vec3::normalize_or_zero`.
        let rcp = s(1.0) / (sx * sx + sy * sy + sz * sz).sqrt();
        let ok = rcp.finite().and(rcp.gt(s(0.0)));
        let (nnx, nny, nnz) = (
            F::select(ok, sx * rcp, s(0.0)),
            F::select(ok, sy * rcp, s(0.0)),
            F::select(ok, sz * rcp, s(0.0)),
        );
        let mut min_cos = s(f32::INFINITY);
        for k in 0..4 {
            min_cos = min_cos.min(nx[k] * nnx + ny[k] * nny + nz[k] * nnz);
        }
        let valid = cand_bits & nnz.lt(s(-1e-6)).bits() & min_cos.gt(s(self.loosest_cos())).bits();
        if valid == 0 {
            return Merged {
                mask: 0,
                zc: s(0.0),
                ex: s(0.0),
                ey: s(0.0),
            };
        }
        // The 16 child corners projected on the proxy normal, child-major.
        let size = (1u32 << cl) as f32;
        let half = 0.5 * size;
        let (hx, hy) = (half / self.wf, half / self.hf);
        let init: f32 = core::iter::empty::<f32>().sum();
        let mut acc = s(init);
        let mut proj = [s(0.0); 16];
        let steps = F::ramp(2.0);
        for (k, &(kx, ky)) in KID.iter().enumerate() {
            let cx = s((2 * qx0 + kx as u32) as f32) + steps;
            let xc = ((cx + s(0.5)) * s(size)) / s(self.wf);
            let yc = s((((2 * qy + ky as u32) as f32 + 0.5) * size) / self.hf);
            let zc = F::zc(kids, k);
            for (m, &(cx, cy)) in CORNER.iter().enumerate() {
                let (dx, dy) = (cx * hx, cy * hy);
                let (px, py, pz) = (xc + s(dx), yc + s(dy), zc + gx[k] * s(dx) + gy[k] * s(dy));
                let v = nnx * px + nny * py + nnz * pz;
                proj[4 * k + m] = v;
                acc = acc + v;
            }
        }
        // `MergeCtx::proxy`.
        let c = acc / s(16.0);
        let mut dm = s(0.0);
        for v in proj {
            dm = (v - c).abs().max_ps(dm);
        }
        let dmax = dm / -nnz;
        let psize = (1u32 << l) as f32;
        let px = F::ramp(1.0);
        let xc = ((s(qx0 as f32) + px + s(0.5)) * s(psize)) / s(self.wf);
        let yc = s(((qy as f32 + 0.5) * psize) / self.hf);
        let zcv = (c - nnx * xc - nny * yc) / nnz;
        let inv = s(-1.0) / nnz;
        // [`Node::plane_with_gradient`] of every lane: the increments `g (2^l / W)`,
        // `g (2^l / H)`, `None` unless `z_c` is finite and `>= 0` and neither increment is
        // NaN; clamped (`maxps` / `minps` are `clamp` for non-NaN values); the caller
        // f16-encodes them as in `leaf_avx2`, rounds `z_c` to 21 bits and adds the tag and
        // flag `O` where a child has it.
        let size = (1u32 << l) as f32;
        let (ex, ey) = (
            (nnx * inv) * s(size / self.wf),
            (nny * inv) * s(size / self.hf),
        );
        let ok_node = zcv
            .finite()
            .and(zcv.ge(s(0.0)))
            .and(ex.ordered())
            .and(ey.ordered())
            .bits();
        let (lo_, hi_) = (s(-F16_MAX), s(F16_MAX));
        let clamp = |e: F| e.max_ps(lo_).min(hi_);
        let (ex, ey) = (clamp(ex), clamp(ey));
        let thr = if self.adaptive {
            // Per lane, the thresholds at the proxy's depth.
            let (zc, min_cos, dmax) = (zcv.to_array(), min_cos.to_array(), dmax.to_array());
            (0..F::N).fold(0u32, |m, p| {
                if valid & (1 << p) == 0 {
                    return m;
                }
                let u = self.depth_fraction(zc[p]);
                let ok = min_cos[p] > self.cos_thr(u) && dmax[p] < self.dist_thr(u);
                m | (u32::from(ok) << p)
            })
        } else {
            // `cos_thr(0)`, `dist_thr(0)`: the fixed thresholds.
            min_cos.gt(s(self.cos_norm)).bits() & dmax.lt(s(self.gamma_dist)).bits()
        };
        Merged {
            mask: valid & thr & ok_node,
            zc: zcv,
            ex,
            ey,
        }
    }
}
