//! The tracer's copy of one LDI, laid out for the traversal: pixels in block-major order (the
//! `n x n` pixels of a coarse block are contiguous, row-major inside the block, blocks
//! row-major), each pixel a [`PixelCell`] (first sample, depth range), the samples as splats
//! `(depth, dz/du, dz/dv)` in the same order (slopes of the plane of the sample's triangle),
//! and per block at most `intervals` depth intervals that cover its samples. A fine walk through one block then reads
//! a few cache lines instead of one per pixel row, and a pixel whose depth range the ray
//! misses is rejected without reading its samples (measured in `docs/notes/ldc.md`). The
//! answers are those of the capture's row-major CSR arrays: only the order in memory differs.

use glam::Vec3;
use parallax_raster::ldc::{Ldi, image_axes};
use rayon::prelude::*;

/// Largest `|dz/du|`, `|dz/dv|` of a splat. The geometric normal of a triangle assigned to an
/// LDI has its largest component on the LDI's axis, so its slopes are at most 1; the clamp
/// only guards against non-finite or degenerate normals.
pub const MAX_SLOPE: f32 = 2.0;

/// The slopes `(dz/du, dz/dv)` of the plane of normal `n` in LDI `axis`, clamped to
/// [`MAX_SLOPE`] (0 for a normal without an `axis` component).
#[inline]
pub(super) fn slopes(n: Vec3, axis: usize) -> (f32, f32) {
    let (u, v) = image_axes(axis);
    let na = n[axis];
    if na == 0.0 || !na.is_finite() {
        return (0.0, 0.0);
    }
    let c = |g: f32| {
        if g.is_finite() {
            g.clamp(-MAX_SLOPE, MAX_SLOPE)
        } else {
            0.0
        }
    };
    (c(-n[u] / na), c(-n[v] / na))
}

/// One pixel: its samples are `cells[i].start..cells[i + 1].start`; `[lo, hi]` is their depth
/// range (`[+inf, -inf]` when empty).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PixelCell {
    pub start: u32,
    pub lo: f32,
    pub hi: f32,
}

/// An LDI in block-major order (module docs).
#[derive(Clone, Debug, Default)]
pub(super) struct BlockLayout {
    /// Per block `intervals` depth intervals `[lo, hi]` that hold all its samples (unused
    /// slots `[+inf, -inf]`): block `b` owns `bounds[b * intervals..(b + 1) * intervals]`.
    pub bounds: Vec<[f32; 2]>,
    pub intervals: usize,
    /// `blocks_x * blocks_y * n * n + 1` cells (pixels past the image edge are empty; the last
    /// cell only ends the previous one).
    pub cells: Vec<PixelCell>,
    /// Per sample `(depth, dz/du, dz/dv)`.
    pub splats: Vec<[f32; 3]>,
    /// Per sample its index in the capture (normal, albedo, primitive id).
    pub sample: Vec<u32>,
}

impl BlockLayout {
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.cells.len() * size_of::<PixelCell>()
            + self.bounds.len() * size_of::<[f32; 2]>()
            + self.splats.len() * size_of::<[f32; 3]>()
            + self.sample.len() * size_of::<u32>()
    }

    /// The layout of `ldi` with its coarse grid's blocks, each block's depths covered by at
    /// most `intervals` intervals; splat slopes from the samples' geometric normals.
    pub fn build(ldi: &Ldi, intervals: usize) -> Self {
        let (cap, axis) = (&ldi.capture, ldi.axis);
        let (n, blocks_x, blocks_y) = (ldi.coarse.block, ldi.coarse.blocks_x, ldi.coarse.blocks_y);
        let (w, h) = (cap.width(), cap.height());
        let nn = (n * n) as usize;
        let blocks = (blocks_x * blocks_y) as usize;
        // The pixel `(x, y)` of padded cell `i`, if inside the image.
        let pixel = |i: usize| -> Option<(u32, u32)> {
            let (b, l) = (i / nn, (i % nn) as u32);
            let x = (b as u32 % blocks_x) * n + l % n;
            let y = (b as u32 / blocks_x) * n + l / n;
            (x < w && y < h).then_some((x, y))
        };
        let counts: Vec<u32> = (0..blocks * nn)
            .into_par_iter()
            .map(|i| pixel(i).map_or(0, |(x, y)| cap.depth_complexity(x, y)))
            .collect();
        let mut cells = Vec::with_capacity(counts.len() + 1);
        let mut total = 0u32;
        for &c in &counts {
            cells.push(PixelCell {
                start: total,
                lo: f32::INFINITY,
                hi: f32::NEG_INFINITY,
            });
            total += c;
        }
        cells.push(PixelCell {
            start: total,
            lo: f32::INFINITY,
            hi: f32::NEG_INFINITY,
        });
        let mut splats = vec![[0f32; 3]; total as usize];
        let mut sample = vec![0u32; total as usize];
        let intervals = intervals.max(1);
        let mut bounds = vec![[f32::INFINITY, f32::NEG_INFINITY]; blocks * intervals];
        // Each block's cells and samples are contiguous: split them into per-block slices.
        let mut work = Vec::with_capacity(blocks);
        let (mut cell_rest, mut splat_rest, mut sample_rest) =
            (&mut cells[..blocks * nn], &mut splats[..], &mut sample[..]);
        for (b, iv) in bounds.chunks_mut(intervals).enumerate() {
            let len = (counts[b * nn..(b + 1) * nn].iter().sum::<u32>()) as usize;
            let (c, cr) = cell_rest.split_at_mut(nn);
            let (s, sr) = splat_rest.split_at_mut(len);
            let (m, mr) = sample_rest.split_at_mut(len);
            work.push((b, c, s, m, iv));
            (cell_rest, splat_rest, sample_rest) = (cr, sr, mr);
        }
        work.into_par_iter()
            .for_each(|(b, cells, splats, sample, iv)| {
                let mut j = 0usize;
                for (l, cell) in cells.iter_mut().enumerate() {
                    let Some((x, y)) = pixel(b * nn + l) else {
                        continue;
                    };
                    let r = cap.range(x, y);
                    if !r.is_empty() {
                        // Samples are sorted by depth.
                        cell.lo = cap.depth[r.start];
                        cell.hi = cap.depth[r.end - 1];
                    }
                    for k in r {
                        let (gu, gv) = slopes(ldi.geometric_normal[k], axis);
                        splats[j] = [cap.depth[k], gu, gv];
                        sample[j] = k as u32;
                        j += 1;
                    }
                }
                let mut depths: Vec<f32> = splats.iter().map(|s| s[0]).collect();
                cover(&mut depths, iv);
            });
        Self {
            bounds,
            intervals,
            cells,
            splats,
            sample,
        }
    }
}

/// Covers `depths` (any order; sorted in place) by at most `out.len()` intervals: split at the
/// `out.len() - 1` widest gaps between consecutive depths (ties at the lower index). With one
/// interval this is the block's `[min, max]`, the paper's coarse bounds (§1.3).
pub(super) fn cover(depths: &mut [f32], out: &mut [[f32; 2]]) {
    out.fill([f32::INFINITY, f32::NEG_INFINITY]);
    if depths.is_empty() || out.is_empty() {
        return;
    }
    depths.sort_unstable_by(f32::total_cmp);
    let m = out.len();
    let mut gaps: Vec<usize> = (0..depths.len() - 1).collect();
    gaps.sort_by(|&a, &b| {
        (depths[b + 1] - depths[b])
            .total_cmp(&(depths[a + 1] - depths[a]))
            .then(a.cmp(&b))
    });
    let mut cuts: Vec<usize> = gaps
        .into_iter()
        .take(m - 1)
        .filter(|&i| depths[i + 1] > depths[i])
        .collect();
    cuts.sort_unstable();
    let mut start = 0;
    for (slot, end) in cuts.into_iter().chain([depths.len() - 1]).enumerate() {
        out[slot] = [depths[start], depths[end]];
        start = end + 1;
    }
}

#[cfg(test)]
mod tests {
    use super::cover;

    #[test]
    fn intervals_cover_every_depth_and_split_at_the_widest_gaps() {
        let mut d = [5.0, 0.1, 0.0, 2.0, 2.05, 5.1];
        let mut out = [[0.0f32; 2]; 3];
        cover(&mut d, &mut out);
        assert_eq!(out, [[0.0, 0.1], [2.0, 2.05], [5.0, 5.1]]);
        let mut one = [[0.0f32; 2]; 1];
        cover(&mut d, &mut one);
        assert_eq!(one, [[0.0, 5.1]]);
        let mut few = [1.0, 1.0];
        let mut out = [[0.0f32; 2]; 4];
        cover(&mut few, &mut out);
        assert_eq!(out[0], [1.0, 1.0]);
        assert!(
            out[1..].iter().all(|b| b[0] > b[1]),
            "unused slots stay empty"
        );
        cover(&mut [], &mut out);
        assert!(out.iter().all(|b| b[0] > b[1]));
    }
}
