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

/// Bucket bounds a line holds (`B + 1` of them are used).
pub(crate) const BOUNDS: usize = 24;

/// One level-0 cell (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub(crate) struct CellLine {
    pub zmin: f32,
    pub scale: f32,
    /// Non-empty buckets ([`parallax_raster::dirt::bucket_mask`]).
    pub mask: u32,
    /// The cell's first id (`offsets[c B]`).
    pub first: u32,
    /// Bucket `b`'s ids start at `first + bounds[b]` (`b in 0..=B`; zero where unused).
    pub bounds: [u16; BOUNDS],
}

const _: () = assert!(std::mem::size_of::<CellLine>() == 64);

/// The lines of one view's cells (row-major, as the capture's records).
#[derive(Clone, Debug)]
pub(crate) struct CellLines {
    pub lines: Vec<CellLine>,
    /// Whether `bounds` hold the bucket ranges (module docs); if not, read the capture's
    /// offsets.
    pub compact: bool,
}

impl CellLines {
    /// The lines of `cap`'s cells.
    pub fn new(cap: &DirtCapture) -> CellLines {
        let nb = cap.buckets() as usize;
        let offsets = cap.offsets();
        let fits = nb < BOUNDS
            && (0..cap.cell_records().len())
                .all(|c| offsets[(c + 1) * nb] - offsets[c * nb] <= u16::MAX as u32);
        let lines = cap
            .cell_records()
            .iter()
            .enumerate()
            .map(|(c, rec)| {
                let first = offsets[c * nb];
                let mut bounds = [0u16; BOUNDS];
                if fits {
                    for (b, d) in bounds.iter_mut().take(nb + 1).enumerate() {
                        *d = (offsets[c * nb + b] - first) as u16;
                    }
                }
                CellLine {
                    zmin: rec.zmin,
                    scale: rec.scale,
                    mask: rec.mask,
                    first,
                    bounds,
                }
            })
            .collect();
        CellLines {
            lines,
            compact: fits,
        }
    }

    /// The ids range of bucket `b` of cell `index` (`offsets` the capture's).
    #[inline(always)]
    pub fn bucket(
        &self,
        line: &CellLine,
        index: usize,
        b: u32,
        nb: u32,
        offsets: &[u32],
    ) -> (usize, usize) {
        if self.compact {
            // `b < B <= BOUNDS - 1` when compact: the `min` changes no valid bucket and lets
            // the compiler drop both bounds checks (a `% BOUNDS` did the same with a division).
            let b = (b as usize).min(BOUNDS - 2);
            let first = line.first as usize;
            (
                first + line.bounds[b] as usize,
                first + line.bounds[b + 1] as usize,
            )
        } else {
            let k = index * nb as usize + b as usize;
            (offsets[k] as usize, offsets[k + 1] as usize)
        }
    }
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
                for (c, rec) in cap.cell_records().iter().enumerate() {
                    let line = &lines.lines[c];
                    assert_eq!(
                        (line.zmin, line.scale, line.mask),
                        (rec.zmin, rec.scale, rec.mask)
                    );
                    for b in 0..buckets {
                        let k = c * buckets as usize + b as usize;
                        assert_eq!(
                            lines.bucket(line, c, b, buckets, offsets),
                            (offsets[k] as usize, offsets[k + 1] as usize),
                            "cell {c} bucket {b}"
                        );
                    }
                }
            }
        }
    }
}
