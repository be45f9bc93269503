//! Tile binning: every raster triangle is listed in each screen tile its pixel bounds touch
//! (sort-middle binning as in Molnar et al. 1994's taxonomy; the tile-based rasterizers of
//! PowerVR and Larrabee, Seiler et al. 2008). Two passes over flat arrays — count, prefix sum,
//! fill — so a tile's list is contiguous and in triangle order (deterministic).

use super::setup::RasterTri;

/// Tile edge in pixels.
pub const TILE: u32 = 32;

/// The triangle lists of all tiles: tile `t` holds `items[offsets[t]..offsets[t + 1]]`.
#[derive(Clone, Debug, Default)]
pub struct Bins {
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub offsets: Vec<usize>,
    pub items: Vec<u32>,
}

impl Bins {
    /// Bins `tris` for a `width x height` viewport.
    pub fn new(tris: &[RasterTri], width: u32, height: u32) -> Self {
        let tiles_x = width.div_ceil(TILE);
        let tiles_y = height.div_ceil(TILE);
        let n = tiles_x as usize * tiles_y as usize;
        let mut offsets = vec![0usize; n + 1];
        let range = |t: &RasterTri| (t.x0 / TILE, t.y0 / TILE, t.x1 / TILE, t.y1 / TILE);
        for t in tris {
            let (a, b, c, d) = range(t);
            for ty in b..=d {
                let row = (ty * tiles_x) as usize;
                for tx in a..=c {
                    offsets[row + tx as usize + 1] += 1;
                }
            }
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut items = vec![0u32; offsets[n]];
        for (i, t) in tris.iter().enumerate() {
            let (a, b, c, d) = range(t);
            for ty in b..=d {
                let row = (ty * tiles_x) as usize;
                for tx in a..=c {
                    let slot = &mut fill[row + tx as usize];
                    items[*slot] = i as u32;
                    *slot += 1;
                }
            }
        }
        Self {
            tiles_x,
            tiles_y,
            offsets,
            items,
        }
    }

    /// Number of tiles.
    pub fn len(&self) -> usize {
        self.tiles_x as usize * self.tiles_y as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The triangle indices binned to tile `t`.
    #[inline]
    pub fn tile(&self, t: usize) -> &[u32] {
        &self.items[self.offsets[t]..self.offsets[t + 1]]
    }

    /// Bytes of the bin arrays.
    pub fn bytes(&self) -> usize {
        self.offsets.len() * size_of::<usize>() + self.items.len() * size_of::<u32>()
    }
}
