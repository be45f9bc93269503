//! The gather of a tile's triangles for the per-tile set-up (HVVR, Hunt et al. 2018, §5.5:
//! "triangle setup"; `cast/setup/tile.rs`): the triangles of the tile's leaves in list order
//! (leaf by leaf, block by block, lane by lane), their nine vertex coordinates, triangle index
//! and source (`4 * block + lane`; both as f32 bits) written as eleven rows of one value per
//! triangle ([`TileRows`]), so the set-up loads a pack of `L::N` consecutive triangles with one
//! load per row. Each leaf block's valid lanes (`tri != u32::MAX`, inside the leaf's count) are
//! moved to the front: one lane at a time in the portable form, with one `vpermilps` per row
//! (a 16-entry table of lane orders) where the CPU has AVX ([`TileRows::gather`]).
//!
//! **Each triangle once.** A build with spatial splits (the SBVH, the BVH's default) puts a
//! triangle in every leaf that holds a piece of it, and a tile's list often holds two of them:
//! the same triangle set up twice, tested twice per ray, and, tying with itself at the same
//! `1/t`, sent to the watertight test by the depth band (`SetupExactness::Full`). The gather
//! keeps a triangle's first entry in list order and drops the later ones ([`SeenIds`]: the
//! ids kept so far in this tile, no allocation once grown), looking up only the lanes
//! [`parallax_bvh::Bvh::block_copies`] marks (a triangle in one leaf cannot repeat). The first entry is in the leaf of
//! smallest near depth among those holding the triangle, and every hit on the triangle lies in
//! the box of one of them, at or beyond that near depth; so the kernels' early exit before
//! that leaf is still valid. The leaf's run box is the box of its kept triangles, whole
//! (`cast/setup/tile.rs`), so the packets' leaf box test sees the whole triangle too. The
//! scalar set-up ([`super::setup_tile_scalar`]) drops the same entries.
//!
//! **Invariant:** both forms write the same first `len` entries of every row and the same leaf
//! ends (the AVX form also writes up to three entries past a block's valid lanes, which the
//! next block overwrites or which stay past `len`); values are moved, never computed on
//! (tested below).
//!
//! | name | value | meaning |
//! |---|---|---|
//! | `PREFETCH_LEAVES` | 8 | leaves ahead whose triangle blocks are prefetched |
//! | [`ROWS`] | 11 | `p[v][a]` at `3 v + a`, then `tri`, `src` |
//! | [`PAD`] | 16 | entries past `len` in every row |

use parallax_bvh::Tri4;
use parallax_bvh::node::{leaf_count, leaf_first};

use crate::beam::LeafRef;

/// Rows of [`TileRows`]: vertex `v` axis `a` at `3 v + a`, the triangle index at 9, the
/// source at 10.
pub const ROWS: usize = 11;

/// Entries past `len` every row holds: a pack of up to this many lanes loads inside the rows
/// (at least the set-up's largest pack, asserted in `cast/setup/tile.rs`).
pub const PAD: usize = 16;

/// Leaves ahead of the gather whose triangle blocks are prefetched ([`prefetch_leaf`]).
const PREFETCH_LEAVES: usize = 8;

/// A tile's triangles in list order, one row per value (module docs); every row holds at
/// least `len + PAD` entries, so a pack's load past `len` stays inside.
#[derive(Clone, Debug, Default)]
pub struct TileRows {
    pub rows: [Vec<f32>; ROWS],
    pub len: usize,
    /// Entries of the last gather's leaves dropped as repeats of a kept triangle.
    pub repeated: u64,
    /// The triangle ids kept by the last gather (or by the scalar set-up).
    pub seen: SeenIds,
}

/// The triangle ids kept so far in one tile's list (module docs, "each triangle once"): open
/// addressing with linear probing over `2^k >= 2 n` slots for a tile of at most `n` entries,
/// each slot `stamp << 32 | id` with the tile's stamp, so a tile starts without clearing the
/// table and a slot of an earlier tile reads as empty.
#[derive(Clone, Debug, Default)]
pub struct SeenIds {
    slots: Vec<u64>,
    /// The current tile's stamp (never 0 once begun: 0 marks a slot never written).
    stamp: u32,
    /// `64 - k`: a hash's top `k` bits index the slots.
    shift: u32,
}

impl SeenIds {
    /// Starts a tile of at most `n` entries (grows the table if needed).
    pub fn begin(&mut self, n: usize) {
        let bits = (2 * n.max(8)).next_power_of_two().trailing_zeros();
        let size = 1usize << bits;
        if self.slots.len() < size {
            self.slots.resize(size, 0);
        }
        self.shift = 64 - bits;
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.slots.fill(0);
            self.stamp = 1;
        }
    }

    /// Records `id` in this tile; false if it was recorded before. At most the `n` of
    /// [`SeenIds::begin`] ids per tile (the table stays at most half full, so probing ends).
    #[inline(always)]
    pub fn insert(&mut self, id: u32) -> bool {
        let mask = (1usize << (64 - self.shift)) - 1;
        // Fibonacci hashing: the top bits of `id * 2^64 / phi` (consecutive ids spread).
        let mut i = ((id as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15) >> self.shift) as usize;
        let tagged = (self.stamp as u64) << 32 | id as u64;
        loop {
            let s = self.slots[i];
            if s == tagged {
                return false;
            }
            if (s >> 32) as u32 != self.stamp {
                self.slots[i] = tagged;
                return true;
            }
            i = (i + 1) & mask;
        }
    }

    /// The lanes of `m` whose triangle of `b` is new in this tile, the lanes of `copies` (their
    /// triangles sit in several leaves) looked up and recorded in lane order, the others kept
    /// without a look-up (a triangle in one leaf reaches a tile's list once).
    #[inline(always)]
    fn keep_new_copies(&mut self, b: &Tri4, m: u32, copies: u32) -> u32 {
        let mut keep = m;
        let mut w = m & copies;
        while w != 0 {
            let l = w.trailing_zeros() as usize;
            w &= w - 1;
            if !self.insert(b.tri[l]) {
                keep &= !(1 << l);
            }
        }
        keep
    }
}

/// Prefetches the triangle blocks of leaf `r` (every cache line of each 160-byte [`Tri4`]):
/// the set-up's first touch of a block (its `tri` indices, then its vertices) was its most
/// expensive load (thread CPU time, `docs/notes/vr.md`). No effect on any value.
#[inline(always)]
fn prefetch_leaf(blocks: &[Tri4], r: u32) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let first = leaf_first(r) as usize;
        let end = (first + leaf_count(r).div_ceil(4) as usize).min(blocks.len());
        for b in blocks.get(first..end).unwrap_or(&[]) {
            let p = (b as *const Tri4).cast::<i8>();
            // SAFETY: prefetches never fault; the offsets stay inside the block.
            unsafe {
                _mm_prefetch::<_MM_HINT_T0>(p);
                _mm_prefetch::<_MM_HINT_T0>(p.add(64));
                _mm_prefetch::<_MM_HINT_T0>(p.add(128));
                _mm_prefetch::<_MM_HINT_T0>(p.add(159));
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (blocks, r);
}

/// `ORDER[m]`: the lanes of the mask `m` (4 bits) in increasing order, then zeros.
const ORDER: [[u32; 4]; 16] = {
    let mut t = [[0u32; 4]; 16];
    let mut m = 0;
    while m < 16 {
        let (mut k, mut l) = (0, 0);
        while l < 4 {
            if m >> l & 1 != 0 {
                t[m][k] = l as u32;
                k += 1;
            }
            l += 1;
        }
        m += 1;
    }
    t
};

/// The lanes of `b` that hold a triangle (`tri != u32::MAX`).
#[inline(always)]
fn filled(b: &Tri4) -> u32 {
    (0..4).fold(0, |m, l| m | ((b.tri[l] != u32::MAX) as u32) << l)
}

impl TileRows {
    /// Gathers the triangles of `leaves`, each once (module docs), and sets `ends[k]` to the
    /// number of triangles kept from the leaves `0..=k`. `copies`: per block the lanes whose
    /// triangle sits in several leaves ([`parallax_bvh::Bvh::block_copies`]; empty: none), the
    /// only ones looked up in [`SeenIds`]. `avx`: the AVX form where the CPU has AVX2 (else the
    /// portable one).
    #[inline(always)]
    pub fn gather(
        &mut self,
        blocks: &[Tri4],
        copies: &[u8],
        leaves: &[LeafRef],
        avx: bool,
        ends: &mut Vec<u32>,
    ) {
        let total: usize = leaves.iter().map(|r| leaf_count(r.leaf) as usize).sum();
        let cap = total + PAD + 4;
        for r in &mut self.rows {
            if r.len() < cap {
                r.resize(cap, 0.0);
            }
        }
        ends.clear();
        let dedup = !copies.is_empty();
        if dedup {
            self.seen.begin(total);
        }
        let mut repeated = 0;
        #[cfg(target_arch = "x86_64")]
        let avx = avx && crate::cast::isa::avx2_detected();
        #[cfg(not(target_arch = "x86_64"))]
        let _ = avx;
        for r in leaves.iter().take(PREFETCH_LEAVES) {
            prefetch_leaf(blocks, r.leaf);
        }
        let mut off = 0usize;
        for (li, r) in leaves.iter().enumerate() {
            if let Some(ahead) = leaves.get(li + PREFETCH_LEAVES) {
                prefetch_leaf(blocks, ahead.leaf);
            }
            let (first, count) = (leaf_first(r.leaf), leaf_count(r.leaf));
            for k in 0..count.div_ceil(4) {
                let bi = first + k;
                let b = &blocks[bi as usize];
                let inside = (1u32 << (count - 4 * k).min(4)) - 1;
                let valid = inside & filled(b);
                let m = if dedup {
                    self.seen
                        .keep_new_copies(b, valid, copies[bi as usize] as u32)
                } else {
                    valid
                };
                repeated += (valid & !m).count_ones() as u64;
                #[cfg(target_arch = "x86_64")]
                if avx {
                    // SAFETY: AVX detected (`avx` below); `off + 4 <= cap` (`off` counts
                    // triangles of the leaves so far, at most `total`).
                    off = unsafe { self.block_avx(b, bi, m, off) };
                    continue;
                }
                off = self.block(b, bi, m, off);
            }
            ends.push(off as u32);
        }
        self.len = off;
        self.repeated = repeated;
    }

    /// The lanes `m` of block `bi` at `off..`, one at a time; the new end.
    #[inline(always)]
    fn block(&mut self, b: &Tri4, bi: u32, m: u32, mut off: usize) -> usize {
        for l in 0..4 {
            if m >> l & 1 != 0 {
                for v in 0..3 {
                    for a in 0..3 {
                        self.rows[3 * v + a][off] = b.p[v][a][l];
                    }
                }
                self.rows[9][off] = f32::from_bits(b.tri[l]);
                self.rows[10][off] = f32::from_bits(4 * bi + l as u32);
                off += 1;
            }
        }
        off
    }

    /// [`TileRows::block`] with one `vpermilps` per row and four-lane stores (module docs).
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    unsafe fn block_avx(&mut self, b: &Tri4, bi: u32, m: u32, off: usize) -> usize {
        use std::arch::x86_64::*;
        assert!(off + 4 <= self.rows[0].len() && m < 16);
        // SAFETY: AVX (the caller); every row holds at least `off + 4` entries (all rows have
        // the same length, `gather`), the loads read a block's 16-byte lanes.
        unsafe {
            let t = _mm_loadu_si128(b.tri.as_ptr().cast());
            let perm = _mm_loadu_si128(ORDER[m as usize].as_ptr().cast());
            for v in 0..3 {
                for a in 0..3 {
                    let x = _mm_loadu_ps(b.p[v][a].as_ref().as_ptr());
                    let dst = self.rows[3 * v + a].as_mut_ptr().add(off);
                    _mm_storeu_ps(dst, _mm_permutevar_ps(x, perm));
                }
            }
            let src = _mm_add_epi32(_mm_set1_epi32((4 * bi) as i32), _mm_setr_epi32(0, 1, 2, 3));
            let dst = self.rows[9].as_mut_ptr().add(off);
            _mm_storeu_ps(dst, _mm_permutevar_ps(_mm_castsi128_ps(t), perm));
            let dst = self.rows[10].as_mut_ptr().add(off);
            _mm_storeu_ps(dst, _mm_permutevar_ps(_mm_castsi128_ps(src), perm));
            off + m.count_ones() as usize
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_bvh::node::ChildRef;

    /// `SeenIds` answers as a fresh hash set per tile: tiles of 0 to 3000 entries (the table
    /// grows and shrinks its mask), ids clustered or spread, and the stamp wrapping around
    /// (the table cleared once, no slot of an earlier tile read as this tile's).
    #[test]
    fn seen_ids_equal_a_hash_set_per_tile() {
        let mut seen = SeenIds::default();
        let mut x = 0x9e37_79b9u32;
        for tile in 0..400u32 {
            if tile == 200 {
                seen.stamp = u32::MAX - 2;
            }
            let n = ((tile * 7919) % 3001) as usize;
            seen.begin(n);
            let mut set = std::collections::HashSet::new();
            for k in 0..n {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                // Repeats, runs of consecutive ids and ids across the whole range.
                let id = match k % 3 {
                    0 => x % (n as u32 / 2 + 1),
                    1 => tile * 64 + k as u32 / 3,
                    _ => x,
                };
                assert_eq!(seen.insert(id), set.insert(id), "tile {tile} id {id}");
            }
        }
        assert!(seen.stamp < 200, "{}", seen.stamp);
    }

    /// The AVX gather writes the same rows (bit for bit, up to `len`) and leaf ends as the
    /// portable one, on blocks with filled and empty lanes in any pattern, arbitrary bits
    /// (NaNs, infinities, signed zeros) and leaves of 1 to 15 triangles; and both hold the
    /// list `4 * block + lane` of the valid lanes in order, a repeated triangle dropped where
    /// its lane is marked in `copies` (every lane, random lanes, none).
    #[test]
    fn avx_gather_equals_portable_gather() {
        #[cfg(target_arch = "x86_64")]
        {
            if !crate::cast::isa::avx2_detected() {
                eprintln!("AVX2 not detected: the AVX gather is not compared");
                return;
            }
            let mut seed = 0x2545_f491_4f6c_dd1du64;
            let mut next = move || {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                seed
            };
            let special = [f32::NAN, f32::INFINITY, -0.0, 0.0, -1.5, f32::MIN_POSITIVE];
            let mut blocks = vec![Tri4::EMPTY; 400];
            for (k, b) in blocks.iter_mut().enumerate() {
                for v in 0..3 {
                    for a in 0..3 {
                        for l in 0..4 {
                            let w = next();
                            b.p[v][a][l] = if w % 4 == 0 {
                                special[(w >> 8) as usize % special.len()]
                            } else {
                                f32::from_bits(w as u32)
                            };
                        }
                    }
                }
                for l in 0..4 {
                    b.tri[l] = if next() % 3 == 0 {
                        u32::MAX
                    } else {
                        (4 * k + l) as u32 ^ 0x5a5a
                    };
                }
            }
            let (mut a, mut b) = (TileRows::default(), TileRows::default());
            let (mut ea, mut eb) = (Vec::new(), Vec::new());
            let (mut lists, mut repeats) = (0, 0);
            // The lanes looked up in the seen set: every lane, random lanes, none (empty).
            let all = vec![15u8; blocks.len()];
            let some: Vec<u8> = (0..blocks.len()).map(|_| (next() % 16) as u8).collect();
            for round in 0..300 {
                let copies: &[u8] = match round % 3 {
                    0 => &all,
                    1 => &some,
                    _ => &[],
                };
                // Leaves in any order, of 1 to 15 triangles.
                let leaves: Vec<LeafRef> = (0..(round % 40 + 1))
                    .map(|_| {
                        let count = (next() % 15 + 1) as u32;
                        let first = (next() % (400 - 4)) as u32;
                        LeafRef {
                            leaf: ChildRef::Leaf { first, count }.encode(),
                            near: 0.0,
                        }
                    })
                    .collect();
                a.gather(&blocks, copies, &leaves, false, &mut ea);
                b.gather(&blocks, copies, &leaves, true, &mut eb);
                assert_eq!((a.len, &ea), (b.len, &eb));
                for (x, y) in a.rows.iter().zip(&b.rows) {
                    let bits =
                        |r: &[f32]| r[..a.len].iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                    assert_eq!(bits(x), bits(y));
                }
                // The list itself: every valid lane of every leaf, in order, each triangle
                // id of a marked lane once (leaves overlap here, as a split triangle's
                // leaves do; an unmarked lane is kept each time).
                let mut want = Vec::new();
                let mut seen = std::collections::HashSet::new();
                let mut dropped = 0;
                for r in &leaves {
                    let (first, count) = (leaf_first(r.leaf), leaf_count(r.leaf));
                    for j in 0..count {
                        let bi = first + j / 4;
                        let t = blocks[bi as usize].tri[(j % 4) as usize];
                        let marked = copies
                            .get(bi as usize)
                            .is_some_and(|&m| m >> (j % 4) & 1 != 0);
                        if t != u32::MAX {
                            if !marked || seen.insert(t) {
                                want.push(4 * first + j);
                            } else {
                                dropped += 1;
                            }
                        }
                    }
                }
                let got: Vec<u32> = a.rows[10][..a.len].iter().map(|v| v.to_bits()).collect();
                assert_eq!(got, want);
                assert_eq!((a.repeated, b.repeated), (dropped, dropped));
                lists += want.len();
                repeats += dropped;
            }
            assert!(lists > 10_000 && repeats > 100, "{lists} {repeats}");
        }
    }
}
