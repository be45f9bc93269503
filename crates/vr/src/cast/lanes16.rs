//! Sixteen f32 lanes as four SSE registers ([`V16`]): the lane type of the 16-ray set-up kernel
//! (Hunt et al. 2018, §5.5, one packet per pixel at 16 subsamples: `cast/setup/mod.rs`).
//!
//! Every operation is glam's [`Vec4`] operation (the 4-lane kernel's) on each quarter, so lane
//! `i` rounds exactly as the 4-lane kernel and scalar f32 do (the invariant of
//! `parallax_core::simd`; tested against the scalar rule in this module's tests). Sixteen
//! lanes amortise the per-triangle work that does not depend on the ray (loading the set-up
//! triangle, splatting its covectors, the mask bookkeeping) over four times as many rays.

use std::ops::{Add, Div, Mul, Sub};

use glam::{BVec4A, Vec4};
use parallax_core::simd::{F8, Lanes};

/// Horizontal operations the set-up kernel needs per packet (not per triangle), so they stay
/// out of the scalar lane-by-lane loops: the smallest / largest lane (compare-and-select, the
/// kernels' values are never NaN where it matters) and all lanes to an array.
pub trait LaneReduce: Lanes {
    fn hmin(self) -> f32;
    fn hmax(self) -> f32;
    /// `[v[0].hmin(), v[1].hmin(), v[2].hmin(), v[3].hmin()]` bit for bit: lane types with a
    /// four-lane quarter form run the four last steps of their trees at once
    /// ([`hmin_of_quarters`]).
    #[inline(always)]
    fn hmin4(v: [Self; 4]) -> Vec4 {
        Vec4::new(v[0].hmin(), v[1].hmin(), v[2].hmin(), v[3].hmin())
    }
    /// `[v[0].hmax(), ..]` bit for bit, as [`LaneReduce::hmin4`].
    #[inline(always)]
    fn hmax4(v: [Self; 4]) -> Vec4 {
        Vec4::new(v[0].hmax(), v[1].hmax(), v[2].hmax(), v[3].hmax())
    }
    /// Lanes `0..N` into `out[..N]`.
    fn write(self, out: &mut [f32]);
    /// `out[l] = v` for the lanes `l` of `m`, the other entries unchanged (`out` holds at
    /// least `N` entries): a packet's winners' triangle index without a loop over the bits.
    fn set_u32(m: Self::M, v: u32, out: &mut [u32]);
    /// Runs per interval test of the set-up kernels' run walk (`cast/setup/edges.rs`): 4
    /// (one SSE register per axis and bound), 8 for `lanes256::Y16` (one AVX register), 16
    /// for `lanes512::Z16` (one AVX-512 register). The walk's decisions are the same for any
    /// (`kernel.rs`).
    const RUN_GROUP: usize = 4;
    /// Lanes that only exist inside AVX2 code (`lanes256`'s): the per-tile set-up's gather takes
    /// its AVX form there (`cast/setup/rows.rs`).
    const AVX2: bool = false;
    /// Lanes `0..N` from `a[..N]` (`N <= 16`).
    #[inline(always)]
    fn load16(a: &[f32; 16]) -> Self {
        Self::from_fn(|l| a[l])
    }
    /// Lanes `0..N` from `a[..N]` (panics if `a` is shorter): contiguous loads where the lane
    /// type has them.
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        Self::from_fn(|l| a[l])
    }
    /// The 8 x `N` transpose of `rows`: `out[l][r]` = lane `l` of `rows[r]` for `l < N`
    /// (`out[N..]` unchanged), bits moved only: a set-up pack's lanes as one row per triangle
    /// (`cast/setup/tile.rs`). This form stores the rows and copies lane by lane; `Y8` runs
    /// an 8 x 8 transpose in AVX registers.
    #[inline(always)]
    fn transpose8(rows: [Self; 8], out: &mut [[f32; 8]; 16]) {
        let mut t = [[0.0f32; 16]; 8];
        for (r, t) in rows.into_iter().zip(t.iter_mut()) {
            r.write(t);
        }
        for (l, o) in out.iter_mut().enumerate().take(Self::N) {
            for (r, t) in t.iter().enumerate() {
                o[r] = t[l];
            }
        }
    }
}

/// The 4 x 4 transpose of `q` (`c[k]` = lane `k` of every register).
#[inline(always)]
fn transpose4(q: [Vec4; 4]) -> [Vec4; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        let [a, b, c, d] = q;
        let (a, b, c, d) = (
            __m128::from(a),
            __m128::from(b),
            __m128::from(c),
            __m128::from(d),
        );
        // SAFETY: SSE is part of the x86-64 baseline.
        unsafe {
            let (t0, t1) = (_mm_unpacklo_ps(a, b), _mm_unpacklo_ps(c, d));
            let (t2, t3) = (_mm_unpackhi_ps(a, b), _mm_unpackhi_ps(c, d));
            [
                Vec4::from(_mm_movelh_ps(t0, t1)),
                Vec4::from(_mm_movehl_ps(t1, t0)),
                Vec4::from(_mm_movelh_ps(t2, t3)),
                Vec4::from(_mm_movehl_ps(t3, t2)),
            ]
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        std::array::from_fn(|k| Vec4::new(q[0][k], q[1][k], q[2][k], q[3][k]))
    }
}

/// Lane `k`: `q[k].hmin()` of [`Vec4`] (`min2(min2(x, y), min2(z, w))`, `min2(a, b) = a < b ?
/// a : b`) for the four registers at once: a transpose and three `minps` of the same pairs.
#[inline(always)]
pub fn hmin_of_quarters(q: [Vec4; 4]) -> Vec4 {
    let [c0, c1, c2, c3] = transpose4(q);
    Lanes::min_or_rhs(Lanes::min_or_rhs(c0, c1), Lanes::min_or_rhs(c2, c3))
}

/// Lane `k`: `q[k].hmax()` of [`Vec4`], as [`hmin_of_quarters`].
#[inline(always)]
pub fn hmax_of_quarters(q: [Vec4; 4]) -> Vec4 {
    let [c0, c1, c2, c3] = transpose4(q);
    Lanes::max_or_rhs(Lanes::max_or_rhs(c0, c1), Lanes::max_or_rhs(c2, c3))
}

#[inline(always)]
fn min2(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}
#[inline(always)]
fn max2(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

impl LaneReduce for Vec4 {
    #[inline(always)]
    fn hmin4(v: [Self; 4]) -> Vec4 {
        hmin_of_quarters(v)
    }
    #[inline(always)]
    fn hmax4(v: [Self; 4]) -> Vec4 {
        hmax_of_quarters(v)
    }
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        Vec4::from_slice(&a[..4])
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        let a = self.to_array();
        min2(min2(a[0], a[1]), min2(a[2], a[3]))
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        let a = self.to_array();
        max2(max2(a[0], a[1]), max2(a[2], a[3]))
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        self.write_to_slice(&mut out[..4]);
    }
    #[inline(always)]
    fn set_u32(m: BVec4A, v: u32, out: &mut [u32]) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::*;
            let out = &mut out[..4];
            // SAFETY: SSE2 (the x86_64 baseline); `out` holds 4 u32. A bitwise blend.
            unsafe {
                let p = out.as_mut_ptr() as *mut __m128i;
                let m = _mm_castps_si128(__m128::from(m));
                let x = _mm_and_si128(m, _mm_set1_epi32(v as i32));
                _mm_storeu_si128(p, _mm_or_si128(x, _mm_andnot_si128(m, _mm_loadu_si128(p))));
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        for (l, o) in out[..4].iter_mut().enumerate() {
            if m.test(l) {
                *o = v;
            }
        }
    }
}

impl LaneReduce for F8 {
    #[inline(always)]
    fn hmin(self) -> f32 {
        self.0.iter().fold(f32::INFINITY, |a, &b| min2(a, b))
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        self.0.iter().fold(f32::NEG_INFINITY, |a, &b| max2(a, b))
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        out[..8].copy_from_slice(&self.0);
    }
    #[inline(always)]
    fn set_u32(m: <F8 as Lanes>::M, v: u32, out: &mut [u32]) {
        let b = <F8 as Lanes>::bits(m);
        for (l, o) in out[..8].iter_mut().enumerate() {
            if b >> l & 1 != 0 {
                *o = v;
            }
        }
    }
}

/// The first steps of [`V16`]'s `hmin` tree: quarters pairwise, then the two.
#[inline(always)]
fn qmin(x: V16) -> Vec4 {
    let q = x.0;
    Lanes::min_or_rhs(Lanes::min_or_rhs(q[0], q[1]), Lanes::min_or_rhs(q[2], q[3]))
}

/// The first steps of [`V16`]'s `hmax` tree.
#[inline(always)]
fn qmax(x: V16) -> Vec4 {
    let q = x.0;
    Lanes::max_or_rhs(Lanes::max_or_rhs(q[0], q[1]), Lanes::max_or_rhs(q[2], q[3]))
}

impl LaneReduce for V16 {
    #[inline(always)]
    fn hmin4([a, b, c, d]: [Self; 4]) -> Vec4 {
        hmin_of_quarters([qmin(a), qmin(b), qmin(c), qmin(d)])
    }
    #[inline(always)]
    fn hmax4([a, b, c, d]: [Self; 4]) -> Vec4 {
        hmax_of_quarters([qmax(a), qmax(b), qmax(c), qmax(d)])
    }
    #[inline(always)]
    fn hmin(self) -> f32 {
        // `a < b ? a : b` per lane (`minps` on SSE2, NaN in either gives `b`), quarters
        // pairwise, then the quarter's lanes.
        let q = self.0;
        let m = |a: Vec4, b: Vec4| Lanes::min_or_rhs(a, b);
        m(m(q[0], q[1]), m(q[2], q[3])).hmin()
    }
    #[inline(always)]
    fn hmax(self) -> f32 {
        let q = self.0;
        let m = |a: Vec4, b: Vec4| Lanes::max_or_rhs(a, b);
        m(m(q[0], q[1]), m(q[2], q[3])).hmax()
    }
    #[inline(always)]
    fn write(self, out: &mut [f32]) {
        for (i, q) in self.0.iter().enumerate() {
            q.write_to_slice(&mut out[4 * i..4 * i + 4]);
        }
    }
    #[inline(always)]
    fn set_u32(m: M16, v: u32, out: &mut [u32]) {
        for (i, q) in m.0.iter().enumerate() {
            Vec4::set_u32(*q, v, &mut out[4 * i..4 * i + 4]);
        }
    }
    #[inline(always)]
    fn load16(a: &[f32; 16]) -> Self {
        V16([0, 1, 2, 3].map(|i| Vec4::from_slice(&a[4 * i..4 * i + 4])))
    }
    #[inline(always)]
    fn load_n(a: &[f32]) -> Self {
        let a: &[f32; 16] = a[..16].try_into().expect("16 lanes");
        Self::load16(a)
    }
}

/// The bits of a [`M16`] quarter by quarter (`movmskps` each): the reference of
/// `V16::bits`.
#[inline(always)]
pub fn bits_by_quarter(m: M16) -> u32 {
    let b = |i: usize| <Vec4 as Lanes>::bits(m.0[i]) << (4 * i);
    b(0) | b(1) | b(2) | b(3)
}

/// Sixteen lanes: lane `i` is `self.0[i / 4][i % 4]`.
#[derive(Clone, Copy, Debug)]
pub struct V16(pub [Vec4; 4]);

/// The mask of [`V16`].
#[derive(Clone, Copy, Debug)]
pub struct M16(pub [BVec4A; 4]);

macro_rules! binop {
    ($tr:ident, $f:ident) => {
        impl $tr for V16 {
            type Output = V16;
            #[inline(always)]
            fn $f(self, o: V16) -> V16 {
                let (a, b) = (self.0, o.0);
                V16([a[0].$f(b[0]), a[1].$f(b[1]), a[2].$f(b[2]), a[3].$f(b[3])])
            }
        }
    };
}
binop!(Add, add);
binop!(Sub, sub);
binop!(Mul, mul);
binop!(Div, div);

macro_rules! quarters {
    ($f:ident, $out:ident) => {
        #[inline(always)]
        fn $f(self, o: Self) -> $out {
            let (a, b) = (self.0, o.0);
            $out([
                Lanes::$f(a[0], b[0]),
                Lanes::$f(a[1], b[1]),
                Lanes::$f(a[2], b[2]),
                Lanes::$f(a[3], b[3]),
            ])
        }
    };
}

impl Lanes for V16 {
    const N: usize = 16;
    type M = M16;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        V16([Vec4::splat(x); 4])
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        let mut q = |i: usize| Vec4::new(f(4 * i), f(4 * i + 1), f(4 * i + 2), f(4 * i + 3));
        V16([q(0), q(1), q(2), q(3)])
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        self.0[i >> 2][i & 3]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        // Written out: `[Vec4; 4]::map` compiled to an out-of-line `try_map` call per packet.
        let [a, b, c, d] = self.0;
        V16([a.sqrt(), b.sqrt(), c.sqrt(), d.sqrt()])
    }
    quarters!(lt, M16);
    quarters!(gt, M16);
    quarters!(le, M16);
    quarters!(ge, M16);
    quarters!(eq, M16);
    quarters!(ne, M16);
    quarters!(max_or_rhs, V16);
    quarters!(min_or_rhs, V16);
    #[inline(always)]
    fn and(a: M16, b: M16) -> M16 {
        M16([
            a.0[0] & b.0[0],
            a.0[1] & b.0[1],
            a.0[2] & b.0[2],
            a.0[3] & b.0[3],
        ])
    }
    #[inline(always)]
    fn or(a: M16, b: M16) -> M16 {
        M16([
            a.0[0] | b.0[0],
            a.0[1] | b.0[1],
            a.0[2] | b.0[2],
            a.0[3] | b.0[3],
        ])
    }
    /// The four quarters' lane masks (every lane all ones or all zeros) packed with signed
    /// saturation to sixteen bytes, one byte-sign mask (`packssdw`, `packsswb`, `pmovmskb`,
    /// SSE2: the x86-64 baseline): bit `i` = lane `i`, as [`bits_by_quarter`].
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn bits(m: M16) -> u32 {
        use std::arch::x86_64::{
            __m128, _mm_castps_si128, _mm_movemask_epi8, _mm_packs_epi16, _mm_packs_epi32,
        };
        let [a, b, c, d] = m.0.map(__m128::from);
        // SAFETY: SSE2 intrinsics on registers only (SSE2 is part of the x86-64 baseline).
        unsafe {
            let lo = _mm_packs_epi32(_mm_castps_si128(a), _mm_castps_si128(b));
            let hi = _mm_packs_epi32(_mm_castps_si128(c), _mm_castps_si128(d));
            _mm_movemask_epi8(_mm_packs_epi16(lo, hi)) as u32
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    #[inline(always)]
    fn bits(m: M16) -> u32 {
        bits_by_quarter(m)
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        let q = |i: usize| self.0[i].is_negative_bitmask() << (4 * i);
        q(0) | q(1) | q(2) | q(3)
    }
    #[inline(always)]
    fn select(m: M16, a: Self, b: Self) -> Self {
        let q = |i: usize| <Vec4 as Lanes>::select(m.0[i], a.0[i], b.0[i]);
        V16([q(0), q(1), q(2), q(3)])
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// NaN on either side, infinities, signed zeros, ordinary values.
    pub(crate) const A: [f32; 16] = [
        f32::NAN,
        3.0,
        -1.0,
        f32::NAN,
        0.0,
        -0.0,
        f32::INFINITY,
        2.0,
        1e-30,
        -5.5,
        7.0,
        0.1,
        f32::NEG_INFINITY,
        4.0,
        -0.0,
        1.0,
    ];
    pub(crate) const B: [f32; 16] = [
        1.0,
        2.0,
        5.0,
        f32::INFINITY,
        -0.0,
        0.0,
        f32::NAN,
        2.0,
        3e-30,
        -5.5,
        -7.0,
        0.3,
        1.0,
        f32::NAN,
        0.0,
        1.0,
    ];

    /// Bit-identical, or both NaN.
    pub(crate) fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// `hmin` / `hmax` equal the compare-and-select tree (`a < b ? a : b` pairwise over the
    /// quarters, then within one) bit for bit, NaN and signed zeros included.
    #[test]
    fn bits_are_the_quarters_bits() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..5000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let a = V16::from_fn(|i| (x >> (2 * i) & 3) as f32 - 1.0);
            let b = V16::from_fn(|i| (x >> (2 * i + 32) & 3) as f32 - 1.0);
            for m in [
                a.lt(b),
                a.ge(b),
                a.eq(b),
                a.ne(b),
                V16::and(a.lt(b), a.ne(b)),
            ] {
                assert_eq!(V16::bits(m), bits_by_quarter(m));
            }
        }
        let zero = V16::splat(0.0);
        assert_eq!(V16::bits(zero.eq(zero)), 0xFFFF);
        assert_eq!(V16::bits(zero.ne(zero)), 0);
    }

    #[test]
    fn reductions_are_the_select_tree() {
        let sel = |a: f32, b: f32, lt: bool| {
            if (lt && a < b) || (!lt && a > b) {
                a
            } else {
                b
            }
        };
        let tree = |x: &[f32; 16], lt: bool| {
            let q: Vec<f32> = (0..4)
                .map(|l| {
                    let (a, b) = (sel(x[l], x[4 + l], lt), sel(x[8 + l], x[12 + l], lt));
                    sel(a, b, lt)
                })
                .collect();
            sel(sel(q[0], q[1], lt), sel(q[2], q[3], lt), lt)
        };
        for r in 0..16 {
            for src in [A, B] {
                let x: [f32; 16] = std::array::from_fn(|i| src[(i + r) % 16]);
                let v = V16::from_fn(|i| x[i]);
                assert!(same(v.hmin(), tree(&x, true)), "{x:?}");
                assert!(same(v.hmax(), tree(&x, false)), "{x:?}");
                // Four reductions at once, `V16` and `Vec4`: each register's own reduction.
                let four = [v, v * v, V16::splat(0.0) - v, v + V16::splat(1.0)];
                let (mn, mx) = (V16::hmin4(four), V16::hmax4(four));
                let q = v.0;
                let (qn, qx) = (Vec4::hmin4(q), Vec4::hmax4(q));
                for k in 0..4 {
                    assert!(same(mn[k], four[k].hmin()), "{x:?}");
                    assert!(same(mx[k], four[k].hmax()), "{x:?}");
                    assert!(same(qn[k], q[k].hmin()), "{x:?}");
                    assert!(same(qx[k], q[k].hmax()), "{x:?}");
                }
            }
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)] // the index addresses the array and the lanes in step
    fn every_lane_is_the_scalar_operation() {
        let (a, b) = (V16::from_fn(|i| A[i]), V16::from_fn(|i| B[i]));
        parallax_core::simd::assert_lanes_match_scalar(a, b, &A, &B);
        for i in 0..16 {
            let x = A[i];
            assert!(same(a.sqrt().get(i), x.sqrt()));
            assert!(same(V16::splat(x).get(i), x));
        }
    }
}
