//! Lane-wise min / max with a defined NaN rule, on glam's `Vec4` (SSE on x86_64).
//!
//! The slab test multiplies `(plane - origin) * inv_dir`; for a ray with a zero direction
//! component (`inv_dir = ±inf`) whose origin lies exactly on a slab plane this is `0 * inf = NaN`.
//! Such a ray lies inside the closed slab for its whole length, so the NaN must be *ignored*:
//! [`max_or_rhs`] / [`min_or_rhs`] return the right operand when the left one is NaN, and the
//! traversal keeps the right operand (the running accumulator) NaN-free.
//!
//! On x86 this is exactly `maxps` / `minps` (`a > b ? a : b`), which glam's SSE2 `Vec4::max` /
//! `min` compile to. glam documents its NaN behaviour as unspecified across back ends, so other
//! targets use an explicit compare-and-select. Both versions are tested.

use glam::Vec4;

/// `a > b ? a : b` per lane (NaN in `a` gives `b`).
#[inline(always)]
pub(crate) fn max_or_rhs(a: Vec4, b: Vec4) -> Vec4 {
    #[cfg(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse2"
    ))]
    {
        // _mm_max_ps(a, b) = a > b ? a : b (Intel SDM, MAXPS).
        a.max(b)
    }
    #[cfg(not(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse2"
    )))]
    {
        max_or_rhs_portable(a, b)
    }
}

/// `a < b ? a : b` per lane (NaN in `a` gives `b`).
#[inline(always)]
pub(crate) fn min_or_rhs(a: Vec4, b: Vec4) -> Vec4 {
    #[cfg(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse2"
    ))]
    {
        // _mm_min_ps(a, b) = a < b ? a : b (Intel SDM, MINPS).
        a.min(b)
    }
    #[cfg(not(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse2"
    )))]
    {
        min_or_rhs_portable(a, b)
    }
}

#[inline(always)]
#[allow(dead_code)]
pub(crate) fn max_or_rhs_portable(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmpgt(b), a, b)
}

#[inline(always)]
#[allow(dead_code)]
pub(crate) fn min_or_rhs_portable(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmplt(b), a, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_on_the_left_yields_the_right_operand() {
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
}
