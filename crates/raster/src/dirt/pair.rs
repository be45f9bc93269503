//! Two independent f64 divisions of the DIRT build in one packed SSE2 division (`divpd`):
//! the two reciprocals of a fragment's `w` range (its view-depth range, Fig. 6a), two
//! vertices' `1 / depth` in the projection, the `w` plane's two slopes, an edge's two slab
//! crossings. The divider is the build's scarcest unit (a division's latency is ~13 cycles
//! and the fragment's next steps wait for it); two lanes cost one division's time.
//!
//! Each lane is the IEEE division of its operands, so the results are bit for bit those of
//! the scalar `a / b` — the portable form, used off x86-64 and by the tests as the reference.
//! SSE2 is part of x86-64's baseline, so no runtime detection is needed.

/// `(a0 / b0, a1 / b1)`, bit for bit.
#[inline(always)]
pub(super) fn div2(a0: f64, a1: f64, b0: f64, b1: f64) -> (f64, f64) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtsd_f64, _mm_div_pd, _mm_set_pd, _mm_unpackhi_pd};
        // SAFETY: SSE2 is part of the x86-64 baseline every x86-64 target enables; the
        // intrinsics touch registers only.
        unsafe {
            let q = _mm_div_pd(_mm_set_pd(a1, a0), _mm_set_pd(b1, b0));
            (_mm_cvtsd_f64(q), _mm_cvtsd_f64(_mm_unpackhi_pd(q, q)))
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        div2_portable(a0, a1, b0, b1)
    }
}

/// The scalar twin of [`div2`].
#[inline(always)]
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
pub(super) fn div2_portable(a0: f64, a1: f64, b0: f64, b1: f64) -> (f64, f64) {
    (a0 / b0, a1 / b1)
}

/// `(1 / b0, 1 / b1)`, bit for bit.
#[inline(always)]
pub(super) fn recip2(b0: f64, b1: f64) -> (f64, f64) {
    div2(1.0, 1.0, b0, b1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The packed division gives the scalar divisions' bits on random operands of every
    /// magnitude, on signed zeros, subnormals, infinities and NaN (NaN compared as NaN).
    #[test]
    fn packed_equals_scalar() {
        let mut rng = parallax_core::Rng::new(11, 5);
        let mut v = vec![
            0.0,
            -0.0,
            1.0,
            -1.0,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE / 8.0,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            1e-300,
            3.0,
        ];
        for _ in 0..3000 {
            let m = [1e-8, 1.0, 1e3, 1e12][rng.next_u32() as usize % 4];
            v.push((rng.next_f32() as f64 - 0.3) * m + rng.next_f32() as f64 * 1e-9);
        }
        let same = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
        let mut n = 0u64;
        for (i, &a) in v.iter().enumerate() {
            for k in 0..40 {
                let b = v[(i * 31 + k * 97 + 7) % v.len()];
                let c = v[(i * 13 + k * 5 + 1) % v.len()];
                let d = v[(i + k * 211 + 3) % v.len()];
                let (p, q) = div2(a, c, b, d);
                let (rp, rq) = div2_portable(a, c, b, d);
                assert!(same(p, rp) && same(q, rq), "{a}/{b} {c}/{d}");
                let (p, q) = recip2(b, d);
                assert!(same(p, 1.0 / b) && same(q, 1.0 / d), "1/{b} 1/{d}");
                n += 1;
            }
        }
        assert!(n > 100_000, "{n}");
    }
}
