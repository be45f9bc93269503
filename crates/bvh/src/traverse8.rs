//! Single-ray traversal of the 8-wide tree ([`crate::node8`]): closest hit, any hit, all hits.
//!
//! The loop is that of `traverse.rs` (explicit stack of `t_bits << 32 | child` keys, nearest
//! child first, pops culled against the closest hit; Wald et al. 2014 §4), with one 8-lane slab
//! test per node: AVX2 (one 256-bit register per plane row) behind runtime detection, and a
//! portable twin on two 4-lane halves (glam `Vec4`: SSE2 on x86_64) that the tests hold the
//! AVX2 path against. Both compute, lane by lane, the same IEEE operations as the 4-wide test:
//!
//! ```text
//! t_near = max(t_min, (near_x - o_x) * inv_x, (near_y - o_y) * inv_y, (near_z - o_z) * inv_z)
//! t_far  = min(t_max, (far_x - o_x) * inv_x, ...) * (1 + 2 gamma(3))     (Ize 2013, robust)
//! hit    = t_near <= t_far
//! ```
//!
//! computed as `(o_x - near_x) * (-inv_x)`: negation is exact and IEEE subtraction and
//! multiplication are sign-symmetric, so every product is the same value (a zero product may
//! have the other sign; `max(x, acc)` returns `acc` on equal zeros, so `t_near` is
//! bit-identical whenever `t_min >= 0`, and the hit mask always is), while the bounds row
//! becomes the memory operand of the subtraction (one load instruction fewer per row).
//!
//! (`vmaxps` / `vminps` return the second operand when one is NaN, exactly as `maxps` /
//! `minps`, so a ray on a slab plane with a zero direction component is handled as in
//! `simd.rs`). No FMA: `(b - o) * inv` rounds twice, each a relative error, which the far
//! scaling covers; Embree's `b * inv - o * inv` has an absolute error in `o * inv` that it does
//! not (notes: docs/notes/bvh.md). Leaves are the shared 4-triangle blocks (`tri4.rs`), tested
//! by a `LeafTest8` step (`leaf8.rs`; a trait, not a closure, so that it inlines into the AVX2
//! kernel with its target features). Hit children are ordered by `u64` keys compressed to the
//! hit lanes (`keys8.rs`: branch-free with AVX2), only for nodes with two or more hit children:
//! two by one compare (their two keys read directly, `keys8::pair_keys`), three or four by a
//! 5-comparator network, more by insertion sort.
//!
//! **Invariant:** every query returns exactly what its 4-wide twin returns
//! ([`Bvh::closest_hit4`], ...): the node test only culls (conservatively), and the closest hit
//! is the lexicographic minimum of `(t, triangle index)` whatever the visiting order.

use std::mem::MaybeUninit;

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::{ROBUST_FAR_SCALE, WatertightRay};

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::keys8;
use crate::lanes8::Pair8;
use crate::leaf8::{AllLeaf, AnyLeaf, ClosestCtx, ClosestLeaf, LeafTest8};
use crate::node::{is_leaf, leaf_first};
use crate::node8::Node8;
use crate::stats::{Counter, NoStats, TraversalStats};
use crate::traverse::{Best, pop_closer, ray_ok, sort_dedup_hits};
use crate::tri4::Tri4Ray;
use parallax_core::simd::{max_or_rhs, min_or_rhs};

/// Stack entries of the 8-wide traversal: a node pushes at most 7, and the build checks
/// `7 * depth8 < STACK8_SIZE`.
pub(crate) const STACK8_SIZE: usize = 576;

/// A ray prepared for the 8-lane slab test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes8 {
    org: [f32; 3],
    /// `-1 / dir`: the slab distances are `(o - b) * (-1 / d)`, equal to `(b - o) * (1 / d)`
    /// (negation is exact), with the bounds row as the subtraction's memory operand.
    neg_inv: [f32; 3],
    /// Byte offsets into `Node8::bounds` of the near / far plane rows (`32 * (2 axis + sign)`).
    near: [usize; 3],
    far: [usize; 3],
    t_min: f32,
}

impl RayBoxes8 {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        // 1 / ±0 = ±inf; 0 * inf = NaN is ignored by the min / max order (module docs). The
        // three reciprocals as one 4-lane division (`Vec3A`), their signs as one lane mask.
        let inv = glam::Vec3A::from(ray.dir).recip();
        let m = inv.is_negative_bitmask() as usize;
        let (sx, sy, sz) = (m & 1, (m >> 1) & 1, (m >> 2) & 1);
        Self {
            org: ray.origin.to_array(),
            neg_inv: (-inv).to_array(),
            near: [32 * sx, 32 * (2 + sy), 32 * (4 + sz)],
            far: [32 * (1 - sx), 32 * (3 - sy), 32 * (5 - sz)],
            t_min: ray.t_min,
        }
    }
}

/// An 8-lane slab test: the hit mask (bit i = lane i) and the entry distances (`Dist`, in
/// registers where the test has them), then, only for nodes with two or more hit children
/// (the child references are the node's fourth cache line), the stack keys of the hit lanes,
/// `t_near bits << 32 | child`, compressed: entry `j < mask.count_ones()` is the key of the
/// `j`-th hit lane in lane order, the other entries are `0`. The distances of hit lanes are
/// `>= t_min`, so their bits order as the floats where `t_min >= 0`; a key is never `0`
/// (child `0` is the root, no node's child), so the padding sorts below every key.
pub(crate) trait NodeTest8 {
    type Dist: Copy;
    /// The lanes of the closest-hit leaf step's two-block triangle test (`lanes8.rs`): AVX2
    /// where the node test is, the portable twin elsewhere.
    type Pair: Pair8;
    fn test(&self, node: &Node8, t_max: f32) -> (u32, Self::Dist);
    fn hit_keys(&self, node: &Node8, t: Self::Dist, mask: u32) -> [u64; 8];
    /// The keys of the two hit lanes of a two-bit `mask`, in lane order (`hit_keys`' first two
    /// entries).
    fn pair_keys(&self, node: &Node8, t: Self::Dist, mask: u32) -> (u64, u64);

    /// The ray prepared for this kernel's triangle tests: `Tri4Ray::new(WatertightRay::new(ray))`
    /// or a bit-identical register form of it.
    #[inline(always)]
    fn tri_ray(&self, ray: &Ray) -> Tri4Ray {
        Tri4Ray::new(WatertightRay::new(ray))
    }

    /// The closest-hit leaf step of this test's kernel ([`ClosestCtx::leaf`] on
    /// [`Self::Pair`] lanes) for leaf reference `leaf`. Inlined by default.
    #[inline(always)]
    fn leaf_closest<C: Counter>(&self, ctx: &mut ClosestCtx, leaf: u32, stats: &mut C) {
        ctx.leaf::<C, Self::Pair>(leaf, stats)
    }
}

/// The portable twin: two 4-lane halves.
pub(crate) struct Portable8(pub RayBoxes8);

impl NodeTest8 for Portable8 {
    type Dist = [f32; 8];
    type Pair = parallax_core::simd::F8;

    #[inline(always)]
    fn hit_keys(&self, node: &Node8, t: [f32; 8], mask: u32) -> [u64; 8] {
        keys8::compress_keys(t, &node.child, mask)
    }

    #[inline(always)]
    fn pair_keys(&self, node: &Node8, t: [f32; 8], mask: u32) -> (u64, u64) {
        keys8::pair_keys(&t, &node.child, mask)
    }

    #[inline(always)]
    fn test(&self, node: &Node8, t_max: f32) -> (u32, [f32; 8]) {
        let rb = &self.0;
        let base = node.bounds.as_ptr() as *const u8;
        let mut mask = 0;
        let mut t = [0.0f32; 8];
        for h in 0..2 {
            // SAFETY: offsets are `32 * i + 16 * h` with `i < 6`, inside `bounds: [[f32; 8]; 6]`.
            let b = |off: usize| unsafe {
                Vec4::from_slice(std::slice::from_raw_parts(
                    base.add(off + 16 * h) as *const f32,
                    4,
                ))
            };
            let o = rb.org.map(Vec4::splat);
            let i = rb.neg_inv.map(Vec4::splat);
            let tnx = (o[0] - b(rb.near[0])) * i[0];
            let tny = (o[1] - b(rb.near[1])) * i[1];
            let tnz = (o[2] - b(rb.near[2])) * i[2];
            let tfx = (o[0] - b(rb.far[0])) * i[0];
            let tfy = (o[1] - b(rb.far[1])) * i[1];
            let tfz = (o[2] - b(rb.far[2])) * i[2];
            let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, Vec4::splat(rb.t_min))));
            let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, Vec4::splat(t_max))));
            let t_far = t_far * ROBUST_FAR_SCALE;
            let hit = t_near.cmple(t_far);
            mask |= hit.bitmask() << (4 * h);
            t[4 * h..4 * h + 4].copy_from_slice(&t_near.to_array());
        }
        (mask, t)
    }
}

/// The AVX2 node test (construct only after detecting AVX2): the plane offsets and `t_min`
/// of [`RayBoxes8`] and its origin and `-1 / dir` broadcast to rows.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx2Boxes8 {
    near: [usize; 3],
    far: [usize; 3],
    t_min: f32,
    org: [std::arch::x86_64::__m256; 3],
    /// `-1 / dir` ([`RayBoxes8`]).
    inv: [std::arch::x86_64::__m256; 3],
}

#[cfg(target_arch = "x86_64")]
impl Avx2Boxes8 {
    /// # Safety
    /// The CPU must support AVX2.
    #[inline(always)]
    pub unsafe fn new(rb: RayBoxes8) -> Self {
        use std::arch::x86_64::*;
        // SAFETY: AVX is available (caller).
        unsafe {
            let [ox, oy, oz] = rb.org;
            let [ix, iy, iz] = rb.neg_inv;
            Self {
                org: [_mm256_set1_ps(ox), _mm256_set1_ps(oy), _mm256_set1_ps(oz)],
                inv: [_mm256_set1_ps(ix), _mm256_set1_ps(iy), _mm256_set1_ps(iz)],
                near: rb.near,
                far: rb.far,
                t_min: rb.t_min,
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl NodeTest8 for Avx2Boxes8 {
    type Dist = std::arch::x86_64::__m256;
    type Pair = crate::lanes8::A8;

    #[inline(always)]
    fn hit_keys(&self, node: &Node8, t_near: Self::Dist, mask: u32) -> [u64; 8] {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { keys8::compress_keys_avx2(t_near, &node.child, mask) }
    }

    #[inline(always)]
    fn pair_keys(&self, node: &Node8, t_near: Self::Dist, mask: u32) -> (u64, u64) {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { keys8::pair_keys_avx2(t_near, &node.child, mask) }
    }

    #[inline(always)]
    fn tri_ray(&self, ray: &Ray) -> Tri4Ray {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { Tri4Ray::new_avx2(ray) }
    }

    #[inline(always)]
    fn leaf_closest<C: Counter>(&self, ctx: &mut ClosestCtx, leaf: u32, stats: &mut C) {
        // Inlined with the context opaque (module docs of `leaf8.rs`): the ray values are read
        // in the step, not hoisted to the kernel entry.
        let ctx = std::hint::black_box(ctx);
        ctx.leaf::<C, crate::lanes8::A8>(leaf, stats)
    }

    #[inline(always)]
    fn test(&self, node: &Node8, t_max: f32) -> (u32, Self::Dist) {
        use std::arch::x86_64::*;
        let rb = self;
        let base = node.bounds.as_ptr() as *const u8;
        // SAFETY: a value of this type exists only where AVX2 was detected (`new`); loads are
        // 32-byte aligned rows of the 64-byte aligned node at offsets `32 * i`, `i < 6`.
        unsafe {
            // A macro, not a closure: closures do not inherit the caller's target features.
            macro_rules! b {
                ($off:expr) => {
                    _mm256_load_ps(base.add($off) as *const f32)
                };
            }
            let (o, i) = (&self.org, &self.inv);
            let tnx = _mm256_mul_ps(_mm256_sub_ps(o[0], b!(rb.near[0])), i[0]);
            let tny = _mm256_mul_ps(_mm256_sub_ps(o[1], b!(rb.near[1])), i[1]);
            let tnz = _mm256_mul_ps(_mm256_sub_ps(o[2], b!(rb.near[2])), i[2]);
            let tfx = _mm256_mul_ps(_mm256_sub_ps(o[0], b!(rb.far[0])), i[0]);
            let tfy = _mm256_mul_ps(_mm256_sub_ps(o[1], b!(rb.far[1])), i[1]);
            let tfz = _mm256_mul_ps(_mm256_sub_ps(o[2], b!(rb.far[2])), i[2]);
            let t_near = _mm256_max_ps(
                tnz,
                _mm256_max_ps(tny, _mm256_max_ps(tnx, _mm256_set1_ps(rb.t_min))),
            );
            let t_far = _mm256_min_ps(
                tfz,
                _mm256_min_ps(tfy, _mm256_min_ps(tfx, _mm256_set1_ps(t_max))),
            );
            let t_far = _mm256_mul_ps(t_far, _mm256_set1_ps(ROBUST_FAR_SCALE));
            let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far);
            (_mm256_movemask_ps(hit) as u32, t_near)
        }
    }
}

/// Whether the traversal prefetches the blocks of hit leaf children (notes: docs/notes/bvh.md).
const PREFETCH_LEAVES: bool = true;

/// Whether the traversal prefetches a node's child references (its fourth cache line) as it
/// enters the node, so that a miss on that line overlaps the slab test instead of following it
/// (the references are read only once the hit mask is known).
const PREFETCH_CHILD_LINE: bool = true;

/// Prefetches the cache line of `node.child` (a hint: never faults, changes no result).
#[inline(always)]
fn prefetch_child_line(node: &Node8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: prefetches never fault; the address is inside `node`.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(node.child.as_ptr() as *const i8);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = node;
}

impl<C: Counter, T: NodeTest8> LeafTest8<C> for ClosestLeaf<'_, T> {
    #[inline(always)]
    fn test(&mut self, _: &Bvh, leaf: u32, t_max: &mut f32, stats: &mut C) -> bool {
        self.nt.leaf_closest(&mut self.ctx, leaf, stats);
        *t_max = self.ctx.t_max;
        false
    }
}

impl Bvh {
    /// Prefetches the first three cache lines of the triangle block of each hit leaf lane
    /// (`Node8::leaf_mask`).
    #[inline(always)]
    fn prefetch_leaves(&self, node: &Node8, mask: u32) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let mut m = mask & node.leaf_mask;
            while m != 0 {
                let c = m.trailing_zeros() as usize;
                m &= m - 1;
                let r = node.child[c];
                debug_assert!(is_leaf(r));
                let b = self.blocks.as_ptr().wrapping_add(leaf_first(r) as usize) as *const i8;
                // SAFETY: prefetches never fault; the address is only a hint.
                unsafe {
                    _mm_prefetch::<_MM_HINT_T0>(b);
                    _mm_prefetch::<_MM_HINT_T0>(b.wrapping_add(64));
                    _mm_prefetch::<_MM_HINT_T0>(b.wrapping_add(128));
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (node, mask);
    }

    /// The 8-wide traversal kernel (the 4-wide `traverse` with eight lanes): `leaf.test(bvh,
    /// leaf, t_max, stats)` tests the leaf of reference `leaf`, may shrink `t_max`, returns
    /// `true` to stop. With
    /// `ORDERED`, hit children are visited near-to-far (two: one compare; three or four: a
    /// 5-comparator network on the compressed keys; more: insertion sort), otherwise in lane
    /// order.
    #[inline(always)]
    fn traverse8<C: Counter, T: NodeTest8, L: LeafTest8<C>, const ORDERED: bool>(
        &self,
        nt: &T,
        root: u32,
        mut t_max: f32,
        stats: &mut C,
        leaf: &mut L,
    ) {
        let mut stack = [MaybeUninit::<u64>::uninit(); STACK8_SIZE];
        let mut sp = 0usize;
        let mut cur = root;
        let nodes = self.nodes8.as_ptr();
        loop {
            while !is_leaf(cur) {
                debug_assert!((cur as usize) < self.nodes8.len());
                // SAFETY: inner child references index the node array (build invariant).
                let node = unsafe { &*nodes.add(cur as usize) };
                stats.node(node.num_children);
                if PREFETCH_CHILD_LINE {
                    prefetch_child_line(node);
                }
                let (mask, dist) = nt.test(node, t_max);
                if mask != 0 {
                    // Leaf children come first (`node8.rs`): start the loads of the hit leaves'
                    // triangle blocks now, so their misses overlap the work until they are
                    // tested.
                    if PREFETCH_LEAVES {
                        self.prefetch_leaves(node, mask);
                    }
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    let n = mask.count_ones() as usize;
                    if ORDERED && n == 2 {
                        // SAFETY (this store and those below): a node pushes at most 7
                        // entries and writes at most 8 slots from `sp`, `sp + 8 <= 7 * depth8 +
                        // 1 < STACK8_SIZE` (checked at build); the entries above the first
                        // `n - 1` are overwritten by later pushes. `n - 1 < 8` indexes `ks`.
                        let (a, b) = nt.pair_keys(node, dist, mask);
                        unsafe { *stack.get_unchecked_mut(sp) = MaybeUninit::new(a.max(b)) };
                        sp += 1;
                        cur = a.min(b) as u32;
                        continue;
                    }
                    // Otherwise the hit keys compressed into `ks` (padding `0`).
                    let mut ks = nt.hit_keys(node, dist, mask);
                    if !ORDERED {
                        for (i, &k) in ks[1..].iter().enumerate() {
                            unsafe { *stack.get_unchecked_mut(sp + i) = MaybeUninit::new(k) };
                        }
                        sp += n - 1;
                        cur = ks[0] as u32;
                        continue;
                    }
                    // Far to near (the padding `0` sorts last), push all but the nearest.
                    let sort2 = |ks: &mut [u64; 8], i: usize, j: usize| {
                        let (x, y) = (ks[i], ks[j]);
                        ks[i] = x.max(y);
                        ks[j] = x.min(y);
                    };
                    if n <= 4 {
                        // Three or four: a 5-comparator network.
                        sort2(&mut ks, 0, 1);
                        sort2(&mut ks, 2, 3);
                        sort2(&mut ks, 0, 2);
                        sort2(&mut ks, 1, 3);
                        sort2(&mut ks, 1, 2);
                        for (i, &k) in ks[..3].iter().enumerate() {
                            unsafe { *stack.get_unchecked_mut(sp + i) = MaybeUninit::new(k) };
                        }
                    } else {
                        // Five to eight: insertion sort.
                        for i in 1..n {
                            let k = ks[i];
                            let mut j = i;
                            while j > 0 && ks[j - 1] < k {
                                ks[j] = ks[j - 1];
                                j -= 1;
                            }
                            ks[j] = k;
                        }
                        // All eight slots (no length-dependent copy: that became a `memcpy`).
                        for (i, &k) in ks.iter().enumerate() {
                            unsafe { *stack.get_unchecked_mut(sp + i) = MaybeUninit::new(k) };
                        }
                    }
                    sp += n - 1;
                    cur = unsafe { *ks.get_unchecked(n - 1) } as u32;
                    continue;
                }
                match pop_closer(&stack, &mut sp, t_max) {
                    Some(next) => cur = next,
                    None => return,
                }
            }
            stats.leaf();
            if leaf.test(self, cur, &mut t_max, stats) {
                return;
            }
            match pop_closer(&stack, &mut sp, t_max) {
                Some(next) => cur = next,
                None => return,
            }
        }
    }

    #[inline(always)]
    fn closest8<C: Counter, T: NodeTest8>(&self, nt: &T, ray: &Ray, stats: &mut C) -> Option<Hit> {
        let r4 = nt.tri_ray(ray);
        let mut best = Best::new();
        let mut t_max = ray.t_max;
        self.closest8_from(nt, &r4, 0, &mut t_max, &mut best, stats);
        best.hit()
    }

    /// The closest-hit traversal of the subtree `root` (an inner node or a leaf reference),
    /// continuing from the closest hit `best` at `t_max` (the packet traversal hands rays over
    /// to it when few remain active).
    #[inline(always)]
    pub(crate) fn closest8_from<C: Counter, T: NodeTest8>(
        &self,
        nt: &T,
        r4: &Tri4Ray,
        root: u32,
        t_max: &mut f32,
        best: &mut Best,
        stats: &mut C,
    ) {
        let mut leaf = ClosestLeaf {
            nt,
            ctx: ClosestCtx::new(self, r4, *best, *t_max),
        };
        self.traverse8::<C, T, _, true>(nt, root, *t_max, stats, &mut leaf);
        *t_max = leaf.ctx.t_max;
        *best = leaf.ctx.best;
    }

    #[inline(always)]
    fn any8<C: Counter, T: NodeTest8>(&self, nt: &T, ray: &Ray, stats: &mut C) -> bool {
        let mut leaf = AnyLeaf {
            r4: nt.tri_ray(ray),
            found: false,
        };
        self.traverse8::<C, T, _, false>(nt, 0, ray.t_max, stats, &mut leaf);
        leaf.found
    }

    #[inline(always)]
    fn all8<C: Counter, T: NodeTest8>(&self, nt: &T, ray: &Ray, out: &mut Vec<Hit>, stats: &mut C) {
        let mut leaf = AllLeaf {
            wt: WatertightRay::new(ray),
            out,
        };
        self.traverse8::<C, T, _, false>(nt, 0, ray.t_max, stats, &mut leaf);
        sort_dedup_hits(leaf.out);
    }
}

impl Bvh {
    #[inline]
    fn closest_hit8<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        stats.ray();
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.closest8_avx2(ray, stats) };
        }
        self.closest8_portable(ray, stats)
    }

    /// The portable kernel, out of line so that the dispatch above stays a small function
    /// (inlined, its 5.5 KB stack frame and spills were paid on the AVX2 path too).
    #[inline(never)]
    fn closest8_portable<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        self.closest8(&Portable8(RayBoxes8::new(ray)), ray, stats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt,bmi1")]
    #[inline]
    unsafe fn closest8_avx2<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        // SAFETY: AVX2 is enabled for this function (the caller detected it).
        let nt = unsafe { Avx2Boxes8::new(RayBoxes8::new(ray)) };
        self.closest8(&nt, ray, stats)
    }

    #[inline(never)]
    fn closest8_portable_nostats(&self, ray: &Ray) -> Option<Hit> {
        self.closest8(&Portable8(RayBoxes8::new(ray)), ray, &mut NoStats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt,bmi1")]
    unsafe fn closest8_avx2_nostats(&self, ray: &Ray) -> Option<Hit> {
        // SAFETY: AVX2 is enabled for this function (the caller detected it).
        unsafe { self.closest8_avx2(ray, &mut NoStats) }
    }

    #[inline]
    fn any_hit8<C: Counter>(&self, ray: &Ray, stats: &mut C) -> bool {
        stats.ray();
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return false;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.any8_avx2(ray, stats) };
        }
        self.any8_portable(ray, stats)
    }

    /// The portable kernel, out of line (as [`Self::closest8_portable`]).
    #[inline(never)]
    fn any8_portable<C: Counter>(&self, ray: &Ray, stats: &mut C) -> bool {
        self.any8(&Portable8(RayBoxes8::new(ray)), ray, stats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt")]
    unsafe fn any8_avx2<C: Counter>(&self, ray: &Ray, stats: &mut C) -> bool {
        // SAFETY: AVX2 is enabled for this function (the caller detected it).
        let nt = unsafe { Avx2Boxes8::new(RayBoxes8::new(ray)) };
        self.any8(&nt, ray, stats)
    }

    #[inline]
    fn all_hits8<C: Counter>(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut C) {
        out.clear();
        stats.ray();
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.all8_avx2(ray, out, stats) };
        }
        self.all8_portable(ray, out, stats)
    }

    /// The portable kernel, out of line (as [`Self::closest8_portable`]).
    #[inline(never)]
    fn all8_portable<C: Counter>(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut C) {
        self.all8(&Portable8(RayBoxes8::new(ray)), ray, out, stats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,popcnt")]
    unsafe fn all8_avx2<C: Counter>(&self, ray: &Ray, out: &mut Vec<Hit>, s: &mut C) {
        // SAFETY: AVX2 is enabled for this function (the caller detected it).
        let nt = unsafe { Avx2Boxes8::new(RayBoxes8::new(ray)) };
        self.all8(&nt, ray, out, s)
    }

    /// The closest intersection with `ray` in `(t_min, t_max)`, or `None`. Both faces of a
    /// triangle are hit. Invalid rays (non-finite, zero direction) hit nothing. Exact ties in
    /// `t` go to the lower index in [`Bvh::triangles`] (with spatial splits: to one of the
    /// tied triangles, [`BuildOptions`](crate::BuildOptions)). Traverses the 8-wide tree (AVX2 node
    /// test where the CPU has it).
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        // `closest_hit8` without a stats argument: no frame for it here, the kernel a tail call.
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.closest8_avx2_nostats(ray) };
        }
        self.closest8_portable_nostats(ray)
    }

    /// [`Self::closest_hit`], adding the work done (8-wide nodes) to `stats`.
    pub fn closest_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        self.closest_hit8(ray, stats)
    }

    /// [`Self::closest_hit`] with the portable node test even where AVX2 exists: the twin the
    /// tests hold the AVX2 path against.
    pub fn closest_hit8_portable(&self, ray: &Ray) -> Option<Hit> {
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        self.closest8(&Portable8(RayBoxes8::new(ray)), ray, &mut NoStats)
    }

    /// Whether anything intersects `ray` in `(t_min, t_max)` (occlusion / shadow rays). Stops
    /// at the first hit found, in no particular order.
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_hit8(ray, &mut NoStats)
    }

    /// [`Self::any_hit`], adding the work done to `stats`.
    pub fn any_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.any_hit8(ray, stats)
    }

    /// [`Self::any_hit`] with the portable node test (the twin of the AVX2 path).
    pub fn any_hit8_portable(&self, ray: &Ray) -> bool {
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return false;
        }
        self.any8(&Portable8(RayBoxes8::new(ray)), ray, &mut NoStats)
    }

    /// Every intersection with `ray` in `(t_min, t_max)`, sorted by `t` (ties by primitive).
    /// `out` is cleared first; it only allocates when it must grow. With the watertight test's
    /// tie-break, a ray through a shared edge or vertex of a closed mesh is reported once.
    pub fn all_hits(&self, ray: &Ray, out: &mut Vec<Hit>) {
        self.all_hits8(ray, out, &mut NoStats)
    }

    /// [`Self::all_hits`], adding the work done to `stats`.
    pub fn all_hits_with_stats(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut TraversalStats) {
        self.all_hits8(ray, out, stats)
    }
}

/// Whether the CPU has AVX2, POPCNT and BMI1: detected once, then one load and compare per call
/// (the two `is_x86_feature_detected!` were two cache reads and tests per ray).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn use_avx2() -> bool {
    use std::sync::atomic::{AtomicU8, Ordering::Relaxed};
    /// 0: not detected yet, 1: no, 2: yes.
    static AVX2: AtomicU8 = AtomicU8::new(0);
    #[cold]
    fn detect() -> bool {
        let yes = std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("popcnt")
            && std::is_x86_feature_detected!("bmi1");
        AVX2.store(1 + yes as u8, Relaxed);
        yes
    }
    match AVX2.load(Relaxed) {
        0 => detect(),
        v => v == 2,
    }
}

#[cfg(test)]
#[path = "traverse8_tests.rs"]
mod tests;
