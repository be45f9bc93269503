//! Leaf steps of the 8-wide single-ray traversal (`traverse8.rs`): any hit over the two
//! blocks of a leaf in one 8-lane watertight test (Woop et al. 2013, `tri4.rs`), and the AVX2
//! kernel's closest-hit step compiled out of line.
//!
//! Why out of line: inlined into the traversal loop, the leaf step's many live values took
//! the vector and general registers, and the node loop (~12 nodes per bounce ray against ~2.4
//! leaves) then reloaded its six broadcast ray rows and six plane offsets from the stack at
//! every node. As a call, the registers are saved around the call instead, once per leaf. The
//! function carries the kernel's target features (`avx2,popcnt`), so its lanes are the AVX2
//! `A8` (`lanes8.rs`) and the 4-lane blocks SSE, exactly as when inlined.
//!
//! | function | lanes | used by |
//! |---|---|---|
//! | [`Bvh::leaf_any8`] | generic [`Pair8`] | both kernels' any-hit step (inlined) |
//! | `leaf_closest8_avx2` | `A8` | the AVX2 closest-hit step (a call) |
//!
//! The any-hit step stays inlined: a call per leaf measured slower there (an any-hit ray stops
//! at its first hit leaf, so the node loop gains less per call; notes: docs/notes/bvh.md).
//!
//! **Invariant:** results are those of the 4-lane block loops of `traverse.rs`
//! ([`Bvh::leaf_closest`], [`Bvh::leaf_any`]): the pair test computes, lane by lane, the bits of
//! the two block tests (`tri4.rs`), and any hit of a leaf is the same set of lanes whichever
//! order they are tested in (only the work counters of a leaf whose first block hits differ:
//! the pair test counts both blocks' triangles).

use crate::bvh::Bvh;
use crate::lanes8::Pair8;
use crate::stats::Counter;
use crate::tri4::{Tri4Ray, blocks_for, lane_mask};

#[cfg(target_arch = "x86_64")]
use crate::traverse::Best;

impl Bvh {
    /// [`Self::leaf_any`] with the two blocks of a leaf of five to eight triangles in one
    /// 8-lane test ([`Tri4Ray::intersect2`], lanes `L`, limit `t_max` for both blocks as in
    /// the block loop), then its exact-zero lanes by the scalar test.
    #[inline(always)]
    pub(crate) fn leaf_any8<C: Counter, L: Pair8>(
        &self,
        r4: &Tri4Ray,
        first: u32,
        count: u32,
        t_max: f32,
        stats: &mut C,
    ) -> bool {
        if blocks_for(count) != 2 {
            return self.leaf_any(r4, first, count, t_max, stats);
        }
        let (b0, b1) = (
            &self.blocks[first as usize],
            &self.blocks[first as usize + 1],
        );
        let mask = lane_mask(count, 0) | lane_mask(count, 1) << 4;
        let h = r4.intersect2::<L>(b0, b1, mask, t_max);
        for l in 0..8 {
            if mask >> l & 1 != 0 {
                stats.triangle(h.hit >> l & 1 != 0);
            }
        }
        if h.hit != 0 {
            return true;
        }
        let mut m = h.exact;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let b = if l < 4 { b0 } else { b1 };
            let (p0, p1, p2) = (b.vertex(l & 3, 0), b.vertex(l & 3, 1), b.vertex(l & 3, 2));
            if r4.wt.intersect_within(p0, p1, p2, t_max).is_some() {
                return true;
            }
        }
        false
    }
}

/// The AVX2 kernel's closest-hit leaf step ([`Bvh::leaf_closest8`] on `A8` lanes), out of
/// line (module docs).
///
/// # Safety
/// The CPU must support AVX2 and POPCNT.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,popcnt")]
#[inline(never)]
pub(crate) unsafe fn leaf_closest8_avx2<C: Counter>(
    bvh: &Bvh,
    r4: &Tri4Ray,
    first: u32,
    count: u32,
    t_max: &mut f32,
    best: &mut Best,
    stats: &mut C,
) {
    bvh.leaf_closest8::<C, crate::lanes8::A8>(r4, first, count, t_max, best, stats);
}
