//! The progressive film: per pixel the sum and the sum of squares of the sample values (per
//! colour channel, in f64) and the sample count, stored tile by tile so that rayon hands each
//! wavefront its own pixels.
//!
//! **Invariant:** a pixel's sums add its samples in sample-index order, one at a time, so the
//! result does not depend on how the samples were split into passes or on the thread count.

use glam::Vec3;
use parallax_core::{Image, Rgb};

/// A rectangle of pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub w: u32,
    pub h: u32,
}

impl Tile {
    pub fn pixels(&self) -> usize {
        self.w as usize * self.h as usize
    }

    /// Tile-local pixel indices in blocks of `b x b` pixels (blocks row-major over the tile,
    /// pixels row-major in each block, blocks clipped at the tile's edges): every pixel once.
    pub fn block_order(&self, b: u32) -> impl Iterator<Item = usize> + use<> {
        let (w, h) = (self.w, self.h);
        let b = b.max(1);
        (0..h).step_by(b as usize).flat_map(move |by| {
            (0..w).step_by(b as usize).flat_map(move |bx| {
                (by..(by + b).min(h))
                    .flat_map(move |y| (bx..(bx + b).min(w)).map(move |x| (y * w + x) as usize))
            })
        })
    }

    /// Image coordinates of tile-local pixel `i` (row-major in the tile).
    #[inline]
    pub fn coords(&self, i: usize) -> (u32, u32) {
        (self.x0 + i as u32 % self.w, self.y0 + i as u32 / self.w)
    }
}

/// The accumulators of one tile (tile-local row-major).
#[derive(Clone, Debug)]
pub struct TileFilm {
    pub tile: Tile,
    sum: Vec<[f64; 3]>,
    sum_sq: Vec<[f64; 3]>,
    count: Vec<u32>,
}

impl TileFilm {
    fn new(tile: Tile) -> Self {
        let n = tile.pixels();
        Self {
            tile,
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
            count: vec![0; n],
        }
    }

    /// Adds channel `c` (0..3) of sample value `v` to tile-local pixel `i`.
    #[inline]
    pub fn add_channel(&mut self, i: usize, c: usize, v: f32) {
        let v = v as f64;
        self.sum[i][c] += v;
        self.sum_sq[i][c] += v * v;
    }

    /// Adds all three channels of sample value `v` to tile-local pixel `i`.
    #[inline]
    pub fn add(&mut self, i: usize, v: Vec3) {
        for c in 0..3 {
            self.add_channel(i, c, v[c]);
        }
    }

    /// Counts one sample at tile-local pixel `i`.
    #[inline]
    pub fn count_sample(&mut self, i: usize) {
        self.count[i] += 1;
    }
}

/// A `width x height` film split into tiles of `tile x tile` pixels.
#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub tiles: Vec<TileFilm>,
}

impl Film {
    pub fn new(width: u32, height: u32, tile: u32) -> Self {
        let tile = tile.max(1);
        let mut tiles = Vec::new();
        for y0 in (0..height).step_by(tile as usize) {
            for x0 in (0..width).step_by(tile as usize) {
                tiles.push(TileFilm::new(Tile {
                    x0,
                    y0,
                    w: tile.min(width - x0),
                    h: tile.min(height - y0),
                }));
            }
        }
        Self {
            width,
            height,
            tiles,
        }
    }

    fn gather<T: Clone>(&self, zero: T, f: impl Fn(&TileFilm, usize) -> T) -> Image<T> {
        let mut img = Image::new(self.width, self.height, zero).expect("film size was checked");
        for t in &self.tiles {
            for i in 0..t.tile.pixels() {
                let (x, y) = t.tile.coords(i);
                img.set(x, y, f(t, i));
            }
        }
        img
    }

    /// Per-pixel mean (the image).
    pub fn mean(&self) -> Image<Rgb> {
        self.gather(Vec3::ZERO, |t, i| {
            let n = t.count[i].max(1) as f64;
            let s = t.sum[i];
            Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
        })
    }

    /// Per-pixel variance of the mean, per channel: the unbiased sample variance over `n`
    /// (0 where fewer than two samples were taken).
    pub fn variance_of_mean(&self) -> Image<Rgb> {
        self.gather(Vec3::ZERO, |t, i| {
            let n = t.count[i] as f64;
            if n < 2.0 {
                return Vec3::ZERO;
            }
            let mut v = [0.0f32; 3];
            for (c, vc) in v.iter_mut().enumerate() {
                let mean = t.sum[i][c] / n;
                let var = ((t.sum_sq[i][c] - n * mean * mean) / (n - 1.0)).max(0.0);
                *vc = (var / n) as f32;
            }
            Vec3::from(v)
        })
    }

    /// Samples taken per pixel.
    pub fn counts(&self) -> Image<u32> {
        self.gather(0, |t, i| t.count[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_order_visits_every_pixel_once_block_by_block() {
        let tile = Tile {
            x0: 32,
            y0: 64,
            w: 10,
            h: 7,
        };
        let order: Vec<usize> = tile.block_order(4).collect();
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..70).collect::<Vec<_>>());
        // The first block: rows 0..4 of columns 0..4; the third clipped to columns 8..10.
        assert_eq!(&order[..5], &[0, 1, 2, 3, 10]);
        assert_eq!(&order[32..34], &[8, 9]);
        assert_eq!(
            tile.block_order(1).collect::<Vec<_>>(),
            (0..70).collect::<Vec<_>>()
        );
    }

    #[test]
    fn tiles_cover_the_film_once_and_statistics_are_per_pixel() {
        let mut f = Film::new(37, 19, 16);
        assert_eq!(f.tiles.len(), 3 * 2);
        let covered: usize = f.tiles.iter().map(|t| t.tile.pixels()).sum();
        assert_eq!(covered, 37 * 19);
        for t in &mut f.tiles {
            for i in 0..t.tile.pixels() {
                let (x, y) = t.tile.coords(i);
                for v in [1.0, 3.0] {
                    t.add(i, Vec3::splat(v * (x + y) as f32));
                    t.count_sample(i);
                }
            }
        }
        let (m, var, n) = (f.mean(), f.variance_of_mean(), f.counts());
        assert_eq!(*m.get(5, 7), Vec3::splat(24.0));
        // Samples 12 and 36: sample variance 288, variance of the mean 144.
        assert!((var.get(5, 7).x - 144.0).abs() < 1e-3);
        assert_eq!(*n.get(36, 18), 2);
    }
}
