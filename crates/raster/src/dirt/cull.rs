//! The cube faces' outcode cull of a triangle, all six faces from one set of sums (DIRT
//! §4.1.1, the geometry stage that drops a primitive outside a view before it reaches the
//! fragment shader).
//!
//! [`ViewXf::setup`](super::setup::ViewXf::setup) drops a triangle whose three corners are all
//! outside one of a view's five clip planes (the near plane and the four guard planes). A
//! triangle is seen by one or two of the six cube faces around the eye, so most of its six
//! face set-ups end there. [`FaceCull`] makes that decision for every face of the group (views
//! whose rotation rows are signed axes, sharing the eye and near plane, with guard slopes of
//! one magnitude `a`) once per triangle, and the setup runs only for the faces it keeps.
//!
//! **Shared sums.** With `d` a corner's offset from the eye and `p_k = a d_k` (rounded), a
//! face's camera point is `q = (s_x d_i, s_y d_j, s_z d_k)`, so its guard plane value
//! `q.x + a_lo q.z` is `s_x (d_i + r p_k)` and `-q.x - a_hi q.z` is `-s_x (d_i + r' p_k)`
//! (`r, r' = ±1`; products by `±1` and negation are exact and round-to-nearest is symmetric,
//! so these are the setup's rounded values up to sign). Over the six faces the 24 guard
//! values are thus `±` one of the twelve sums `d_i ± p_k` (`i != k`), and the six near plane
//! values `-s_z d_k - near` are `±` one of `d_k ± near`. A corner is outside a plane when the
//! plane's value is `< 0` (finite values; a zero of either sign is inside, as `!(x >= 0)`
//! says), i.e. when the sum is `< 0` or `> 0` depending on the sign; all three corners are
//! outside when the sums' maximum is `< 0` (or their minimum `> 0`). So the cull computes the
//! 18 sums per corner, their maximum and minimum over the corners, and one bit per (sum,
//! sign); a face is dropped when one of its five (sum, sign) bits is set — exactly when the
//! setup's outcodes drop it. Likewise some corner is outside when the sums' minimum is `< 0`
//! (or their maximum `> 0`): a kept face none of whose five (sum, sign) bits of that kind is
//! set has every corner inside every plane, and its setup skips its own outcode test (no
//! clipping). The AVX2 version holds the 18 sums in five vectors of four lanes
//! and tests the faces' masks in the lanes of two; [`FaceCull::keep_portable`] is its scalar
//! twin; the tests (in `setup.rs`) check both against the setup's own outcodes.

use glam::DVec3;

/// What the cull needs of a view ([`super::setup::ViewXf::axis_view`]).
pub(super) struct AxisView {
    /// The signed axes of the rotation rows, when every row is one.
    pub axes: Option<[(usize, f64); 3]>,
    /// The guard planes' slopes `[ax_lo, ax_hi, ay_lo, ay_hi]`.
    pub slopes: [f64; 4],
    pub near: f64,
    pub eye: DVec3,
}

/// Sums per corner, at `vector * 4 + lane`: `d_i + p_k` for `(i, k)` = (0, 1), (0, 2), (1, 0),
/// (1, 2); the same with `- p_k`; `d_2 + p_0`, `d_2 + p_1`, `d_2 - p_0`, `d_2 - p_1`; `d_k +
/// near` (k = 0..3, lane 3 unused); `d_k - near`.
const SUMS: usize = 20;

/// Slot of the sum `d_i + r p_k` (`r = ±1`, `i != k`) in the layout of [`SUMS`].
fn guard_slot(i: usize, k: usize, r: f64) -> usize {
    let neg = r < 0.0;
    match (i, k) {
        (2, 0) => 8 + 2 * neg as usize,
        (2, 1) => 9 + 2 * neg as usize,
        _ => {
            let lane = match (i, k) {
                (0, 1) => 0,
                (0, 2) => 1,
                (1, 0) => 2,
                (1, 2) => 3,
                _ => unreachable!("i != k"),
            };
            4 * neg as usize + lane
        }
    }
}

/// Most views a group can hold (the lanes of two AVX2 vectors).
const MAX_GROUP: usize = 8;

/// The outcode cull of a group of axis views with one eye (module docs).
pub(super) struct FaceCull {
    /// `a`, the guard slopes' magnitude.
    a: f64,
    near: f64,
    /// Per member view (`views[first + m]`, then padding of all ones): bit `s` set when "all
    /// corners have sum `s` `< 0`" culls the view, bit `32 + s` when "all corners have sum `s`
    /// `> 0`" does.
    masks: [u64; MAX_GROUP],
    /// Bits of the group's views.
    members: u32,
    first: usize,
    len: usize,
    avx2: bool,
}

impl FaceCull {
    /// The group of `views`: the views with signed-axis rotation rows and the eye and near
    /// plane of the first such view, when there are 2..=8 of them, consecutive, and all their
    /// guard slopes have one magnitude; else `None`.
    pub fn new(views: &[AxisView]) -> Option<FaceCull> {
        let first = views.iter().position(|v| v.axes.is_some())?;
        let f = &views[first];
        let a = f.slopes[0].abs();
        let mut masks = [u64::MAX; MAX_GROUP];
        let mut members = Vec::new();
        for (k, v) in views.iter().enumerate() {
            let Some([(ix, sx), (iy, sy), (iz, sz)]) = v.axes else {
                continue;
            };
            if v.eye != f.eye || v.near != f.near {
                continue;
            }
            let [a_lo, a_hi, b_lo, b_hi] = v.slopes;
            if [a_lo, a_hi, b_lo, b_hi].iter().any(|s| s.abs() != a) || a == 0.0 {
                return None;
            }
            if k != first + members.len() || members.len() == MAX_GROUP {
                return None;
            }
            // "Outside" is `sign * sum < 0`: bit `s` for sign +1 (sum < 0), `32 + s` for -1.
            let bit = |slot: usize, sign: f64| 1u64 << (slot + 32 * (sign < 0.0) as usize);
            // Near: -q.z - near = -s_z (d_k + s_z near).
            let near = bit(if sz > 0.0 { 12 + iz } else { 16 + iz }, -sz);
            // q.x + a_lo q.z = s_x (d_i + s_x sign(a_lo s_z) p_k); -q.x - a_hi q.z likewise
            // with the opposite outer sign.
            let r = |s: f64, slope: f64| s * (slope * sz).signum();
            masks[members.len()] = near
                | bit(guard_slot(ix, iz, r(sx, a_lo)), sx)
                | bit(guard_slot(ix, iz, r(sx, a_hi)), -sx)
                | bit(guard_slot(iy, iz, r(sy, b_lo)), sy)
                | bit(guard_slot(iy, iz, r(sy, b_hi)), -sy);
            members.push(k);
        }
        if members.len() < 2 || first + members.len() > 32 {
            return None;
        }
        Some(FaceCull {
            a,
            near: f.near,
            masks,
            members: ((1u32 << members.len()) - 1) << first,
            first,
            len: members.len(),
            avx2: avx2_available(),
        })
    }

    /// Bits of the views in the group.
    #[cfg(test)]
    pub fn members(&self) -> u32 {
        self.members
    }

    /// The group's first view (its offsets `d` from the eye are every member's).
    pub fn first_view(&self) -> usize {
        self.first
    }

    /// The number of views in the group (`first_view()..first_view() + len()`).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Bits of the group's views whose setup does not drop the triangle with corner offsets
    /// `d` from the eye by its outcodes, and the bits of those (a subset) whose outcodes are
    /// all zero: every corner inside every clip plane (module docs).
    #[inline(always)]
    pub fn keep(&self, d: &[[f64; 3]; 3]) -> (u32, u32) {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only when the CPU has AVX2 (`avx2_available`).
            return unsafe { self.keep_avx2(d) };
        }
        self.keep_portable(d)
    }

    /// [`Self::keep`] in scalar code.
    pub fn keep_portable(&self, d: &[[f64; 3]; 3]) -> (u32, u32) {
        let (culled, cut) = self.culled_portable(d);
        let faces = |bits: u64| {
            let f = (0..MAX_GROUP).fold(0, |m, f| m | ((bits & self.masks[f] == 0) as u32) << f);
            (f << self.first) & self.members
        };
        (faces(culled), faces(cut))
    }

    /// The (sum, sign) bits of `d`: bit `s` when sum `s` is `< 0` at every corner, bit
    /// `32 + s` when `> 0` at every corner; and with "some corner" for "every corner", in
    /// scalar code.
    fn culled_portable(&self, d: &[[f64; 3]; 3]) -> (u64, u64) {
        let mut max = [f64::NEG_INFINITY; SUMS];
        let mut min = [f64::INFINITY; SUMS];
        for c in d {
            let p = c.map(|x| self.a * x);
            let sums: [f64; SUMS] = [
                c[0] + p[1],
                c[0] + p[2],
                c[1] + p[0],
                c[1] + p[2],
                c[0] - p[1],
                c[0] - p[2],
                c[1] - p[0],
                c[1] - p[2],
                c[2] + p[0],
                c[2] + p[1],
                c[2] - p[0],
                c[2] - p[1],
                c[0] + self.near,
                c[1] + self.near,
                c[2] + self.near,
                0.0,
                c[0] - self.near,
                c[1] - self.near,
                c[2] - self.near,
                0.0,
            ];
            for s in 0..SUMS {
                max[s] = max[s].max(sums[s]);
                min[s] = min[s].min(sums[s]);
            }
        }
        let all = (0..SUMS).fold(0, |m, s| {
            m | ((max[s] < 0.0) as u64) << s | ((min[s] > 0.0) as u64) << (32 + s)
        });
        let some = (0..SUMS).fold(0, |m, s| {
            m | ((min[s] < 0.0) as u64) << s | ((max[s] > 0.0) as u64) << (32 + s)
        });
        (all, some)
    }

    /// [`Self::keep`] with the sums in five AVX2 vectors (module docs) and the faces' masks
    /// tested in the lanes of two.
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn keep_avx2(&self, d: &[[f64; 3]; 3]) -> (u32, u32) {
        use std::arch::x86_64::*;
        let a = _mm256_set1_pd(self.a);
        let near = _mm256_setr_pd(self.near, self.near, self.near, 0.0);
        let neg_hi = _mm256_setr_pd(0.0, 0.0, -0.0, -0.0);
        let three = _mm256_setr_epi64x(-1, -1, -1, 0);
        let sums = |c: &[f64; 3]| {
            // SAFETY: the mask reads the corner's three f64 only.
            let v = unsafe { _mm256_maskload_pd(c.as_ptr(), three) };
            let p = _mm256_mul_pd(a, v);
            let l = _mm256_permute4x64_pd::<0b01_01_00_00>(v);
            let r = _mm256_permute4x64_pd::<0b10_00_10_01>(p);
            let l2 = _mm256_permute4x64_pd::<0b10_10_10_10>(v);
            let r2 = _mm256_xor_pd(_mm256_permute4x64_pd::<0b01_00_01_00>(p), neg_hi);
            [
                _mm256_add_pd(l, r),
                _mm256_sub_pd(l, r),
                _mm256_add_pd(l2, r2),
                _mm256_add_pd(v, near),
                _mm256_sub_pd(v, near),
            ]
        };
        let mut max = sums(&d[0]);
        let mut min = max;
        for c in &d[1..] {
            let s = sums(c);
            for k in 0..5 {
                max[k] = _mm256_max_pd(max[k], s[k]);
                min[k] = _mm256_min_pd(min[k], s[k]);
            }
        }
        // Lane 3 of the near sums holds 0: never set (0 is neither < 0 nor > 0).
        let zero = _mm256_setzero_pd();
        let (mut culled, mut cut) = (0u64, 0u64);
        for k in 0..5 {
            let lt = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(max[k], zero)) as u64;
            let gt = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(min[k], zero)) as u64;
            culled |= lt << (4 * k) | gt << (32 + 4 * k);
            let lt = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(min[k], zero)) as u64;
            let gt = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_GT_OQ>(max[k], zero)) as u64;
            cut |= lt << (4 * k) | gt << (32 + 4 * k);
        }
        let z = _mm256_setzero_si256();
        // SAFETY: two loads of four u64 from the eight masks.
        let (m0, m1) = unsafe {
            (
                _mm256_loadu_si256(self.masks.as_ptr().cast()),
                _mm256_loadu_si256(self.masks.as_ptr().add(4).cast()),
            )
        };
        let faces = |bits: u64| {
            let c = _mm256_set1_epi64x(bits as i64);
            let k0 = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(
                _mm256_and_si256(c, m0),
                z,
            )));
            let k1 = _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_cmpeq_epi64(
                _mm256_and_si256(c, m1),
                z,
            )));
            (((k0 | k1 << 4) as u32) << self.first) & self.members
        };
        (faces(culled), faces(cut))
    }
}

pub(super) fn avx2_available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}
