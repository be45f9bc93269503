//! The coarse level of the two-level LDC (Bürger et al. 2007, "Layered depth cubes for GPU ray
//! tracing", §1.3 "Two Level LDC", Fig. 6): for every `n x n` block of an LDI the minimum and
//! maximum depth over all its layers — a box per block that a ray traversal (§1.4) tests before
//! stepping down to the block's pixels, skipping empty space (after Krüger & Westermann 2003).

use rayon::prelude::*;
use serde::Serialize;

use crate::capture::AllLayersCapture;

/// Per-block depth bounds, row-major: block `(bx, by)` is `bounds[by * blocks_x + bx]` =
/// `[min, max]` over every sample of its pixels; an empty block is `[+inf, -inf]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CoarseGrid {
    /// Block edge in pixels.
    pub block: u32,
    pub blocks_x: u32,
    pub blocks_y: u32,
    pub bounds: Vec<[f32; 2]>,
}

impl CoarseGrid {
    /// The bounds of the `block x block` pixel blocks of `ldi` (partial blocks at the right and
    /// bottom edges). Each pixel's samples are sorted, so its range is `[first, last]`.
    pub fn build(ldi: &AllLayersCapture, block: u32) -> Self {
        let block = block.max(1);
        let (w, h) = (ldi.width(), ldi.height());
        let blocks_x = w.div_ceil(block);
        let blocks_y = h.div_ceil(block);
        let mut bounds = vec![[f32::INFINITY, f32::NEG_INFINITY]; (blocks_x * blocks_y) as usize];
        bounds
            .par_chunks_mut(blocks_x as usize)
            .enumerate()
            .for_each(|(by, row)| {
                let y0 = by as u32 * block;
                for y in y0..(y0 + block).min(h) {
                    for x in 0..w {
                        let d = ldi.depths(x, y);
                        if let (Some(&lo), Some(&hi)) = (d.first(), d.last()) {
                            let b = &mut row[(x / block) as usize];
                            b[0] = b[0].min(lo);
                            b[1] = b[1].max(hi);
                        }
                    }
                }
            });
        Self {
            block,
            blocks_x,
            blocks_y,
            bounds,
        }
    }

    /// `[min, max]` of the block holding pixel `(x, y)`.
    #[inline]
    pub fn bounds_of_pixel(&self, x: u32, y: u32) -> [f32; 2] {
        self.bounds[((y / self.block) * self.blocks_x + x / self.block) as usize]
    }

    /// Bytes of the bounds.
    pub fn bytes(&self) -> usize {
        self.bounds.len() * size_of::<[f32; 2]>()
    }
}
