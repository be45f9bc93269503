//! Seeded random streams of the crate's unit tests.

/// Uniform floats in [0, 1) from an xorshift stream seeded with `x` (not 0).
pub(crate) fn uniform(mut x: u64) -> impl FnMut() -> f32 {
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 40) as f32 / (1u64 << 24) as f32
    }
}
