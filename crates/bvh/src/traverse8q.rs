//! Closest hits of single rays over the quantised 8-wide tree ([`crate::node8q`]), and the
//! closest-hit entry points, which take that tree where the build made one.
//!
//! The loop is the 8-wide kernel of `traverse8.rs` (`Bvh::traverse8`, generic over the node
//! layout); only the node test differs. It first dequantises the six plane rows of the node,
//! `fma(q, scale, origin)` per lane (AVX2: one `vpmovzxbd`, one `vcvtdq2ps` and one FMA per
//! row; the portable twin: `f32::mul_add` per lane, the same single rounding), then
//! runs the robust slab test of `traverse8.rs` on those f32 boxes, unchanged (Ize 2013 far
//! scaling, no FMA in the slab). Each dequantised box contains its child's exact box, so the
//! test culls no box the ray touches, and the closest hit, the lexicographic minimum of
//! `(t, triangle index)` over the leaves reached, is bit for bit that of the exact tree; the
//! visiting order may differ. Unused lanes are masked by `Node8Q::valid`.

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::ROBUST_FAR_SCALE;
use parallax_core::simd::{max_or_rhs, min_or_rhs};

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::keys8;
use crate::node8q::Node8Q;
use crate::stats::{Counter, NoStats, TraversalStats};
use crate::traverse::ray_ok;
use crate::traverse8::{NodeTest8, RayBoxes8};

/// The portable quantised node test: two 4-lane halves.
pub(crate) struct Portable8Q(pub RayBoxes8);

impl NodeTest8 for Portable8Q {
    type Node = Node8Q;
    type Dist = [f32; 8];
    type Pair = parallax_core::simd::F8;

    #[inline(always)]
    fn nodes(bvh: &Bvh) -> &[Node8Q] {
        &bvh.nodes8q
    }

    #[inline(always)]
    fn hit_keys(&self, node: &Node8Q, t: [f32; 8], mask: u32) -> [u64; 8] {
        keys8::compress_keys(t, &node.child, mask)
    }

    #[inline(always)]
    fn pair_keys(&self, node: &Node8Q, t: [f32; 8], mask: u32) -> (u64, u64) {
        keys8::pair_keys(&t, &node.child, mask)
    }

    #[inline(always)]
    fn test(&self, node: &Node8Q, t_max: f32) -> (u32, [f32; 8]) {
        let rb = &self.0;
        let mut mask = 0;
        let mut t = [0.0f32; 8];
        // Row `off / 32` of `RayBoxes8`'s byte offsets; axis `a`.
        let plane = |off: usize, a: usize, h: usize| {
            let q = &node.q[off / 32][4 * h..4 * h + 4];
            let d = |k: usize| crate::node8q::dequantise(node.origin[a], node.scale[a], q[k]);
            Vec4::new(d(0), d(1), d(2), d(3))
        };
        for h in 0..2 {
            let o = rb.org.map(Vec4::splat);
            let i = rb.neg_inv.map(Vec4::splat);
            let tnx = (o[0] - plane(rb.near[0], 0, h)) * i[0];
            let tny = (o[1] - plane(rb.near[1], 1, h)) * i[1];
            let tnz = (o[2] - plane(rb.near[2], 2, h)) * i[2];
            let tfx = (o[0] - plane(rb.far[0], 0, h)) * i[0];
            let tfy = (o[1] - plane(rb.far[1], 1, h)) * i[1];
            let tfz = (o[2] - plane(rb.far[2], 2, h)) * i[2];
            let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, Vec4::splat(rb.t_min))));
            let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, Vec4::splat(t_max))));
            let t_far = t_far * ROBUST_FAR_SCALE;
            mask |= t_near.cmple(t_far).bitmask() << (4 * h);
            t[4 * h..4 * h + 4].copy_from_slice(&t_near.to_array());
        }
        (mask & node.valid, t)
    }
}

/// The AVX2 quantised node test (construct only after detecting AVX2 and FMA): the ray's
/// origin and `-1 / dir` broadcast to rows, the plane rows' byte offsets into `Node8Q::q`.
#[cfg(target_arch = "x86_64")]
pub(crate) struct Avx2Boxes8Q {
    near: [usize; 3],
    far: [usize; 3],
    t_min: f32,
    org: [std::arch::x86_64::__m256; 3],
    inv: [std::arch::x86_64::__m256; 3],
}

#[cfg(target_arch = "x86_64")]
impl Avx2Boxes8Q {
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
                near: rb.near.map(|o| o / 4),
                far: rb.far.map(|o| o / 4),
                t_min: rb.t_min,
            }
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl NodeTest8 for Avx2Boxes8Q {
    type Node = Node8Q;
    type Dist = std::arch::x86_64::__m256;
    type Pair = crate::lanes8::A8;

    #[inline(always)]
    fn nodes(bvh: &Bvh) -> &[Node8Q] {
        &bvh.nodes8q
    }

    #[inline(always)]
    fn hit_keys(&self, node: &Node8Q, t_near: Self::Dist, mask: u32) -> [u64; 8] {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { keys8::compress_keys_avx2(t_near, &node.child, mask) }
    }

    #[inline(always)]
    fn pair_keys(&self, node: &Node8Q, t_near: Self::Dist, mask: u32) -> (u64, u64) {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { keys8::pair_keys_avx2(t_near, &node.child, mask) }
    }

    #[inline(always)]
    fn tri_ray(&self, ray: &Ray) -> crate::tri4::Tri4Ray {
        // SAFETY: AVX2 was detected (`new`).
        unsafe { crate::tri4::Tri4Ray::new_avx2(ray) }
    }

    #[inline(always)]
    fn leaf_closest<C: Counter>(&self, ctx: &mut crate::leaf8::ClosestCtx, leaf: u32, s: &mut C) {
        // As `Avx2Boxes8::leaf_closest`: inlined with the context opaque.
        let ctx = std::hint::black_box(ctx);
        ctx.leaf::<C, crate::lanes8::A8>(leaf, s)
    }

    #[inline(always)]
    fn test(&self, node: &Node8Q, t_max: f32) -> (u32, Self::Dist) {
        use std::arch::x86_64::*;
        let base = node.q.as_ptr() as *const u8;
        // SAFETY: a value of this type exists only where AVX2 and FMA were detected (`new`);
        // the 8-byte loads are rows of `q` at offsets `8 * r`, `r < 6`.
        unsafe {
            let s = node.scale.map(|s| _mm256_set1_ps(s));
            let org = node.origin.map(|o| _mm256_set1_ps(o));
            // A macro, not a closure: closures do not inherit the caller's target features.
            macro_rules! plane {
                ($off:expr, $a:expr) => {{
                    let q = _mm_loadl_epi64(base.add($off) as *const __m128i);
                    let q = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(q));
                    _mm256_fmadd_ps(q, s[$a], org[$a])
                }};
            }
            let (o, i) = (&self.org, &self.inv);
            let tnx = _mm256_mul_ps(_mm256_sub_ps(o[0], plane!(self.near[0], 0)), i[0]);
            let tny = _mm256_mul_ps(_mm256_sub_ps(o[1], plane!(self.near[1], 1)), i[1]);
            let tnz = _mm256_mul_ps(_mm256_sub_ps(o[2], plane!(self.near[2], 2)), i[2]);
            let tfx = _mm256_mul_ps(_mm256_sub_ps(o[0], plane!(self.far[0], 0)), i[0]);
            let tfy = _mm256_mul_ps(_mm256_sub_ps(o[1], plane!(self.far[1], 1)), i[1]);
            let tfz = _mm256_mul_ps(_mm256_sub_ps(o[2], plane!(self.far[2], 2)), i[2]);
            let t_near = _mm256_max_ps(
                tnz,
                _mm256_max_ps(tny, _mm256_max_ps(tnx, _mm256_set1_ps(self.t_min))),
            );
            let t_far = _mm256_min_ps(
                tfz,
                _mm256_min_ps(tfy, _mm256_min_ps(tfx, _mm256_set1_ps(t_max))),
            );
            let t_far = _mm256_mul_ps(t_far, _mm256_set1_ps(ROBUST_FAR_SCALE));
            let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far);
            (_mm256_movemask_ps(hit) as u32 & node.valid, t_near)
        }
    }
}

impl Bvh {
    /// Whether the closest-hit queries take the quantised tree (the build made one).
    #[inline(always)]
    fn quantised(&self) -> bool {
        !self.nodes8q.is_empty()
    }

    #[inline(never)]
    fn closest8q_portable<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        self.closest8(&Portable8Q(RayBoxes8::new(ray)), ray, stats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,bmi1")]
    #[inline]
    unsafe fn closest8q_avx2<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        // SAFETY: AVX2 and FMA are enabled for this function (the caller detected them).
        let nt = unsafe { Avx2Boxes8Q::new(RayBoxes8::new(ray)) };
        self.closest8(&nt, ray, stats)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,popcnt,bmi1")]
    unsafe fn closest8q_avx2_nostats(&self, ray: &Ray) -> Option<Hit> {
        // SAFETY: AVX2 and FMA are enabled for this function (the caller detected them).
        unsafe { self.closest8q_avx2(ray, &mut NoStats) }
    }

    /// The closest intersection with `ray` in `(t_min, t_max)`, or `None`. Both faces of a
    /// triangle are hit. Invalid rays (non-finite, zero direction) hit nothing. Exact ties in
    /// `t` go to the lower index in [`Bvh::triangles`] (with spatial splits: to one of the
    /// tied triangles, [`BuildOptions`](crate::BuildOptions)). Traverses the quantised 8-wide
    /// tree where the build made one, else the 8-wide tree (AVX2 node test where the CPU has
    /// it); the answer is the same.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        // No frame here: the kernel is a tail call.
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::traverse8::use_avx2() {
            // SAFETY: AVX2 and FMA were detected.
            return unsafe {
                if self.quantised() {
                    self.closest8q_avx2_nostats(ray)
                } else {
                    self.closest8_avx2_nostats(ray)
                }
            };
        }
        if self.quantised() {
            return self.closest8q_portable(ray, &mut NoStats);
        }
        self.closest8_portable_nostats(ray)
    }

    /// [`Self::closest_hit`], adding the work done (8-wide nodes) to `stats`.
    pub fn closest_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        if !self.quantised() {
            return self.closest_hit8(ray, stats);
        }
        stats.ray();
        if !ray_ok(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::traverse8::use_avx2() {
            // SAFETY: AVX2 and FMA were detected.
            return unsafe { self.closest8q_avx2(ray, stats) };
        }
        self.closest8q_portable(ray, stats)
    }

    /// [`Self::closest_hit`] with the portable node test even where AVX2 exists (quantised
    /// where [`Self::closest_hit`] is): the twin the tests hold the AVX2 path against.
    pub fn closest_hit8_portable(&self, ray: &Ray) -> Option<Hit> {
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        if self.quantised() {
            return self.closest8q_portable(ray, &mut NoStats);
        }
        self.closest8_portable_nostats(ray)
    }

    /// [`Self::closest_hit`] over the exact (unquantised) 8-wide tree, AVX2 where the CPU has
    /// it: the reference of the quantised tree, bit for bit.
    pub fn closest_hit8_exact(&self, ray: &Ray) -> Option<Hit> {
        if self.nodes8.is_empty() || !ray_ok(ray) {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::traverse8::use_avx2() {
            // SAFETY: AVX2 was detected.
            return unsafe { self.closest8_avx2_nostats(ray) };
        }
        self.closest8_portable_nostats(ray)
    }

    /// Whether [`Self::closest_hit`] traverses the quantised tree (`node8q.rs`).
    pub fn has_quantised_tree(&self) -> bool {
        self.quantised()
    }
}
