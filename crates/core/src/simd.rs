//! SIMD lanes: one trait ([`Lanes`]) over `f32` (one lane), glam's [`Vec4`] (SSE on x86_64) and
//! [`F8`] (eight lanes for code compiled with AVX2), so that a kernel is written once and every
//! lane rounds exactly like scalar f32 (IEEE lanes, no FMA: Rust never contracts `a * b + c`).
//!
//! **NaN rule of min / max.** [`max_or_rhs`] (`a > b ? a : b`) and [`min_or_rhs`]
//! (`a < b ? a : b`) return the *right* operand when either is NaN. Slab tests rely on it: for a
//! ray with a zero direction component (`inv_dir = ±inf`) whose origin lies exactly on a slab
//! plane, `(plane - origin) * inv_dir = 0 * inf = NaN`; such a ray lies inside the closed slab for
//! its whole length, so the NaN must be ignored, and the traversal keeps the right operand (the
//! running accumulator) NaN-free. On x86 this is exactly `maxps` / `minps` (Intel SDM: "if either
//! value is a NaN, the second operand is returned"), which glam's SSE2 `Vec4::max` / `min`
//! compile to; glam documents its NaN behaviour as unspecified across back ends, so other
//! targets use an explicit compare-and-select. Every implementation is tested against the scalar
//! rule (including NaNs and signed zeros).
//!
//! **Invariant:** lane `i` of every operation equals the scalar f32 operation on lane `i`.

use std::ops::{Add, Div, Mul, Sub};

use glam::{BVec4A, Vec4};

/// A vector of `N` f32 lanes: the operations the SIMD kernels of parallax need, each lane
/// rounding exactly like scalar f32 (module docs).
pub trait Lanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// Number of lanes.
    const N: usize;
    /// A lane mask.
    type M: Copy;
    fn splat(x: f32) -> Self;
    fn from_fn(f: impl FnMut(usize) -> f32) -> Self;
    fn get(self, i: usize) -> f32;
    fn sqrt(self) -> Self;
    fn lt(self, o: Self) -> Self::M;
    fn gt(self, o: Self) -> Self::M;
    fn le(self, o: Self) -> Self::M;
    fn ge(self, o: Self) -> Self::M;
    fn eq(self, o: Self) -> Self::M;
    /// Unordered not-equal (true on NaN), as `cmpneqps`.
    fn ne(self, o: Self) -> Self::M;
    /// `self > o ? self : o` per lane (NaN in either gives `o`; module docs).
    fn max_or_rhs(self, o: Self) -> Self;
    /// `self < o ? self : o` per lane (NaN in either gives `o`; module docs).
    fn min_or_rhs(self, o: Self) -> Self;
    /// Lane-wise AND of two masks.
    fn and(a: Self::M, b: Self::M) -> Self::M;
    /// Lane-wise OR of two masks.
    fn or(a: Self::M, b: Self::M) -> Self::M;
    /// Bit `i` set iff lane `i` of the mask is set.
    fn bits(m: Self::M) -> u32;
    /// Bit `i` set iff lane `i` has its sign bit set (`-0.0`, negative numbers, NaNs with the
    /// sign bit): one `movmskps` on SSE / AVX, no compare.
    fn sign_bits(self) -> u32;
    fn select(m: Self::M, a: Self, b: Self) -> Self;
}

/// `a > b ? a : b` per lane (NaN in either gives `b`; module docs).
#[inline(always)]
pub fn max_or_rhs<L: Lanes>(a: L, b: L) -> L {
    a.max_or_rhs(b)
}

/// `a < b ? a : b` per lane (NaN in either gives `b`; module docs).
#[inline(always)]
pub fn min_or_rhs<L: Lanes>(a: L, b: L) -> L {
    a.min_or_rhs(b)
}

/// `|x|` per lane as `x < 0 ? 0 - x : x` (`-0.0` and NaN pass through unchanged). A plain
/// function, not a closure, so that a kernel compiled with target features inlines its lane
/// operations.
#[inline(always)]
pub fn abs_lanes<L: Lanes>(x: L) -> L {
    let zero = L::splat(0.0);
    L::select(x.lt(zero), zero - x, x)
}

/// One lane: the scalar reference every other implementation is tested against.
impl Lanes for f32 {
    const N: usize = 1;
    type M = bool;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        f(0)
    }
    #[inline(always)]
    fn get(self, _i: usize) -> f32 {
        self
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> bool {
        self < o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn eq(self, o: Self) -> bool {
        self == o
    }
    #[inline(always)]
    fn ne(self, o: Self) -> bool {
        self != o
    }
    #[inline(always)]
    fn max_or_rhs(self, o: Self) -> Self {
        if self > o { self } else { o }
    }
    #[inline(always)]
    fn min_or_rhs(self, o: Self) -> Self {
        if self < o { self } else { o }
    }
    #[inline(always)]
    fn and(a: bool, b: bool) -> bool {
        a & b
    }
    #[inline(always)]
    fn or(a: bool, b: bool) -> bool {
        a | b
    }
    #[inline(always)]
    fn bits(m: bool) -> u32 {
        m as u32
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        self.is_sign_negative() as u32
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
}

/// Four lanes: glam's `Vec4` (SSE2 on x86_64, plain f32 elsewhere).
impl Lanes for Vec4 {
    const N: usize = 4;
    type M = BVec4A;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        Vec4::new(f(0), f(1), f(2), f(3))
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        self[i]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Vec4::from_array(self.to_array().map(f32::sqrt))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> BVec4A {
        self.cmplt(o)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> BVec4A {
        self.cmpgt(o)
    }
    #[inline(always)]
    fn le(self, o: Self) -> BVec4A {
        self.cmple(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> BVec4A {
        self.cmpge(o)
    }
    #[inline(always)]
    fn eq(self, o: Self) -> BVec4A {
        self.cmpeq(o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> BVec4A {
        self.cmpne(o)
    }
    #[inline(always)]
    fn max_or_rhs(self, o: Self) -> Self {
        #[cfg(all(
            any(target_arch = "x86", target_arch = "x86_64"),
            target_feature = "sse2"
        ))]
        {
            // _mm_max_ps(a, b) = a > b ? a : b (Intel SDM, MAXPS).
            self.max(o)
        }
        #[cfg(not(all(
            any(target_arch = "x86", target_arch = "x86_64"),
            target_feature = "sse2"
        )))]
        {
            Vec4::select(self.cmpgt(o), self, o)
        }
    }
    #[inline(always)]
    fn min_or_rhs(self, o: Self) -> Self {
        #[cfg(all(
            any(target_arch = "x86", target_arch = "x86_64"),
            target_feature = "sse2"
        ))]
        {
            // _mm_min_ps(a, b) = a < b ? a : b (Intel SDM, MINPS).
            self.min(o)
        }
        #[cfg(not(all(
            any(target_arch = "x86", target_arch = "x86_64"),
            target_feature = "sse2"
        )))]
        {
            Vec4::select(self.cmplt(o), self, o)
        }
    }
    #[inline(always)]
    fn and(a: BVec4A, b: BVec4A) -> BVec4A {
        a & b
    }
    #[inline(always)]
    fn or(a: BVec4A, b: BVec4A) -> BVec4A {
        a | b
    }
    #[inline(always)]
    fn bits(m: BVec4A) -> u32 {
        m.bitmask()
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        self.is_negative_bitmask()
    }
    #[inline(always)]
    fn select(m: BVec4A, a: Self, b: Self) -> Self {
        Vec4::select(m, a, b)
    }
}

/// Eight lanes as plain `[f32; 8]` loops. Meant to be instantiated inside a
/// `#[target_feature(enable = "avx2")]` function, where LLVM turns each loop into one AVX
/// instruction (`vaddps`, `vcmpps`, `vblendvps`, `vmovmskps`, `vsqrtps`, ...); elsewhere they are
/// correct, only slower. Plain loops rather than `std::arch` intrinsics: intrinsics cannot be
/// inlined into a kernel's closures, which have no target features of their own.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct F8(pub [f32; 8]);

/// The mask of [`F8`]: all bits set in a true lane.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct M8(pub [u32; 8]);

macro_rules! binop {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for F8 {
            type Output = F8;
            #[inline(always)]
            fn $f(self, o: F8) -> F8 {
                let mut r = [0.0f32; 8];
                for i in 0..8 {
                    r[i] = self.0[i] $op o.0[i];
                }
                F8(r)
            }
        }
    };
}
binop!(Add, add, +);
binop!(Sub, sub, -);
binop!(Mul, mul, *);
binop!(Div, div, /);

macro_rules! cmp {
    ($f:ident, $e:expr) => {
        #[inline(always)]
        fn $f(self, o: Self) -> M8 {
            let mut r = [0u32; 8];
            for i in 0..8 {
                let f: fn(f32, f32) -> bool = $e;
                r[i] = if f(self.0[i], o.0[i]) { u32::MAX } else { 0 };
            }
            M8(r)
        }
    };
}

macro_rules! mask_op {
    ($f:ident, $op:tt) => {
        #[inline(always)]
        fn $f(a: M8, b: M8) -> M8 {
            let mut r = [0u32; 8];
            for i in 0..8 {
                r[i] = a.0[i] $op b.0[i];
            }
            M8(r)
        }
    };
}

impl Lanes for F8 {
    const N: usize = 8;
    type M = M8;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        F8([x; 8])
    }
    #[inline(always)]
    fn from_fn(mut f: impl FnMut(usize) -> f32) -> Self {
        F8([f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7)])
    }
    #[inline(always)]
    fn get(self, i: usize) -> f32 {
        self.0[i]
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        F8(self.0.map(f32::sqrt))
    }
    cmp!(lt, |a, b| a < b);
    cmp!(gt, |a, b| a > b);
    cmp!(le, |a, b| a <= b);
    cmp!(ge, |a, b| a >= b);
    cmp!(eq, |a, b| a == b);
    cmp!(ne, |a, b| a != b);
    #[inline(always)]
    fn max_or_rhs(self, o: Self) -> Self {
        F8::select(self.gt(o), self, o)
    }
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // the index addresses several arrays in step
    fn min_or_rhs(self, o: Self) -> Self {
        let mut r = [0.0f32; 8];
        for i in 0..8 {
            r[i] = if self.0[i] < o.0[i] {
                self.0[i]
            } else {
                o.0[i]
            };
        }
        F8(r)
    }
    mask_op!(and, &);
    mask_op!(or, |);
    #[inline(always)]
    fn bits(m: M8) -> u32 {
        let mut b = 0;
        for i in 0..8 {
            b |= (m.0[i] >> 31) << i;
        }
        b
    }
    #[inline(always)]
    fn sign_bits(self) -> u32 {
        let mut b = 0;
        for i in 0..8 {
            b |= (self.0[i].to_bits() >> 31) << i;
        }
        b
    }
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn select(m: M8, a: Self, b: Self) -> Self {
        let mut r = [0.0f32; 8];
        for i in 0..8 {
            r[i] = if m.0[i] != 0 { a.0[i] } else { b.0[i] };
        }
        F8(r)
    }
}

/// Bit-equal, or both NaN (NaN payloads may differ between constant folding and hardware).
fn same_f32(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// Test support for every [`Lanes`] implementation (here and in the technique crates): each
/// lane of `a` and `b` (holding `xs` and `ys`) gives, under min / max, the compares, the mask
/// logic, select and arithmetic, what the scalar `f32` gives. Panics naming the lane otherwise.
pub fn assert_lanes_match_scalar<L: Lanes>(a: L, b: L, xs: &[f32], ys: &[f32]) {
    assert!(
        xs.len() >= L::N && ys.len() >= L::N,
        "{} operands per side",
        L::N
    );
    for i in 0..L::N {
        let (x, y) = (xs[i], ys[i]);
        assert!(same_f32(a.get(i), x), "get lane {i}");
        assert!(
            same_f32(a.max_or_rhs(b).get(i), x.max_or_rhs(y)),
            "max lane {i}"
        );
        assert!(
            same_f32(a.min_or_rhs(b).get(i), x.min_or_rhs(y)),
            "min lane {i}"
        );
        assert!(
            same_f32(max_or_rhs(a, b).get(i), x.max_or_rhs(y)),
            "max_or_rhs lane {i}"
        );
        assert!(
            same_f32(min_or_rhs(a, b).get(i), x.min_or_rhs(y)),
            "min_or_rhs lane {i}"
        );
        let bit = |m: L::M| L::bits(m) >> i & 1 == 1;
        assert_eq!(bit(a.lt(b)), x < y, "lt lane {i}");
        assert_eq!(bit(a.gt(b)), x > y, "gt lane {i}");
        assert_eq!(bit(a.le(b)), x <= y, "le lane {i}");
        assert_eq!(bit(a.ge(b)), x >= y, "ge lane {i}");
        assert_eq!(bit(a.eq(b)), x == y, "eq lane {i}");
        assert_eq!(bit(a.ne(b)), x != y, "ne lane {i}");
        assert_eq!(
            a.sign_bits() >> i & 1 == 1,
            x.is_sign_negative(),
            "sign lane {i}"
        );
        assert_eq!(
            b.sign_bits() >> i & 1 == 1,
            y.is_sign_negative(),
            "sign lane {i}"
        );
        assert_eq!(bit(L::or(a.lt(b), a.eq(b))), x <= y, "or lane {i}");
        assert_eq!(bit(L::and(a.le(b), a.ge(b))), x == y, "and lane {i}");
        assert!(
            same_f32(L::select(a.lt(b), a, b).get(i), if x < y { x } else { y }),
            "select lane {i}"
        );
        assert!(
            same_f32((a * b + a / b - b).get(i), x * y + x / y - y),
            "arithmetic lane {i}"
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Operands covering NaN on either side, infinities and signed zeros.
    const A: [f32; 8] = [f32::NAN, 3.0, -1.0, f32::NAN, 0.0, -0.0, f32::INFINITY, 2.0];
    const B: [f32; 8] = [1.0, 2.0, 5.0, f32::INFINITY, -0.0, 0.0, f32::NAN, 2.0];

    /// Bit-equal, or both NaN (NaN payloads may differ between constant folding and hardware).
    fn same(a: f32, b: f32) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    /// Every lane of `L`'s min / max / compares equals the scalar (`f32`) implementation.
    fn check<L: Lanes>(load: impl Fn(&[f32]) -> L) {
        for start in (0..8).step_by(L::N) {
            let (a, b) = (load(&A[start..]), load(&B[start..]));
            assert_lanes_match_scalar(a, b, &A[start..start + L::N], &B[start..start + L::N]);
        }
    }

    /// (Moved from `parallax-bvh`'s former `simd.rs`, whose slab test now uses these.)
    #[test]
    fn nan_on_the_left_yields_the_right_operand() {
        let max_or_rhs_portable = |a: Vec4, b: Vec4| Vec4::select(a.cmpgt(b), a, b);
        let min_or_rhs_portable = |a: Vec4, b: Vec4| Vec4::select(a.cmplt(b), a, b);
        let a = Vec4::new(f32::NAN, 3.0, -1.0, f32::NAN);
        let b = Vec4::new(1.0, 2.0, 5.0, f32::INFINITY);
        let max = Vec4::new(1.0, 3.0, 5.0, f32::INFINITY);
        let min = Vec4::new(1.0, 2.0, -1.0, f32::INFINITY);
        for (got, want) in [
            (max_or_rhs(a, b), max),
            (max_or_rhs_portable(a, b), max),
            (min_or_rhs(a, b), min),
            (min_or_rhs_portable(a, b), min),
        ] {
            assert_eq!(got.to_array(), want.to_array());
        }
    }

    #[test]
    fn the_scalar_rule_returns_the_right_operand_on_nan() {
        assert_eq!(f32::NAN.max_or_rhs(1.0), 1.0);
        assert_eq!(f32::NAN.min_or_rhs(1.0), 1.0);
        assert!(1.0f32.max_or_rhs(f32::NAN).is_nan());
        assert!(1.0f32.min_or_rhs(f32::NAN).is_nan());
        assert!(same(0.0f32.max_or_rhs(-0.0), -0.0));
        assert!(same((-0.0f32).min_or_rhs(0.0), 0.0));
    }

    #[test]
    fn vec4_lanes_equal_the_scalar_rule() {
        check(|s| Vec4::new(s[0], s[1], s[2], s[3]));
        // The portable select form (used off x86) against the same rule.
        let (a, b) = (Vec4::from_slice(&A), Vec4::from_slice(&B));
        for i in 0..4 {
            assert!(same(
                Vec4::select(a.cmpgt(b), a, b)[i],
                A[i].max_or_rhs(B[i])
            ));
            assert!(same(
                Vec4::select(a.cmplt(b), a, b)[i],
                A[i].min_or_rhs(B[i])
            ));
        }
    }

    #[test]
    fn eight_lanes_equal_the_scalar_rule() {
        check(|s| F8(std::array::from_fn(|i| s[i])));
    }
}
