//! The level-0 cells as the walk reads them (Vardis et al. 2017, §4.2.1, Alg. 1 lines 7-11:
//! the cell's depth range for eq. 1, then the bucket's primitive list): one 64-byte line per
//! cell with the cell's record (`CellRecord`: `zmin`, the eq. 1 scale, the non-empty bucket
//! mask) *and* where each of its buckets' ids start, relative to the cell's first id.
//!
//! The capture keeps the records (16 bytes a cell) and the CSR offsets (`B + 1` `u32` a cell,
//! 68 bytes at `B = 16`) in two arrays, so a traced cell costs two dependent cache misses
//! before its ids: the record, then the offsets. On a CPU whose L2 holds neither array
//! (a 512 KiB L2 against ~0.5 MiB of records and ~2.2 MiB of offsets for the atrium's camera
//! view at 1024x512, tile 4, `B = 16`) both miss; here they are one line.
//!
//! **Invariants.** `bounds[b]` is `offsets[c B + b] - offsets[c B]` for `b in 0..=B` (so
//! bucket `b`'s ids are `ids[first + bounds[b]..first + bounds[b + 1]]`, exactly the
//! capture's range); the lines exist only when every cell fits (`B + 1 <= BOUNDS` and at most
//! `u16::MAX` entries in a cell); otherwise `CellLines::compact` is false and the walk reads
//! the capture's offsets (same ranges).
//!
//! | parameter | value | meaning |
//! |---|---|---|
//! | line size | 64 bytes | one cache line per cell (`repr(align(64))`) |
//! | [`BOUNDS`] | 24 | bucket bounds per line: `B <= 23` buckets |
//! | bound type | `u16` | at most 65 535 ids in one cell |

use parallax_raster::dirt::DirtCapture;

/// Bucket ends a line holds: compact lines need `B <= ENDS`.
pub(crate) const ENDS: usize = 16;
/// Ids a line holds: a cell with at most this many list entries has them in its line.
pub(crate) const INLINE: usize = 8;
/// The mask bit of a cell with more than 255 entries (its ranges from the capture's offsets).
/// Above every bucket's bit for `B <= ENDS`, so the walk's mask tests never see it.
pub(crate) const WIDE: u32 = 1 << 31;
/// `u32` words of a line, and the word of its first inline id.
const WORDS: usize = 16;
const INLINE_WORD: usize = 8;

/// One level-0 cell (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct CellLine {
    pub zmin: f32,
    pub scale: f32,
    /// Non-empty buckets ([`parallax_raster::dirt::bucket_mask`]), and [`WIDE`].
    pub mask: u32,
    /// Where the cell's ids start: in [`CellLines::ids`] when compact (this line's own
    /// `ids` or the overflow after the lines), else in the capture's ids (`offsets[c B]`).
    pub first: u32,
    /// Bucket `b`'s ids end at `first + ends[b]` and start where bucket `b - 1`'s end (`0`
    /// for `b = 0`); compact lines of cells that are not [`WIDE`] only.
    pub ends: [u8; ENDS],
    /// The cell's ids when it has at most [`INLINE`] of them (compact lines only).
    pub ids: [u32; INLINE],
}

const _: () = assert!(std::mem::size_of::<CellLine>() == 4 * WORDS);
const _: () = assert!(std::mem::offset_of!(CellLine, ids) == 4 * INLINE_WORD);

/// The lines of one view's cells (row-major, as the capture's records).
#[derive(Clone, Debug)]
pub(crate) struct CellLines {
    /// One line per cell, then (compact) the ids of the cells that do not fit their line,
    /// cell after cell, on further lines.
    pub lines: Vec<CellLine>,
    /// Whether the lines hold the bucket ranges and ids (module docs); if not, read the
    /// capture's offsets and ids.
    pub compact: bool,
}

impl CellLines {
    /// The lines of `cap`'s cells.
    pub fn new(cap: &DirtCapture) -> CellLines {
        let nb = cap.buckets() as usize;
        let offsets = cap.offsets();
        let all = cap.ids();
        let cells = cap.cell_records().len();
        let overflow: usize = (0..cells)
            .map(|c| (offsets[(c + 1) * nb] - offsets[c * nb]) as usize)
            .map(|n| n.saturating_sub(INLINE))
            .sum();
        let compact = nb <= ENDS && (cells + overflow.div_ceil(WORDS)) * WORDS <= u32::MAX as usize;
        let mut next = cells * WORDS;
        let mut spill: Vec<(usize, usize)> = Vec::new();
        let mut lines: Vec<CellLine> = cap
            .cell_records()
            .iter()
            .enumerate()
            .map(|(c, rec)| {
                let (s, e) = (offsets[c * nb] as usize, offsets[(c + 1) * nb] as usize);
                let mut line = CellLine {
                    zmin: rec.zmin,
                    scale: rec.scale,
                    mask: rec.mask,
                    first: s as u32,
                    ends: [0; ENDS],
                    ids: [0; INLINE],
                };
                if !compact {
                    return line;
                }
                let own = (e - s).min(INLINE);
                line.ids[..own].copy_from_slice(&all[s..s + own]);
                if e - s <= INLINE {
                    line.first = (c * WORDS + INLINE_WORD) as u32;
                } else {
                    line.first = (next - INLINE) as u32;
                    next += e - s - INLINE;
                    spill.push((s + INLINE, e));
                }
                if e - s <= u8::MAX as usize {
                    for (b, end) in line.ends.iter_mut().take(nb).enumerate() {
                        *end = (offsets[c * nb + b + 1] as usize - s) as u8;
                    }
                } else {
                    line.mask |= WIDE;
                }
                line
            })
            .collect();
        if compact {
            lines.resize(cells + overflow.div_ceil(WORDS), CellLine::ZERO);
            let words = words_mut(&mut lines);
            let mut at = cells * WORDS;
            for (s, e) in spill {
                words[at..at + e - s].copy_from_slice(&all[s..e]);
                at += e - s;
            }
        }
        CellLines { lines, compact }
    }

    /// The ids the ranges of [`Self::bucket`] index: the lines' words when compact, else the
    /// capture's.
    #[inline(always)]
    pub fn ids<'a>(&'a self, cap: &'a DirtCapture) -> &'a [u32] {
        if self.compact {
            words(&self.lines)
        } else {
            cap.ids()
        }
    }

    /// The ranges in [`Self::ids`] of bucket `b` of cell `index` (`offsets` the capture's):
    /// its entries among the cell's first [`INLINE`] (in the line), then the others (in the
    /// overflow); either may be empty.
    #[inline(always)]
    pub fn bucket(
        &self,
        line: &CellLine,
        index: usize,
        b: u32,
        nb: u32,
        offsets: &[u32],
    ) -> [(usize, usize); 2] {
        // The bucket's entries among the cell's.
        let (s, e) = if self.compact && line.mask & WIDE == 0 {
            // `b < B <= ENDS` when compact: the `min` changes no valid bucket and lets the
            // compiler drop the bounds checks.
            let b = (b as usize).min(ENDS - 1);
            let start = if b > 0 { line.ends[b - 1] } else { 0 };
            (start as usize, line.ends[b] as usize)
        } else {
            let k = index * nb as usize + b as usize;
            let (s, e) = (offsets[k] as usize, offsets[k + 1] as usize);
            if !self.compact {
                return [(s, e), (e, e)];
            }
            let base = offsets[index * nb as usize] as usize;
            (s - base, e - base)
        };
        let own = index * WORDS + INLINE_WORD;
        let first = line.first as usize;
        [
            (own + s.min(INLINE), own + e.min(INLINE)),
            (first + s.max(INLINE), first + e.max(INLINE)),
        ]
    }
}

impl CellLine {
    const ZERO: CellLine = CellLine {
        zmin: 0.0,
        scale: 0.0,
        mask: 0,
        first: 0,
        ends: [0; ENDS],
        ids: [0; INLINE],
    };
}

/// The lines as `u32` words.
fn words(lines: &[CellLine]) -> &[u32] {
    // SAFETY: `CellLine` is `repr(C)`, 16 words with no padding (asserted above), of `f32`,
    // `u32` and `u8` fields: every bit pattern is a valid `u32` and a valid line; the
    // alignment of 64 exceeds `u32`'s.
    unsafe { std::slice::from_raw_parts(lines.as_ptr().cast::<u32>(), lines.len() * WORDS) }
}

/// The lines as mutable `u32` words ([`words`]).
fn words_mut(lines: &mut [CellLine]) -> &mut [u32] {
    // SAFETY: as in `words`; the borrow is exclusive.
    unsafe { std::slice::from_raw_parts_mut(lines.as_mut_ptr().cast::<u32>(), lines.len() * WORDS) }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every bucket's range from a line is the capture's CSR range, on a random soup's views
    /// (B = 16: compact; B = 48: the capture's offsets).
    #[test]
    fn lines_give_the_capture_ranges() {
        use parallax_raster::dirt::{DirtOptions, DirtViews, DirtViewsOptions};
        let mut rng = parallax_core::sampling::Rng::for_pixel(1, 2, 3, 4);
        let m = super::super::test_soup::random_soup(&mut rng, 300);
        for (buckets, compact) in [(16u32, true), (48, false)] {
            let opts = DirtViewsOptions {
                face_size: 32,
                capture: DirtOptions {
                    tile_size: 2,
                    buckets,
                    ..DirtOptions::default()
                },
            };
            let views = DirtViews::build(&m, None, glam::Vec3::ZERO, &opts).expect("build");
            for cap in &views.cube.faces {
                let lines = CellLines::new(cap);
                assert_eq!(lines.compact, compact);
                let offsets = cap.offsets();
                let ids = lines.ids(cap);
                for (c, rec) in cap.cell_records().iter().enumerate() {
                    let line = &lines.lines[c];
                    assert_eq!(
                        (line.zmin, line.scale, line.mask & !WIDE),
                        (rec.zmin, rec.scale, rec.mask)
                    );
                    for b in 0..buckets {
                        let k = c * buckets as usize + b as usize;
                        let [(s0, e0), (s1, e1)] = lines.bucket(line, c, b, buckets, offsets);
                        assert_eq!(
                            [&ids[s0..e0], &ids[s1..e1]].concat(),
                            &cap.ids()[offsets[k] as usize..offsets[k + 1] as usize],
                            "cell {c} bucket {b}"
                        );
                    }
                }
            }
        }
    }
}
