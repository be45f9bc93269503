//! The instruction set the reprojection passes run with. The passes are written for x86-64's
//! baseline (SSE2 lanes through glam and `std::arch`); on a CPU with AVX each pass's body over a
//! band of pixels is compiled a second time with AVX enabled and that build is chosen at run
//! time ([`Isa::detect`]), as the tracer's BVH traversal picks its AVX2 build. The AVX build
//! runs the same IEEE operations in the same order, in VEX encodings: three-operand forms that
//! need no register copies, splats and unaligned loads folded into the arithmetic. No fused
//! multiply-add is enabled and Rust never contracts `a * b + c` on its own, so every result
//! is the baseline build's bit for bit (tested per pass against [`Isa::BASELINE`]).
//!
//! **Invariants:** an [`Isa`] with AVX exists only where `is_x86_feature_detected!("avx")`
//! returned true, so `Isa::run` never executes an AVX instruction on a CPU without it.

/// The instruction set of a pass (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Isa {
    avx: bool,
}

impl Isa {
    /// x86-64's baseline (SSE2), or the target's own instruction set elsewhere.
    pub const BASELINE: Isa = Isa { avx: false };

    /// AVX where the CPU has it, else [`Self::BASELINE`].
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            Isa {
                avx: std::arch::is_x86_feature_detected!("avx"),
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Self::BASELINE
    }

    /// True for the AVX build.
    pub fn is_avx(self) -> bool {
        self.avx
    }

    /// Runs `f` (a pass's body, its callees inlined) in the build of this instruction set.
    #[inline(always)]
    pub(crate) fn run<R>(self, f: impl FnOnce() -> R) -> R {
        #[cfg(target_arch = "x86_64")]
        if self.avx {
            // SAFETY: `avx` is true only where the CPU was found to have AVX (`detect`).
            return unsafe { run_avx(f) };
        }
        f()
    }
}

/// `f()` compiled with AVX enabled (`f` is inlined into it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn run_avx<R>(f: impl FnOnce() -> R) -> R {
    f()
}
