//! The AVX2 single-ray kernel's closest-hit leaf step (`traverse8.rs`), compiled out of line:
//! the leaf's blocks tested by the 4-lane watertight test, or both blocks of a leaf of five to
//! eight triangles by one 8-lane test (Woop et al. 2013; `tri4.rs`, `lanes8.rs`).
//!
//! Why out of line: inlined into the traversal loop, the leaf step's many live values took the
//! vector and general registers, and the node loop (~12 nodes per bounce ray against ~2.4
//! leaves) reloaded its six broadcast ray rows (`org`, `-1 / dir`) and six plane offsets from
//! the stack at every node. As a call, the loop keeps them in registers and saves them around
//! the call instead, once per leaf (all vector registers are caller-saved in the System V
//! ABI). The function carries the kernel's target features (`avx2,popcnt`), so its 8-lane test
//! is the AVX2 `A8` and its 4-lane test SSE, the same instructions as when inlined.
//!
//! | query | leaf step in the AVX2 kernel | in the portable kernel |
//! |---|---|---|
//! | closest hit | [`leaf_closest8_avx2`] (a call) | `Bvh::leaf_closest8` on `F8`, inlined |
//! | any hit | `Bvh::leaf_any`, inlined (a call measured slower: an any-hit ray ends at its first hit leaf) | the same |
//! | all hits | `Bvh::leaf_all`, inlined | the same |
//!
//! **Invariant:** the call computes exactly what the inlined step computed (the same function,
//! `Bvh::leaf_closest8::<_, A8>`): results are bit-identical to the portable kernel's
//! (`tests/simd_twins.rs`) and to the 4-wide tree's.

use crate::bvh::Bvh;
use crate::stats::Counter;
use crate::traverse::Best;
use crate::tri4::Tri4Ray;

/// The AVX2 kernel's closest-hit leaf step: [`Bvh::leaf_closest8`] on `A8` lanes, out of line
/// (module docs).
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
