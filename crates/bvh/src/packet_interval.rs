//! The interval bounds of a coherent packet (Reshetov, Soupikov & Hurley 2005; Wald et al.
//! 2007): per axis the packet's origins span `[o_lo, o_hi]` and its `1 / dir` `[inv_lo,
//! inv_hi]`, so a lower bound of every ray's near-plane distance `fl(fl(p - o) * inv)` is the
//! same expression at one corner of that box (the exact product is bilinear, so its extremes
//! are at corners, and rounding is monotone), and likewise an upper bound of the far-plane
//! distances. One 8-lane test of those bounds against an 8-wide node culls the children that no
//! ray of the packet can enter (used by `packet8.rs` for 16-ray packets and by `packet64.rs` for
//! a 64-ray packet and each of its 16-ray groups).
//!
//! **Invariant:** a child the test rejects is rejected by every ray's own single-ray slab test
//! (robust far scaling included), provided `t_min` is at most every ray's `t_min` and `t_max`
//! at least every ray's current `t_max`.
//!
//! | field | meaning |
//! |---|---|
//! | `o_near`, `o_far` | per axis, the origin corner for the near / far row |
//! | `inv_near`, `inv_far` | per axis, `1 / dir` corner for a positive / negative `p - o` |
//! | `near`, `far` | byte offsets of the near / far rows in [`Node8`] |
//! | `t_min`, `t_max` | the smallest `t_min`, the largest current `t_max` of the rays |

use glam::Vec4;
use parallax_core::math::ROBUST_FAR_SCALE;

use crate::node8::Node8;

/// The packet's interval bounds, as 8-lane splats for the node's rows (module docs).
pub(crate) struct Interval {
    /// Per axis: the origin to subtract for the near / far row, and `(inv if d >= 0, inv if
    /// d < 0)` for the near / far row.
    pub o_near: [Vec4; 3],
    pub o_far: [Vec4; 3],
    pub inv_near: [(Vec4, Vec4); 3],
    pub inv_far: [(Vec4, Vec4); 3],
    /// Byte offsets of the near / far rows (`32 * (2 axis + sign)`).
    pub near: [usize; 3],
    pub far: [usize; 3],
    pub t_min: Vec4,
    /// The largest `t_max` of the packet's rays (refreshed after each leaf).
    pub t_max: f32,
}

impl Interval {
    /// The children (bit mask) that some ray of the packet may enter, and a lower bound of
    /// their entry distances.
    #[inline(always)]
    pub fn test(&self, node: &Node8) -> (u32, [f32; 8]) {
        let base = node.bounds.as_ptr() as *const u8;
        let mut mask = 0;
        let mut t = [0.0f32; 8];
        let neg = |d: Vec4, (pos, negv): (Vec4, Vec4)| Vec4::select(d.cmplt(Vec4::ZERO), negv, pos);
        for h in 0..2 {
            // SAFETY: offsets are `32 * i + 16 * h`, `i < 6`, inside `bounds`.
            let b = |off: usize| unsafe {
                Vec4::from_slice(std::slice::from_raw_parts(
                    base.add(off + 16 * h) as *const f32,
                    4,
                ))
            };
            let mut t_near = self.t_min;
            let mut t_far = Vec4::splat(self.t_max);
            for a in 0..3 {
                let dn = b(self.near[a]) - self.o_near[a];
                t_near = t_near.max(dn * neg(dn, self.inv_near[a]));
                let df = b(self.far[a]) - self.o_far[a];
                t_far = t_far.min(df * neg(df, self.inv_far[a]));
            }
            let hit = t_near.cmple(t_far * ROBUST_FAR_SCALE);
            mask |= hit.bitmask() << (4 * h);
            t[4 * h..4 * h + 4].copy_from_slice(&t_near.to_array());
        }
        (mask, t)
    }

    /// [`Self::test`] with 256-bit registers (the same operations lane for lane).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub unsafe fn test_avx2(&self, node: &Node8) -> (u32, [f32; 8]) {
        use std::arch::x86_64::*;
        let base = node.bounds.as_ptr() as *const u8;
        // SAFETY: AVX2 (caller); rows are 32-byte aligned at offsets `32 * i`, `i < 6`.
        unsafe {
            // Macros, not closures: closures do not inherit the caller's target features.
            macro_rules! s {
                ($v:expr) => {
                    _mm256_set1_ps($v.x)
                };
            }
            let zero = _mm256_setzero_ps();
            let mut t_near = s!(self.t_min);
            let mut t_far = _mm256_set1_ps(self.t_max);
            for a in 0..3 {
                let dn = _mm256_sub_ps(
                    _mm256_load_ps(base.add(self.near[a]) as *const f32),
                    s!(self.o_near[a]),
                );
                let (pos, neg) = self.inv_near[a];
                let f = _mm256_blendv_ps(s!(pos), s!(neg), _mm256_cmp_ps::<_CMP_LT_OQ>(dn, zero));
                t_near = _mm256_max_ps(t_near, _mm256_mul_ps(dn, f));
                let df = _mm256_sub_ps(
                    _mm256_load_ps(base.add(self.far[a]) as *const f32),
                    s!(self.o_far[a]),
                );
                let (pos, neg) = self.inv_far[a];
                let f = _mm256_blendv_ps(s!(pos), s!(neg), _mm256_cmp_ps::<_CMP_LT_OQ>(df, zero));
                t_far = _mm256_min_ps(t_far, _mm256_mul_ps(df, f));
            }
            let far = _mm256_mul_ps(t_far, _mm256_set1_ps(ROBUST_FAR_SCALE));
            let hit = _mm256_cmp_ps::<_CMP_LE_OQ>(t_near, far);
            let mut t = [0.0f32; 8];
            _mm256_storeu_ps(t.as_mut_ptr(), t_near);
            (_mm256_movemask_ps(hit) as u32, t)
        }
    }
}
