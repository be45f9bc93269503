//! One row of effective levels ([`super::tree::effective_levels`]) sixteen nodes per step in
//! SSE2 lanes (part of the x86_64 baseline): per node, its parent's effective level if that
//! is not [`NO_PLANE`], else the node's level `l` if it is a plane node, else [`NO_PLANE`] —
//! byte for byte the values of the scalar definition `tree::eff_row` (the twin test is in
//! `tree.rs`). The nodes' plane tags (sign bits of their first words) become byte masks by
//! arithmetic shifts and two saturating packs; the parents' bytes are doubled by one unpack.

use core::arch::x86_64::*;

use super::node::{NO_PLANE, Node};

/// `row[x]` for `x < n` from the parents' effective levels `prow` (node `x`'s parent is
/// `prow[x / 2]`) and the nodes `nrow` of level `l`; `n` = the largest multiple of 16 with
/// `n <= row.len()`, `n <= nrow.len()`, `n <= 2 prow.len()`. Returns `n`.
pub(super) fn eff_row16(row: &mut [u8], prow: &[u8], nrow: &[Node], l: u8) -> usize {
    let n = row.len().min(nrow.len()).min(2 * prow.len()) & !15;
    // SAFETY: SSE2 is part of the x86_64 baseline; for `x + 16 <= n` the loads read nodes
    // `x .. x + 16` (`Node` is `repr(C)`, two `u32`s, 16 bytes per pair) and parents
    // `x / 2 .. x / 2 + 8`, the store writes `row[x .. x + 16]`, all in bounds.
    unsafe {
        let lv = _mm_set1_epi8(l as i8);
        let ones = _mm_set1_epi8(-1);
        let mut x = 0;
        while x < n {
            let np = nrow.as_ptr().add(x) as *const f32;
            // Nodes `4 q .. 4 q + 4`: their first words, `-1` where the sign (plane) bit is set.
            let tags = |q: usize| {
                let lo = _mm_loadu_ps(np.add(8 * q));
                let hi = _mm_loadu_ps(np.add(8 * q + 4));
                _mm_srai_epi32::<31>(_mm_castps_si128(_mm_shuffle_ps::<0b10_00_10_00>(lo, hi)))
            };
            let planes = _mm_packs_epi16(
                _mm_packs_epi32(tags(0), tags(1)),
                _mm_packs_epi32(tags(2), tags(3)),
            );
            // `l` on planes, `NO_PLANE` (all ones) elsewhere.
            let own = _mm_or_si128(lv, _mm_xor_si128(planes, ones));
            let p = _mm_loadl_epi64(prow.as_ptr().add(x / 2) as *const __m128i);
            let p = _mm_unpacklo_epi8(p, p);
            let none = _mm_cmpeq_epi8(p, _mm_set1_epi8(NO_PLANE as i8));
            let out = _mm_or_si128(_mm_and_si128(none, own), _mm_andnot_si128(none, p));
            _mm_storeu_si128(row.as_mut_ptr().add(x) as *mut __m128i, out);
            x += 16;
        }
    }
    n
}
