//! Where the set-up kernels write their results ([`Out`]): the visibility buffer's entries,
//! one subsample, one sample's run of subsamples or whole samples at a time.

use parallax_core::NO_ID;

use crate::cast::packet::{ClosestN, MAX_LANES};

/// Where the set-up kernels write their results: the visibility buffer's entries
/// `sample * spp + k` (raw pointers: every sample's entries are written by one tile only).
/// The kernels' `tri` values are the blocks' primitive ids (`parallax_bvh::Tri4::tri`), stored
/// as they are; a miss is `u32::MAX`, which is [`NO_ID`].
#[derive(Clone, Copy)]
pub(super) struct Out {
    pub prim: *mut u32,
    pub t: *mut f32,
    pub spp: usize,
}

const _: () = assert!(NO_ID == u32::MAX);

impl Out {
    /// Stores subsample `(i, k)`'s closest hit (`tri` = `u32::MAX`: none).
    ///
    /// # Safety
    /// Exclusive access to the entry, within the buffer (`test_tile_setup`).
    #[inline(always)]
    pub(super) unsafe fn one(&self, (i, k): (u32, u32), bt: f32, tri: u32) {
        let o = i as usize * self.spp + k as usize;
        // SAFETY: the caller's.
        unsafe {
            if tri == u32::MAX {
                *self.prim.add(o) = NO_ID;
                *self.t.add(o) = f32::INFINITY;
            } else {
                *self.prim.add(o) = tri;
                *self.t.add(o) = bt;
            }
        }
    }

    /// Stores lane `l` of `c` as the one subsample of sample `idx[l]` (`spp == 1`: entry
    /// `idx[l]`; a miss has `t = inf` in `c` and `tri = u32::MAX` = [`NO_ID`]).
    ///
    /// # Safety
    /// As [`Out::one`], for the entries `idx`.
    #[inline(always)]
    pub(super) unsafe fn spp1(&self, idx: &[u32], c: &ClosestN) {
        debug_assert_eq!(self.spp, 1);
        for (l, &i) in idx.iter().enumerate().take(MAX_LANES) {
            // SAFETY: the caller's.
            unsafe {
                *self.prim.add(i as usize) = c.tri[l];
                *self.t.add(i as usize) = c.t[l];
            }
        }
    }

    /// Stores `c`'s lanes as the whole samples `idx` (`spp` lanes each, in order: each
    /// sample's entries are contiguous).
    ///
    /// # Safety
    /// As [`Out::one`], for these samples' entries.
    #[inline(always)]
    pub(super) unsafe fn samples(&self, idx: &[u32], c: &ClosestN) {
        for (q, &i) in idx.iter().enumerate() {
            let (o, l0) = (i as usize * self.spp, q * self.spp);
            // SAFETY: the caller's; the buffers do not overlap `c`.
            unsafe {
                std::ptr::copy_nonoverlapping(c.t[l0..].as_ptr(), self.t.add(o), self.spp);
                std::ptr::copy_nonoverlapping(c.tri[l0..].as_ptr(), self.prim.add(o), self.spp);
            }
        }
    }

    /// Stores lanes `0..n` of `c`, the subsamples `k0..k0 + n` of sample `i` (contiguous
    /// entries; a miss has `t = inf` in `c` already).
    ///
    /// # Safety
    /// As [`Out::one`], for the `n` entries.
    #[inline(always)]
    pub(super) unsafe fn run(&self, (i, k0): (u32, u32), c: &ClosestN, n: usize) {
        let o = i as usize * self.spp + k0 as usize;
        let n = n.min(MAX_LANES);
        if n == MAX_LANES {
            // A full packet: fixed-size copies (vector stores, no `memcpy` call).
            // SAFETY: the caller's: `MAX_LANES` entries from `o`, not overlapping `c`.
            unsafe {
                (self.t.add(o) as *mut [f32; MAX_LANES]).write_unaligned(c.t);
                (self.prim.add(o) as *mut [u32; MAX_LANES]).write_unaligned(c.tri);
            }
            return;
        }
        // SAFETY: the caller's; the buffers do not overlap `c`, so each run is one copy (a
        // miss has `t = inf` and `tri = NO_ID` in `c` already).
        unsafe {
            std::ptr::copy_nonoverlapping(c.t.as_ptr(), self.t.add(o), n);
            std::ptr::copy_nonoverlapping(c.tri.as_ptr(), self.prim.add(o), n);
        }
    }

    /// [`Out::run`] of a full packet (`MAX_LANES` entries) by non-temporal stores where both
    /// arrays' entries are 16-byte aligned (x86-64): the entries are not read again by the
    /// cast, and streaming them saves the read of each line before its write. The
    /// [`crate::VisibilityBuffer`]'s arrays start on a cache line, so at 16 and 32 spp a
    /// packet's run is one whole line of each (a run across two lines writes two partial
    /// lines: measurements in `docs/notes/vr.md`). Elsewhere
    /// [`Out::run`]. The caller ends its stores with [`Out::fence`].
    ///
    /// # Safety
    /// As [`Out::run`].
    #[inline(always)]
    pub(super) unsafe fn run_streamed(&self, (i, k0): (u32, u32), c: &ClosestN) {
        let o = i as usize * self.spp + k0 as usize;
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{__m128, __m128i, _mm_loadu_ps, _mm_loadu_si128};
            use std::arch::x86_64::{_mm_stream_ps, _mm_stream_si128};
            // SAFETY: the caller's: `MAX_LANES` entries from `o`; aligned as checked.
            unsafe {
                let (t, prim) = (self.t.add(o), self.prim.add(o));
                if (t as usize | prim as usize) & 15 == 0 {
                    for q in 0..MAX_LANES / 4 {
                        let tv: __m128 = _mm_loadu_ps(c.t.as_ptr().add(4 * q));
                        _mm_stream_ps(t.add(4 * q), tv);
                        let pv: __m128i = _mm_loadu_si128(c.tri.as_ptr().add(4 * q).cast());
                        _mm_stream_si128(prim.add(4 * q).cast(), pv);
                    }
                    return;
                }
            }
        }
        // SAFETY: the caller's.
        unsafe { self.run((i, k0), c, MAX_LANES) };
    }

    /// Orders the non-temporal stores of [`Out::run_streamed`] before what follows (a store
    /// fence on x86-64).
    #[inline(always)]
    pub(super) fn fence(&self) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE is part of x86-64.
        unsafe {
            std::arch::x86_64::_mm_sfence()
        };
    }
}
