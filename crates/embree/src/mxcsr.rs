//! Flush-to-zero / denormals-are-zero for the duration of an Embree call batch.
//!
//! Embree asks its callers to trace with FTZ and DAZ set (MXCSR bits 15 and 6); parallax's own
//! code relies on IEEE denormals (the watertight test's exactness), so the flags are set only
//! inside [`FastFloats`]' scope and the previous MXCSR is restored when it ends. MXCSR is per
//! thread, so each rayon task that calls Embree opens its own scope.

/// Sets FTZ and DAZ on this thread until dropped (a no-op off x86_64).
pub struct FastFloats {
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

#[cfg(target_arch = "x86_64")]
const FTZ_DAZ: u32 = 1 << 15 | 1 << 6;

impl FastFloats {
    #[inline]
    #[allow(clippy::new_without_default)]
    pub fn new() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let saved = read();
            write(saved | FTZ_DAZ);
            Self { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        Self {}
    }
}

impl Drop for FastFloats {
    #[inline]
    fn drop(&mut self) {
        #[cfg(target_arch = "x86_64")]
        write(self.saved);
    }
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn read() -> u32 {
    let mut csr = 0u32;
    // SAFETY: STMXCSR stores the 32-bit MXCSR to the given address (SSE, always on x86_64).
    unsafe {
        std::arch::asm!("stmxcsr [{}]", in(reg) &mut csr, options(nostack, preserves_flags));
    }
    csr
}

#[cfg(target_arch = "x86_64")]
#[inline]
fn write(csr: u32) {
    // SAFETY: LDMXCSR loads MXCSR; only the FTZ / DAZ bits differ from a value read before,
    // and both are defined, reserved-bit-free flags.
    unsafe {
        std::arch::asm!("ldmxcsr [{}]", in(reg) &csr, options(nostack, preserves_flags));
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;

    #[test]
    fn flags_are_set_inside_and_restored_after() {
        let before = read();
        {
            let _g = FastFloats::new();
            assert_eq!(read() & FTZ_DAZ, FTZ_DAZ);
            // Denormals flush to zero inside the scope.
            let tiny = std::hint::black_box(f32::MIN_POSITIVE);
            assert_eq!(std::hint::black_box(tiny * 0.5), 0.0);
        }
        assert_eq!(read(), before);
        let tiny = std::hint::black_box(f32::MIN_POSITIVE);
        assert!(std::hint::black_box(tiny * 0.5) > 0.0);
    }
}
