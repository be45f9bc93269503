//! The min-max mip chain of DIRT's depth bounds texture (DIRT §4.1.1 "Mipmap Depth"), for
//! Hi-Z traversal (DIRT §4.2.1, Algorithm 1 lines 1-6).
//!
//! Level 0 is the per-cell (pixel or tile) depth bounds; level `k + 1` has
//! `ceil(w_k / 2) x ceil(h_k / 2)` texels, texel `(i, j)` holding the min of the mins and the
//! max of the maxes over the children `(2i..=2i+1, 2j..=2j+1)` that exist (odd sizes: the last
//! texel covers only the remaining child column/row). The chain ends at 1 x 1. Empty cells hold
//! `(+inf, -inf)`, so they never widen a parent. All levels live in one flat array of
//! `[min, max]` pairs (one load per texel visited by a traversal).
//!
//! **Reciprocal chain.** The tracer walks a ray's projection with `1 / depth` affine along
//! it (as screen-space ray marchers do; DIRT §4.2.1 traces in screen space), so it reads the
//! same chain as reciprocal bounds `[1 / max, 1 / min]` ([`reciprocal`]), each widened outward
//! by a relative `2^-22` so that the reciprocal's rounding never narrows a texel.

use serde::Serialize;

/// Where one level lives in the flat arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct LevelInfo {
    pub width: u32,
    pub height: u32,
    pub offset: usize,
}

/// The bounds of an empty texel.
pub const EMPTY: [f32; 2] = [f32::INFINITY, f32::NEG_INFINITY];

/// One level of the chain (borrowed).
#[derive(Clone, Copy, Debug)]
pub struct MipLevel<'a> {
    pub width: u32,
    pub height: u32,
    /// Row-major `[minimum, maximum]` view depth per texel ([`EMPTY`] where empty).
    pub bounds: &'a [[f32; 2]],
}

impl MipLevel<'_> {
    /// `(min, max)` of texel `(x, y)`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> (f32, f32) {
        let [lo, hi] = self.bounds[(y * self.width + x) as usize];
        (lo, hi)
    }
}

/// The levels of a `width x height` chain and the total texel count.
pub fn layout(width: u32, height: u32) -> (Vec<LevelInfo>, usize) {
    let mut levels = Vec::new();
    let (mut w, mut h, mut offset) = (width, height, 0usize);
    loop {
        levels.push(LevelInfo {
            width: w,
            height: h,
            offset,
        });
        offset += w as usize * h as usize;
        if w == 1 && h == 1 {
            break;
        }
        w = w.div_ceil(2);
        h = h.div_ceil(2);
    }
    (levels, offset)
}

/// Fills levels 1.. of `bounds` from level 0 (already written at offset 0).
pub fn build_chain(levels: &[LevelInfo], bounds: &mut [[f32; 2]]) {
    for k in 1..levels.len() {
        let (c, p) = (levels[k - 1], levels[k]);
        let (child, parent) = bounds.split_at_mut(p.offset);
        let child = &child[c.offset..];
        for y in 0..p.height {
            for x in 0..p.width {
                let mut b = EMPTY;
                for cy in 2 * y..(2 * y + 2).min(c.height) {
                    for cx in 2 * x..(2 * x + 2).min(c.width) {
                        let [lo, hi] = child[(cy * c.width + cx) as usize];
                        b = [b[0].min(lo), b[1].max(hi)];
                    }
                }
                parent[(y * p.width + x) as usize] = b;
            }
        }
    }
}

/// Relative widening of a reciprocal bound (several f32 ulps).
const RECIP_MARGIN: f64 = 1.0 / (1u64 << 22) as f64;

/// The reciprocal depth bounds `[1 / max, 1 / min]` of every texel (module docs), widened
/// outward: a texel whose depths are all `<= 0` (or an empty one) is [`EMPTY`], a minimum
/// `<= 0` gives an upper bound of `+inf`.
pub fn reciprocal(bounds: &[[f32; 2]]) -> Vec<[f32; 2]> {
    bounds
        .iter()
        .map(|&[lo, hi]| {
            if lo > hi || hi <= 0.0 {
                return EMPTY;
            }
            let w_lo = (1.0 - RECIP_MARGIN) / hi as f64;
            let w_hi = if lo > 0.0 {
                (1.0 + RECIP_MARGIN) / lo as f64
            } else {
                f64::INFINITY
            };
            [w_lo as f32, w_hi as f32]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn odd_chain_layout() {
        let (levels, total) = layout(5, 3);
        let sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, vec![(5, 3), (3, 2), (2, 1), (1, 1)]);
        assert_eq!(total, 15 + 6 + 2 + 1);
    }

    /// Every positive depth inside a texel's bounds has its reciprocal inside the texel's
    /// reciprocal bounds; empty and non-positive texels are empty.
    #[test]
    fn reciprocal_bounds_contain_every_depth() {
        let zs = [1e-4f32, 0.37, 1.0, 3.3, 1234.5, 1e7];
        for &a in &zs {
            for &b in &zs {
                if a > b {
                    continue;
                }
                let [lo, hi] = reciprocal(&[[a, b]])[0];
                for z in [a, b, a * 0.5 + b * 0.5] {
                    let w = 1.0 / z;
                    assert!(
                        lo <= w && w <= hi,
                        "{z} in [{a}, {b}]: {w} not in [{lo}, {hi}]"
                    );
                }
            }
        }
        assert_eq!(reciprocal(&[EMPTY])[0], EMPTY);
        assert_eq!(reciprocal(&[[-2.0, -1.0]])[0], EMPTY);
        assert_eq!(reciprocal(&[[0.0, 2.0]])[0][1], f32::INFINITY);
    }
}
