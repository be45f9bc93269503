//! The level-0 cells as the walk reads them (Vardis et al. 2017, §4.2.1, Alg. 1 lines 7-11:
//! the cell's depth range for eq. 1, then the bucket's primitive list): one 64-byte line per
//! cell with the cell's record (`CellRecord`: `zmin`, the eq. 1 scale, the non-empty bucket
//! mask), where each of its buckets' entries end, *and* the cell's first [`INLINE`] list
//! entries, each a `u16` relative to the cell's smallest triangle id; the entries after those
//! follow the lines, cell after cell ("the overflow"), in the same form.
//!
//! The capture keeps the records (16 bytes a cell), the CSR offsets (`B + 1` `u32` a cell)
//! and the ids (`u32`) in three arrays, so a traced cell costs up to three dependent cache
//! misses before its triangles: the record, the offsets, the bucket's ids. On a CPU whose L2
//! holds none of them (a 512 KiB L2 against ~0.5 MiB of records, ~2.2 MiB of offsets and
//! ~1.7 MiB of ids for the atrium's camera view at 1024x512, tile 4, `B = 16`) all miss; here
//! a bucket among the cell's first entries costs the line alone, a later one the line and one
//! line of the overflow (half the bytes of `u32` ids).
//!
//! **Layout** (compact lines, `B <= ENDS`): `ends[b]` is the end of bucket `b` among the
//! cell's entries (`offsets[c B + b + 1] - offsets[c B]`, a `u8`; bucket `b` starts at
//! `ends[b - 1]`, or 0). Entry `i` of the cell is triangle `base + d` with `d` the line's
//! `ids[i]` for `i < INLINE`, else half `first + i` of the lines seen as `u16` halves
//! ([`CellLines::halves`]). A bucket's entries are then at most two ranges of halves
//! ([`CellLines::bucket`]), together exactly the capture's range in the same order. A cell
//! with more than 255 entries, or whose ids lie more than `u16::MAX` apart, is marked
//! [`WIDE`] in its mask: its ranges and ids are the capture's. When `B > ENDS` the lines are
//! not compact: they carry the record only, and the walk reads the capture's offsets and ids
//! (same ranges).
//!
//! | parameter | value | meaning |
//! |---|---|---|
//! | line size | 64 bytes | one cache line per cell (`repr(align(64))`) |
//! | [`ENDS`] | 16 | bucket ends per line (`u8`): compact for `B <= 16` |
//! | [`INLINE`] | 14 | list entries (`u16`) in the line |
//! | [`WIDE`] | mask bit 31 | a cell read from the capture (> 255 entries or an id span > `u16::MAX`) |

use parallax_raster::dirt::DirtCapture;

/// Bucket ends a line holds: compact lines need `B <= ENDS`.
pub(crate) const ENDS: usize = 16;
/// List entries a line holds (the cell's first ones).
pub(crate) const INLINE: usize = 14;
/// The mask bit of a wide cell: more than 255 entries, or ids more than `u16::MAX` apart; its
/// ranges and ids are the capture's. Above every bucket's bit for `B <= ENDS`, so the walk's
/// mask tests never see it.
pub(crate) const WIDE: u32 = 1 << 31;
/// `u16` halves of a line, and the half of its first inline entry.
const HALVES: usize = 32;
const INLINE_HALF: usize = 18;

/// One level-0 cell (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct CellLine {
    pub zmin: f32,
    pub scale: f32,
    /// Non-empty buckets ([`parallax_raster::dirt::bucket_mask`]), and [`WIDE`].
    pub mask: u32,
    /// Compact and not wide: the cell's entry `i >= INLINE` is half `first + i` of
    /// [`CellLines::halves`]. Otherwise the cell's first index in the capture's ids.
    pub first: u32,
    /// The cell's smallest triangle id: entries are `id - base`.
    pub base: u32,
    /// Bucket `b`'s entries end at entry `ends[b]` and start at `ends[b - 1]` (`0` for
    /// `b = 0`).
    pub ends: [u8; ENDS],
    /// The cell's first [`INLINE`] entries.
    pub ids: [u16; INLINE],
}

const _: () = assert!(std::mem::size_of::<CellLine>() == 2 * HALVES);
const _: () = assert!(std::mem::offset_of!(CellLine, ids) == 2 * INLINE_HALF);

/// Where a bucket's triangles are listed ([`CellLines::bucket`]).
pub(crate) enum Entries {
    /// Ids `base + d` for the `d` in two ranges of [`CellLines::halves`] (in the line, after
    /// the lines; either may be empty).
    Packed {
        base: u32,
        ranges: [(usize, usize); 2],
    },
    /// A range of the capture's ids.
    Capture(usize, usize),
}

/// The lines of one view's cells (row-major, as the capture's records).
#[derive(Clone, Debug)]
pub(crate) struct CellLines {
    /// One line per cell, then (compact) the entries of the cells past their first
    /// [`INLINE`], cell after cell, on further lines.
    pub lines: Vec<CellLine>,
    /// Whether the lines hold the bucket ranges and entries (module docs); if not, read the
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
        let wide = |s: usize, e: usize| {
            let ids = &all[s..e];
            let (lo, hi) = (ids.iter().min(), ids.iter().max());
            e - s > u8::MAX as usize || hi.zip(lo).is_some_and(|(h, l)| h - l > u16::MAX as u32)
        };
        let range = |c: usize| (offsets[c * nb] as usize, offsets[(c + 1) * nb] as usize);
        let kinds: Vec<bool> = (0..cells)
            .map(|c| {
                let (s, e) = range(c);
                wide(s, e)
            })
            .collect();
        let overflow: usize = (0..cells)
            .filter(|&c| !kinds[c])
            .map(|c| {
                let (s, e) = range(c);
                (e - s).saturating_sub(INLINE)
            })
            .sum();
        let compact =
            nb <= ENDS && (cells + overflow.div_ceil(HALVES)) * HALVES <= u32::MAX as usize;
        let mut next = cells * HALVES;
        let mut spill: Vec<(usize, usize, u32)> = Vec::new();
        let mut lines: Vec<CellLine> = cap
            .cell_records()
            .iter()
            .enumerate()
            .map(|(c, rec)| {
                let (s, e) = range(c);
                let mut line = CellLine {
                    zmin: rec.zmin,
                    scale: rec.scale,
                    mask: rec.mask,
                    first: s as u32,
                    base: 0,
                    ends: [0; ENDS],
                    ids: [0; INLINE],
                };
                if !compact {
                    return line;
                }
                if kinds[c] {
                    line.mask |= WIDE;
                    return line;
                }
                line.base = all[s..e].iter().copied().min().unwrap_or(0);
                let own = (e - s).min(INLINE);
                for (d, &id) in line.ids.iter_mut().zip(&all[s..s + own]) {
                    *d = (id - line.base) as u16;
                }
                if e - s <= INLINE {
                    line.first = (c * HALVES + INLINE_HALF) as u32;
                } else {
                    line.first = (next - INLINE) as u32;
                    next += e - s - INLINE;
                    spill.push((s + INLINE, e, line.base));
                }
                for (b, end) in line.ends.iter_mut().take(nb).enumerate() {
                    *end = (offsets[c * nb + b + 1] as usize - s) as u8;
                }
                line
            })
            .collect();
        if compact {
            lines.resize(cells + overflow.div_ceil(HALVES), CellLine::ZERO);
            let halves = halves_mut(&mut lines);
            let mut at = cells * HALVES;
            for (s, e, base) in spill {
                for (d, &id) in halves[at..at + e - s].iter_mut().zip(&all[s..e]) {
                    *d = (id - base) as u16;
                }
                at += e - s;
            }
        }
        CellLines { lines, compact }
    }

    /// The lines as `u16` halves (the entries of [`Entries::Packed`]).
    #[inline(always)]
    pub fn halves(&self) -> &[u16] {
        // SAFETY: `CellLine` is `repr(C)`, 32 halves with no padding (asserted above), of
        // `f32`, `u32`, `u8` and `u16` fields: every bit pattern is a valid `u16`; its
        // alignment of 64 exceeds `u16`'s.
        unsafe {
            std::slice::from_raw_parts(self.lines.as_ptr().cast::<u16>(), self.lines.len() * HALVES)
        }
    }

    /// Where bucket `b` of cell `index` is listed (`offsets` the capture's): in the cell's
    /// line for its entries among the cell's first [`INLINE`], after the lines for the others.
    #[inline(always)]
    pub fn bucket(
        &self,
        line: &CellLine,
        index: usize,
        b: u32,
        nb: u32,
        offsets: &[u32],
    ) -> Entries {
        if !self.compact || line.mask & WIDE != 0 {
            let k = index * nb as usize + b as usize;
            return Entries::Capture(offsets[k] as usize, offsets[k + 1] as usize);
        }
        // `b < B <= ENDS` when compact: the `min` changes no valid bucket and lets the
        // compiler drop the bounds checks.
        let b = (b as usize).min(ENDS - 1);
        let start = if b > 0 { line.ends[b - 1] } else { 0 };
        let (s, e) = (start as usize, line.ends[b] as usize);
        let own = index * HALVES + INLINE_HALF;
        let first = line.first as usize;
        Entries::Packed {
            base: line.base,
            ranges: [
                (own + s.min(INLINE), own + e.min(INLINE)),
                (first + s.max(INLINE), first + e.max(INLINE)),
            ],
        }
    }
}

impl CellLine {
    const ZERO: CellLine = CellLine {
        zmin: 0.0,
        scale: 0.0,
        mask: 0,
        first: 0,
        base: 0,
        ends: [0; ENDS],
        ids: [0; INLINE],
    };
}

/// The lines as mutable `u16` halves ([`CellLines::halves`]).
fn halves_mut(lines: &mut [CellLine]) -> &mut [u16] {
    // SAFETY: as in `CellLines::halves`; the borrow is exclusive.
    unsafe {
        std::slice::from_raw_parts_mut(lines.as_mut_ptr().cast::<u16>(), lines.len() * HALVES)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every bucket's entries from a line (its two ranges, plus the base) are the capture's
    /// CSR range, on random soups' views: B = 16 compact, with cells of every kind (all
    /// entries in the line, some after the lines, wide), and B = 48 (the capture's offsets).
    #[test]
    fn lines_give_the_capture_ranges() {
        use parallax_raster::dirt::{DirtOptions, DirtViews, DirtViewsOptions};
        let mut rng = parallax_core::sampling::Rng::for_pixel(1, 2, 3, 4);
        let sparse = super::super::test_soup::random_soup(&mut rng, 300);
        let dense = super::super::test_soup::random_soup(&mut rng, 6000);
        // Cells seen with all their entries in the line, with some after it, wide.
        let mut kinds = [0usize; 3];
        for (m, tile_size, buckets, compact) in [
            (&sparse, 2, 16u32, true),
            (&dense, 16, 16, true),
            (&sparse, 2, 48, false),
        ] {
            let opts = DirtViewsOptions {
                face_size: 32,
                capture: DirtOptions {
                    tile_size,
                    buckets,
                    ..DirtOptions::default()
                },
                camera_tile_size: None,
            };
            let views = DirtViews::build(m, None, glam::Vec3::ZERO, &opts).expect("build");
            for cap in &views.cube.faces {
                let lines = CellLines::new(cap);
                assert_eq!(lines.compact, compact);
                let offsets = cap.offsets();
                let halves = lines.halves();
                for (c, rec) in cap.cell_records().iter().enumerate() {
                    let line = &lines.lines[c];
                    assert_eq!(
                        (line.zmin, line.scale, line.mask & !WIDE),
                        (rec.zmin, rec.scale, rec.mask)
                    );
                    let n = offsets[(c + 1) * buckets as usize] - offsets[c * buckets as usize];
                    let wide = line.mask & WIDE != 0;
                    if compact {
                        let cell =
                            &cap.ids()[offsets[c * buckets as usize] as usize..][..n as usize];
                        let span = cell.iter().max().zip(cell.iter().min()).map(|(h, l)| h - l);
                        assert_eq!(wide, n > 255 || span > Some(u16::MAX as u32));
                        kinds[if wide {
                            2
                        } else {
                            (n as usize > INLINE) as usize
                        }] += 1;
                    }
                    for b in 0..buckets {
                        let k = c * buckets as usize + b as usize;
                        let want = &cap.ids()[offsets[k] as usize..offsets[k + 1] as usize];
                        match lines.bucket(line, c, b, buckets, offsets) {
                            Entries::Packed { base, ranges } => {
                                assert!(compact && !wide);
                                let got: Vec<u32> = ranges
                                    .iter()
                                    .flat_map(|&(s, e)| &halves[s..e])
                                    .map(|&d| base + d as u32)
                                    .collect();
                                assert_eq!(got, want, "cell {c} bucket {b}");
                            }
                            Entries::Capture(s, e) => {
                                assert!(!compact || wide);
                                assert_eq!(&cap.ids()[s..e], want, "cell {c} bucket {b}");
                            }
                        }
                    }
                }
            }
        }
        assert!(
            kinds.iter().all(|&k| k > 0),
            "cells of every kind: {kinds:?}"
        );
    }
}
