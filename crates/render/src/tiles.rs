//! Screen tiles: the unit of parallel work of every per-pixel pass.

use rayon::prelude::*;

/// Tile edge in pixels: 16x16 keeps a tile's rays coherent and gives enough tiles to balance
/// two to many cores.
pub const TILE: u32 = 16;

/// Runs `f(x, y, &mut out[y * width + x])` for every pixel, tile by tile over rayon.
/// Each tile writes only its own pixels, so the output is identical whatever the thread count.
/// `done(n)` is called after each tile with its pixel count (progress bars).
pub fn for_each_pixel<T: Send>(
    width: u32,
    height: u32,
    out: &mut [T],
    f: impl Fn(u32, u32, &mut T) + Sync,
    done: &(dyn Fn(u64) + Sync),
) {
    assert_eq!(out.len(), width as usize * height as usize);
    // Rows of tiles: split the output into horizontal bands of TILE rows, then walk tiles
    // inside a band; bands are processed in parallel, tiles of a band sequentially by one
    // thread — this keeps each &mut disjoint without unsafe code.
    let band = TILE as usize * width as usize;
    out.par_chunks_mut(band).enumerate().for_each(|(by, rows)| {
        let y0 = by as u32 * TILE;
        let h = rows.len() as u32 / width;
        for x0 in (0..width).step_by(TILE as usize) {
            let w = TILE.min(width - x0);
            for dy in 0..h {
                let row = &mut rows[(dy * width) as usize..][..width as usize];
                for dx in 0..w {
                    f(x0 + dx, y0 + dy, &mut row[(x0 + dx) as usize]);
                }
            }
            done((w * h) as u64);
        }
    });
}
