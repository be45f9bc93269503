//! The kept triangles of a set-up pack appended to the tile's list (HVVR, Hunt et al. 2018,
//! §5.5: the per-tile "triangle setup"; `cast/setup/tile.rs`): the pack's lanes
//! ([`super::lazy::LazySetupN::arrays`]: thirteen rows of one value per lane) become one
//! [`TriSetup`] each, in lane order, the dropped lanes skipped. [`push_kept`] is the portable
//! form, one field at a time; [`push_kept8_avx2`] transposes eight lanes in AVX registers
//! (two 8 x 8 transposes: the first 32 bytes of every [`TriSetup`], `n[0..2]`, `n[2][0..2]`,
//! and the next 32, `n[2][2]`, `g`, `tri`, `src`, `bound`, `rho`) and stores each kept lane's
//! 68 bytes directly into the list.
//!
//! **Invariant:** both give the same list, field for field and bit for bit (the transposes
//! only move bits; tested below).

use super::lazy::PACK;
use super::tri::TriSetup;

/// The kept lanes `keep` of a pack as set-up triangles: lane `l` of row `r` is `x[r][l]`
/// (`n_0 x, y, z, n_1 .., n_2 .., g x, y, z, bound`), its triangle index `tri[l]` (bits of
/// an f32 lane: the gather's), source `src[l]`, lazy band (`rho` NaN), all-in `inm >> l & 1`.
#[inline(always)]
pub(super) fn lane_of(
    x: &[[f32; PACK]; 13],
    l: usize,
    tri: u32,
    src: u32,
    all_in: bool,
) -> TriSetup {
    TriSetup {
        n: [
            [x[0][l], x[1][l], x[2][l]],
            [x[3][l], x[4][l], x[5][l]],
            [x[6][l], x[7][l], x[8][l]],
        ],
        g: [x[9][l], x[10][l], x[11][l]],
        tri,
        src,
        bound: x[12][l],
        rho: f32::NAN,
        all_in,
    }
}

/// Appends lanes `keep` (bits below `PACK`) of the pack `x` to `tris` in lane order
/// ([`lane_of`]); the portable form.
#[inline(always)]
pub(super) fn push_kept(
    tris: &mut Vec<TriSetup>,
    x: &[[f32; PACK]; 13],
    tri: &[f32; PACK],
    src: &[u32; PACK],
    keep: u32,
    inm: u32,
) {
    let mut k = keep;
    while k != 0 {
        let l = k.trailing_zeros() as usize;
        k &= k - 1;
        tris.push(lane_of(x, l, tri[l].to_bits(), src[l], inm >> l & 1 != 0));
    }
}

#[cfg(target_arch = "x86_64")]
const _: () = {
    use std::mem::{offset_of, size_of};
    assert!(offset_of!(TriSetup, n) == 0 && offset_of!(TriSetup, g) == 36);
    assert!(offset_of!(TriSetup, tri) == 48 && offset_of!(TriSetup, src) == 52);
    assert!(offset_of!(TriSetup, bound) == 56 && offset_of!(TriSetup, rho) == 60);
    assert!(offset_of!(TriSetup, all_in) == 64 && size_of::<TriSetup>() == 68);
};

/// [`push_kept`] for packs of eight lanes (`keep < 256`), by two 8 x 8 transposes in AVX
/// registers and two 32-byte stores per kept lane (module docs).
///
/// # Safety
/// The CPU must support AVX2 (only inside the AVX2 entry points).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn push_kept8_avx2(
    tris: &mut Vec<TriSetup>,
    x: &[[f32; PACK]; 13],
    tri: &[f32; PACK],
    src: &[u32; PACK],
    keep: u32,
    inm: u32,
) {
    use std::arch::x86_64::*;
    debug_assert!(keep < 256);
    // SAFETY: AVX2 code (the caller); every load reads 8 f32 of a 16-f32 row; the stores
    // write kept lane `i`'s 68 bytes at `tris[len + i]`, inside the reserved capacity
    // (`i < 8`), as `TriSetup`'s `repr(C)` layout places them (asserted above): the first
    // 32 bytes, the next 32, then `all_in` (0 or 1, a valid `bool`) and three padding bytes.
    unsafe {
        // (No closure: it would not be compiled with the caller's AVX features.)
        macro_rules! ld {
            ($r:expr) => {
                _mm256_loadu_ps($r.as_ptr())
            };
        }
        let a = transpose8([
            ld!(x[0]),
            ld!(x[1]),
            ld!(x[2]),
            ld!(x[3]),
            ld!(x[4]),
            ld!(x[5]),
            ld!(x[6]),
            ld!(x[7]),
        ]);
        let b = transpose8([
            ld!(x[8]),
            ld!(x[9]),
            ld!(x[10]),
            ld!(x[11]),
            ld!(tri),
            _mm256_castsi256_ps(_mm256_loadu_si256(src.as_ptr().cast())),
            ld!(x[12]),
            _mm256_set1_ps(f32::NAN),
        ]);
        tris.reserve(8);
        let len = tris.len();
        let dst = tris.as_mut_ptr().add(len).cast::<u8>();
        let mut k = 0usize;
        for l in 0..8 {
            if keep >> l & 1 != 0 {
                let p = dst.add(68 * k);
                _mm256_storeu_ps(p.cast(), a[l]);
                _mm256_storeu_ps(p.add(32).cast(), b[l]);
                p.add(64).cast::<u32>().write_unaligned(inm >> l & 1);
                k += 1;
            }
        }
        tris.set_len(len + k);
    }
}

/// The 8 x 8 transpose of `r` (`out[l]` = lane `l` of every row), bits moved only.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn transpose8(r: [std::arch::x86_64::__m256; 8]) -> [std::arch::x86_64::__m256; 8] {
    use std::arch::x86_64::*;
    // SAFETY: AVX code (the caller).
    unsafe {
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpackhi_ps(r[0], r[1]);
        let t2 = _mm256_unpacklo_ps(r[2], r[3]);
        let t3 = _mm256_unpackhi_ps(r[2], r[3]);
        let t4 = _mm256_unpacklo_ps(r[4], r[5]);
        let t5 = _mm256_unpackhi_ps(r[4], r[5]);
        let t6 = _mm256_unpacklo_ps(r[6], r[7]);
        let t7 = _mm256_unpackhi_ps(r[6], r[7]);
        let s0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let s1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
        let s2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let s3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
        let s4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let s5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
        let s6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let s7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
        [
            _mm256_permute2f128_ps::<0x20>(s0, s4),
            _mm256_permute2f128_ps::<0x20>(s1, s5),
            _mm256_permute2f128_ps::<0x20>(s2, s6),
            _mm256_permute2f128_ps::<0x20>(s3, s7),
            _mm256_permute2f128_ps::<0x31>(s0, s4),
            _mm256_permute2f128_ps::<0x31>(s1, s5),
            _mm256_permute2f128_ps::<0x31>(s2, s6),
            _mm256_permute2f128_ps::<0x31>(s3, s7),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The AVX2 transposes append the same triangles as the portable form, for every mask
    /// of kept lanes, on values with NaNs, infinities, signed zeros and arbitrary bits.
    #[test]
    fn push_kept8_equals_push_kept() {
        #[cfg(target_arch = "x86_64")]
        {
            if !crate::cast::isa::avx2_detected() {
                eprintln!("AVX2 not detected: push_kept8_avx2 not compared");
                return;
            }
            let mut seed = 0x9e37_79b9_7f4a_7c15u64;
            let mut next = move || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed as u32
            };
            let special = [
                f32::NAN,
                f32::INFINITY,
                -0.0,
                0.0,
                1.5,
                -3.25,
                f32::MIN_POSITIVE,
            ];
            let (mut a, mut b) = (Vec::new(), Vec::new());
            for round in 0..600u32 {
                let mut x = [[0.0f32; PACK]; 13];
                for r in x.iter_mut() {
                    for v in r.iter_mut() {
                        let w = next();
                        *v = if w % 5 == 0 {
                            special[(w / 5) as usize % special.len()]
                        } else {
                            f32::from_bits(next())
                        };
                    }
                }
                let tri: [f32; PACK] = std::array::from_fn(|_| f32::from_bits(next()));
                let src: [u32; PACK] = std::array::from_fn(|_| next());
                let (keep, inm) = (round % 256, next() & 0xff);
                // Lists grow across rounds (capacity and offsets vary).
                push_kept(&mut a, &x, &tri, &src, keep, inm);
                // SAFETY: AVX2 detected above.
                unsafe { push_kept8_avx2(&mut b, &x, &tri, &src, keep, inm) };
                if round % 97 == 0 {
                    a.clear();
                    b.clear();
                }
                assert_eq!(a.len(), b.len());
                for (s, t) in a.iter().zip(&b) {
                    assert_eq!(s.bits(), t.bits(), "round {round}");
                }
            }
            assert!(!a.is_empty());
        }
    }
}
