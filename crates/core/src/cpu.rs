//! The x86-64 micro-architecture levels the CPU runs, detected at run time: the kernels that
//! exist in several copies (one per instruction-set tier, each compiled with
//! `#[target_feature]`) pick theirs with these. One definition of each level for the whole
//! workspace, so that a copy's feature list and its check cannot drift apart.
//!
//! | level | features checked |
//! |---|---|
//! | [`x86_64_v3`] | AVX2, FMA, F16C, BMI1, BMI2, LZCNT, POPCNT |
//! | [`x86_64_v4`] | `x86_64_v3` and AVX-512 F, VL, BW, DQ |
//!
//! On other architectures both are `false`.

/// Whether the CPU runs x86-64-v3 code (module docs).
#[inline]
pub fn x86_64_v3() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        has!("avx2")
            && has!("fma")
            && has!("f16c")
            && has!("bmi1")
            && has!("bmi2")
            && has!("lzcnt")
            && has!("popcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Whether the CPU runs x86-64-v4 code (module docs).
#[inline]
pub fn x86_64_v4() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        x86_64_v3() && has!("avx512f") && has!("avx512vl") && has!("avx512bw") && has!("avx512dq")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}
