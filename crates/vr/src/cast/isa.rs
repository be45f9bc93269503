//! The instruction-set tiers of the set-up kernel (`cast/setup/mod.rs`) and the per-tile
//! triangle set-up (`cast/setup/tile.rs`): [`Isa`] names the widest tier a cast may use
//! ([`crate::CastOptions::isa`]), and [`Isa::available`] the tier that runs on this CPU (the
//! widest detected at or below it, checked at run time with `is_x86_feature_detected!`).
//! Every tier gives the same buffer bit for bit (lane types: `cast/lanes16.rs`,
//! `cast/lanes256.rs`, `cast/lanes512.rs`).
//!
//! | tier | 16-ray packets | per-tile set-up | needs |
//! |---|---|---|---|
//! | [`Isa::Sse`] | four SSE registers (`V16`, the portable twin) | 4 SSE lanes | x86-64 baseline (any target) |
//! | [`Isa::Avx2`] | two AVX registers (`Y16`) | 8 AVX lanes (`Y8`) | AVX2, BMI1, BMI2, LZCNT, POPCNT |
//! | [`Isa::Avx512`] | one AVX-512 register (`Z16`) | 16 AVX-512 lanes | AVX-512F and the AVX2 tier's features |

/// The widest instruction-set tier the set-up kernel may use (module docs); the kernel runs
/// the widest the CPU has at or below it ([`Isa::available`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    /// SSE lanes only (the portable twin; on other targets, plain Rust).
    Sse,
    /// AVX2 lanes where the CPU has them.
    Avx2,
    /// AVX-512F lanes where the CPU has them, else AVX2, else SSE.
    #[default]
    Avx512,
}

impl Isa {
    /// The tier that runs: the widest tier at or below `self` that this CPU supports.
    #[inline]
    pub fn available(self) -> Isa {
        // (The AVX-512 tier implies the AVX2 one: its 8-lane packets run the AVX2 lanes.)
        if self >= Isa::Avx512 && avx512_detected() && avx2_detected() {
            Isa::Avx512
        } else if self >= Isa::Avx2 && avx2_detected() {
            Isa::Avx2
        } else {
            Isa::Sse
        }
    }
}

/// Whether the CPU runs the AVX2 tier: AVX2 and the bit instructions its entry points enable
/// (`avx2,bmi1,bmi2,lzcnt,popcnt`).
#[inline]
pub fn avx2_detected() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt")
    }
    #[cfg(not(target_arch = "x86_64"))]
    false
}

/// Whether the CPU runs the AVX-512 tier: x86-64-v4 (AVX-512 F, VL, BW and DQ, and the AVX2
/// tier's features: the kernels' bit scans, population counts and shifts compile to `tzcnt`,
/// `popcnt`, `shrx`, `blsr` in both tiers).
#[inline]
pub fn avx512_detected() -> bool {
    parallax_core::cpu::x86_64_v4()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `available` never exceeds the request and is monotone in it.
    #[test]
    fn available_tier_is_at_most_the_request() {
        let tiers = [Isa::Sse, Isa::Avx2, Isa::Avx512];
        for &t in &tiers {
            assert!(t.available() <= t);
        }
        assert_eq!(Isa::Sse.available(), Isa::Sse);
        assert!(Isa::Avx2.available() <= Isa::Avx512.available());
        assert_eq!(Isa::Avx2.available() == Isa::Avx2, avx2_detected());
    }
}
