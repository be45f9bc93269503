//! The leaf steps of the 8-wide single-ray traversal (`traverse8.rs`; [`LeafTest8`]: closest,
//! any and all hits). The closest-hit step: the leaf's
//! blocks tested by the 4-lane watertight test, or both blocks of a leaf of five to eight
//! triangles by one 8-lane test (Woop et al. 2013; `tri4.rs`, `lanes8.rs`), the closest hit
//! kept in a [`ClosestCtx`].
//!
//! **One context pointer.** Everything the step reads or updates besides the leaf reference
//! is one [`ClosestCtx`]: the triangle blocks, the prepared ray, the traversal's `t_max`, the
//! closest hit so far and its tie-break limit ([`Best::limit`], kept current when a hit is
//! accepted instead of recomputed per block). Both kernels inline the same generic step
//! ([`ClosestCtx::leaf`]), the AVX2 kernel on `A8` lanes, the portable kernel on `F8`.
//!
//! **The context opaque in the AVX2 kernel.** There the step is inlined with the context
//! passed through `std::hint::black_box`, so the compiler no longer sees the prepared ray's
//! values: they are read from the context in the step, once per leaf. Without it, LLVM hoisted
//! the step's broadcasts of the ray to the kernel's entry and kept them on the stack (a cost
//! per ray, whether or not its leaves needed them); an out-of-line step instead paid a call
//! per leaf (callee-saved registers, the node test's rows read again after it).
//!
//! | query | leaf step in the AVX2 kernel | in the portable kernel |
//! |---|---|---|
//! | closest hit | [`ClosestCtx::leaf`] on `A8`, inlined, context opaque | [`ClosestCtx::leaf`] on `F8`, inlined |
//! | any hit | `Bvh::leaf_any`, inlined (an any-hit ray ends at its first hit leaf) | the same |
//! | all hits | `Bvh::leaf_all`, inlined | the same |
//!
//! **Invariant:** the step computes, block for block, what `Bvh::leaf_closest` computes (the
//! same lane tests under the same limit, hits offered to the same [`Best`]): results are
//! bit-identical to the portable kernel's (`tests/simd_twins.rs`), to the 4-wide tree's and to
//! the scalar test's (the closest hit is the lexicographic minimum of `(t, primitive id)` over the
//! hits in range, whatever order they are offered in).

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::lanes8::Pair8;
use crate::node::{leaf_count, leaf_first};
use crate::stats::Counter;
use crate::traverse::Best;
use crate::tri4::{Tri4, Tri4Ray, blocks_for, lane_mask};
use parallax_core::math::WatertightRay;

/// `t.next_up()`, with a positive finite `t` (every hit of a ray with `t_min >= 0`) as one
/// integer increment of its bits instead of the general NaN / infinity / sign branches.
#[inline(always)]
pub(crate) fn next_up(t: f32) -> f32 {
    let b = t.to_bits();
    // `b - 1 < 0x7f7f_ffff` exactly for `b` in `1..=0x7f7f_ffff`: the positive finite floats.
    if b.wrapping_sub(1) < 0x7f7f_ffff {
        f32::from_bits(b + 1)
    } else {
        t.next_up()
    }
}

/// The closest-hit state of one ray's traversal, behind the one pointer the leaf step takes
/// (module docs).
pub(crate) struct ClosestCtx<'a> {
    pub bvh: &'a Bvh,
    pub r4: &'a Tri4Ray,
    pub best: Best,
    /// The traversal's `t_max`: the ray's, then `best.t` once something was hit.
    pub t_max: f32,
    /// `best.limit(t_max)` for the traversal's current `t_max` (which is `best.t` once
    /// something was hit): updated whenever a hit is accepted.
    limit: f32,
}

impl<'a> ClosestCtx<'a> {
    /// The state for a traversal at `t_max` that already found `best` (`t_max == best.t` if
    /// `best` holds a hit).
    #[inline(always)]
    pub fn new(bvh: &'a Bvh, r4: &'a Tri4Ray, best: Best, t_max: f32) -> Self {
        Self {
            bvh,
            r4,
            best,
            t_max,
            limit: best.limit(t_max),
        }
    }

    /// [`Best::offer`], keeping the limit current.
    #[inline(always)]
    fn offer(&mut self, t: f32, tri: u32, u: f32, v: f32) {
        let b = &self.best;
        if t < b.t || (t == b.t && tri < b.tri) || b.tri == u32::MAX {
            self.best = Best { t, tri, u, v };
            self.t_max = t;
            self.limit = next_up(t);
        }
    }

    /// Block `i` of the triangle array.
    #[inline(always)]
    fn block(&self, i: u32) -> &'a Tri4 {
        let blocks = &self.bvh.blocks;
        debug_assert!((i as usize) < blocks.len());
        // SAFETY: leaf references index their blocks (build invariant, as node references
        // index the node array; refit keeps the topology).
        unsafe { blocks.get_unchecked(i as usize) }
    }

    /// Lane `l` of `b` left to the scalar test (an exactly-zero edge function), as
    /// `traverse.rs`' `offer_exact`.
    #[inline(always)]
    fn offer_exact(&mut self, b: &Tri4, l: usize) {
        let (p0, p1, p2) = (b.vertex(l, 0), b.vertex(l, 1), b.vertex(l, 2));
        if let Some(h) = self.r4.wt.intersect_within(p0, p1, p2, self.limit) {
            self.offer(h.t, b.tri[l], h.u, h.v);
        }
    }

    /// The closest-hit step of leaf reference `leaf` (may shrink `t_max`). Lanes `L` for the
    /// two-block test (`lanes8.rs`). One block (up to four triangles) and two blocks (five
    /// to eight) are tested without a loop, their lane masks `(1 << count) - 1` (the masks
    /// of `lane_mask` side by side); larger leaves (only with `max_leaf_size > 8`) block by
    /// block, as is an empty leaf.
    #[inline(always)]
    pub fn leaf<C: Counter, L: Pair8>(&mut self, leaf: u32, stats: &mut C) {
        let (first, count) = (leaf_first(leaf), leaf_count(leaf));
        // `count - 1` wraps for an empty leaf, which takes the (empty) block loop.
        if count.wrapping_sub(1) < 4 {
            self.block4(self.block(first), (1 << count) - 1, stats);
        } else if count.wrapping_sub(1) < 8 {
            self.pair::<C, L>(first, (1 << count) - 1, stats);
        } else {
            for k in 0..blocks_for(count) {
                self.block4(self.block(first + k), lane_mask(count, k), stats);
            }
        }
    }

    /// The lanes `mask` (eight bits) of blocks `first` and `first + 1` in one 8-lane test.
    #[inline(always)]
    fn pair<C: Counter, L: Pair8>(&mut self, first: u32, mask: u32, stats: &mut C) {
        let (b0, b1) = (self.block(first), self.block(first + 1));
        let h = self.r4.intersect2::<L>(b0, b1, mask, self.limit);
        stats.triangles(mask, h.hit);
        let mut m = h.hit;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let b = if l < 4 { b0 } else { b1 };
            self.offer(h.t[l], b.tri[l & 3], h.u[l], h.v[l]);
        }
        let mut m = h.exact;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            self.offer_exact(if l < 4 { b0 } else { b1 }, l & 3);
        }
    }

    /// The lanes `mask` (four bits) of block `b` in one 4-lane test.
    #[inline(always)]
    fn block4<C: Counter>(&mut self, b: &Tri4, mask: u32, stats: &mut C) {
        let h = self.r4.intersect(b, mask, self.limit);
        stats.triangles(mask, h.hit);
        if h.hit != 0 {
            let (t, u, v) = (h.t.to_array(), h.u.to_array(), h.v.to_array());
            let mut m = h.hit;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                self.offer(t[l], b.tri[l], u[l], v[l]);
            }
        }
        let mut m = h.exact;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            self.offer_exact(b, l);
        }
    }
}

/// The leaf step of `Bvh::traverse8`: a struct with an `#[inline(always)]` method, not a
/// closure, so that it inlines into the AVX2 traversal and is compiled with its target features
/// (closures do not inherit them, and a leaf closure became an out-of-line SSE call per leaf).
pub(crate) trait LeafTest8<C: Counter> {
    /// Tests the leaf of reference `leaf`, may shrink `t_max`; `true` stops the traversal.
    fn test(&mut self, bvh: &Bvh, leaf: u32, t_max: &mut f32, stats: &mut C) -> bool;
}

/// Closest hit: keeps the lexicographic minimum of `(t, primitive id)` and the traversal's
/// `t_max` in `ctx`.
pub(crate) struct ClosestLeaf<'a, T> {
    /// The node test, whose kernel's leaf step this runs (`NodeTest8::leaf_closest`; the
    /// `LeafTest8` implementation is in `traverse8.rs`).
    pub nt: &'a T,
    pub ctx: ClosestCtx<'a>,
}

/// Any hit: stops at the first hit.
pub(crate) struct AnyLeaf {
    pub r4: Tri4Ray,
    pub found: bool,
}

impl<C: Counter> LeafTest8<C> for AnyLeaf {
    #[inline(always)]
    fn test(&mut self, bvh: &Bvh, leaf: u32, t_max: &mut f32, stats: &mut C) -> bool {
        let (first, count) = (leaf_first(leaf), leaf_count(leaf));
        self.found = bvh.leaf_any(&self.r4, first, count, *t_max, stats);
        self.found
    }
}

/// All hits: appends every hit to `out`.
pub(crate) struct AllLeaf<'a> {
    pub wt: WatertightRay,
    pub out: &'a mut Vec<Hit>,
}

impl<C: Counter> LeafTest8<C> for AllLeaf<'_> {
    #[inline(always)]
    fn test(&mut self, bvh: &Bvh, leaf: u32, _: &mut f32, stats: &mut C) -> bool {
        let (first, count) = (leaf_first(leaf), leaf_count(leaf));
        bvh.leaf_all(&self.wt, first, count, self.out, stats);
        false
    }
}

#[cfg(test)]
mod tests {
    /// `next_up` is `f32::next_up` on zeros, subnormals, normals, the largest finite value,
    /// infinities, NaN and negatives, and on a sweep of bit patterns.
    #[test]
    fn next_up_matches_std() {
        let special = [
            0.0,
            -0.0,
            f32::from_bits(1),
            f32::MIN_POSITIVE,
            1.0,
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -1.0,
            -f32::from_bits(1),
        ];
        let sweep = (0..=u32::MAX).step_by(65_521).map(f32::from_bits);
        let mut fast = 0;
        for t in special.into_iter().chain(sweep) {
            assert_eq!(super::next_up(t).to_bits(), t.next_up().to_bits(), "{t:e}");
            fast += (t > 0.0 && t.is_finite()) as u32;
        }
        assert!(fast > 1000, "{fast}");
    }
}
