//! Stack keys of an 8-wide node's hit children, compressed (the single-ray traversal of
//! `traverse8.rs`; Wald et al. 2014 §4, nearest child first).
//!
//! A key is `t_near bits << 32 | child`: the entry distance of a hit lane (`>= t_min >= 0`, so
//! its bits order as the float) above the child reference. [`compress_keys`] returns the keys
//! of the lanes set in `mask`, in lane order, in the first `mask.count_ones()` entries, and `0`
//! in the others. A key is never `0` (child `0` is the root, no node's child), so the padding
//! sorts below every key: a descending sort of all eight leaves the hit keys first.
//!
//! The AVX2 form ([`compress_keys_avx2`]) has no loop and no branch: one `vpermd` per row by
//! the mask's row of [`COMPRESS`] (hit lanes to the front), the lanes from the hit count on
//! zeroed, the two rows interleaved into 64-bit keys. Its portable twin is the loop over set
//! bits; the test below holds them equal for all 256 masks.
//!
//! | item | value |
//! |---|---|
//! | [`COMPRESS`] | 256 rows of 8 one-byte lane indices (2 KB) |
//! | instructions (AVX2) | ~14, no branch |
//!
//! Two hit lanes (the most frequent case of several) take [`pair_keys`] instead: the two
//! lanes by `tzcnt`, their keys read directly (one store of the distance row with AVX2).

/// `COMPRESS[m]`, byte `j`: the lane of the `j`-th set bit of `m` (low bits first); bytes at
/// and above `m.count_ones()` are `0`.
pub(crate) const COMPRESS: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut m = 0;
    while m < 256 {
        let (mut c, mut n) = (0, 0);
        while c < 8 {
            if m >> c & 1 != 0 {
                t[m] |= (c as u64) << (8 * n);
                n += 1;
            }
            c += 1;
        }
        m += 1;
    }
    t
};

/// The keys of the lanes of `mask` (low 8 bits), compressed (module docs): the portable twin.
#[inline(always)]
pub(crate) fn compress_keys(t: [f32; 8], child: &[u32; 8], mask: u32) -> [u64; 8] {
    let mut ks = [0u64; 8];
    let (mut m, mut n) = (mask & 0xFF, 0);
    while m != 0 {
        let c = m.trailing_zeros() as usize;
        m &= m - 1;
        ks[n] = (t[c].to_bits() as u64) << 32 | child[c] as u64;
        n += 1;
    }
    ks
}

/// [`compress_keys`] with AVX2, branch-free (module docs).
///
/// # Safety
/// The CPU must support AVX2 and POPCNT; `child` must be 32-byte aligned (a `Node8`'s is).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) unsafe fn compress_keys_avx2(
    t: std::arch::x86_64::__m256,
    child: &[u32; 8],
    mask: u32,
) -> [u64; 8] {
    use std::arch::x86_64::*;
    // SAFETY: AVX2 (caller); `m < 256` indexes `COMPRESS`; `child` is 32-byte aligned (caller).
    unsafe {
        let m = (mask & 0xFF) as usize;
        let idx = _mm256_cvtepu8_epi32(_mm_loadl_epi64(COMPRESS.as_ptr().add(m) as *const __m128i));
        let keep = _mm256_cmpgt_epi32(
            _mm256_set1_epi32(m.count_ones() as i32),
            _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
        );
        let child = _mm256_load_si256(child.as_ptr() as *const __m256i);
        let child = _mm256_and_si256(_mm256_permutevar8x32_epi32(child, idx), keep);
        let tb = _mm256_castps_si256(t);
        let tb = _mm256_and_si256(_mm256_permutevar8x32_epi32(tb, idx), keep);
        // Interleave the children (low halves) with the distance bits (high halves), then
        // restore lane order: `lo` = keys 0, 1 | 4, 5, `hi` = 2, 3 | 6, 7.
        let lo = _mm256_unpacklo_epi32(child, tb);
        let hi = _mm256_unpackhi_epi32(child, tb);
        let mut keys = [0u64; 8];
        let kp = keys.as_mut_ptr() as *mut __m256i;
        _mm256_storeu_si256(kp, _mm256_permute2x128_si256::<0x20>(lo, hi));
        _mm256_storeu_si256(kp.add(1), _mm256_permute2x128_si256::<0x31>(lo, hi));
        keys
    }
}

/// The keys of the two lanes of a two-bit `mask`, in lane order: [`compress_keys`]' first two
/// entries, without the compression (the traversal's most frequent case of several hits).
#[inline(always)]
pub(crate) fn pair_keys(t: &[f32; 8], child: &[u32; 8], mask: u32) -> (u64, u64) {
    debug_assert_eq!(mask.count_ones(), 2);
    let (i, j) = (
        mask.trailing_zeros() as usize & 7,
        (mask & mask.wrapping_sub(1)).trailing_zeros() as usize & 7,
    );
    let key = |c: usize| (t[c].to_bits() as u64) << 32 | child[c] as u64;
    (key(i), key(j))
}

/// [`pair_keys`] of AVX2 distances: one store of the row, two scalar reads.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) unsafe fn pair_keys_avx2(
    t: std::arch::x86_64::__m256,
    child: &[u32; 8],
    mask: u32,
) -> (u64, u64) {
    let mut ts = [0f32; 8];
    // SAFETY: AVX (caller); `ts` holds 8 f32.
    unsafe { std::arch::x86_64::_mm256_storeu_ps(ts.as_mut_ptr(), t) };
    pair_keys(&ts, child, mask)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[repr(C, align(32))]
    struct Row([u32; 8]);

    /// Every mask: the portable keys are the hit lanes' keys in lane order, then zeros; the
    /// AVX2 keys equal them bit for bit; for two-bit masks, the pair keys are the first two.
    #[test]
    fn compressed_keys_of_every_mask() {
        let t = [0.5f32, 0.0, 3.0, 1e-30, 7.25, f32::INFINITY, 2.0, 1e30];
        let child = Row([11, 0x8000_0005, 13, 14, 0x8000_0100, 16, 17, 9]);
        for mask in 0u32..256 {
            let ks = compress_keys(t, &child.0, mask | 0xF00);
            let lanes: Vec<usize> = (0..8).filter(|c| mask >> c & 1 != 0).collect();
            for (j, k) in ks.iter().enumerate() {
                let want = lanes
                    .get(j)
                    .map_or(0, |&c| (t[c].to_bits() as u64) << 32 | child.0[c] as u64);
                assert_eq!(*k, want, "mask {mask:#x} entry {j}");
            }
            if mask.count_ones() == 2 {
                assert_eq!(
                    pair_keys(&t, &child.0, mask),
                    (ks[0], ks[1]),
                    "mask {mask:#x}"
                );
                #[cfg(target_arch = "x86_64")]
                if std::is_x86_feature_detected!("avx") {
                    // SAFETY: AVX detected.
                    let kp = unsafe {
                        let tv = std::arch::x86_64::_mm256_loadu_ps(t.as_ptr());
                        pair_keys_avx2(tv, &child.0, mask)
                    };
                    assert_eq!(kp, (ks[0], ks[1]), "mask {mask:#x}: AVX pair keys");
                }
            }
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("popcnt") {
                // SAFETY: AVX2 and POPCNT detected; `Row` is 32-byte aligned.
                let kv = unsafe {
                    let tv = std::arch::x86_64::_mm256_loadu_ps(t.as_ptr());
                    compress_keys_avx2(tv, &child.0, mask)
                };
                assert_eq!(kv, ks, "mask {mask:#x}: AVX2 against portable");
            }
        }
    }
}
