//! Depth-slab occupancy of every mip texel of a DIRT view: a finer skip test for the Hi-Z walk
//! than the texel's min-max bounds (Vardis et al. 2017, §4.2.1 and Algorithm 1 lines 1-6 test
//! the min-max bounds only).
//!
//! A cell lists every triangle over it at every depth, so its bounds `[zmin, zmax]` run from
//! the nearest surface to the farthest one behind it, and a coarse texel's bounds span nearly
//! the whole view: the min-max test rarely skips. The buckets know better: most of a cell's
//! depth range is empty (the record's non-empty bucket mask). This module turns each cell's
//! non-empty buckets into a mask of occupied *slabs* of reciprocal depth `w = 1 / z` over the
//! cell's own bounds, and carries the masks up the mip chain, each texel in its own partition
//! of its own bounds. The walk skips a texel when the slabs of the ray's `w` range over it
//! miss its mask.
//!
//! **Slabs.** A texel with reciprocal bounds `[lo, hi]` (`lo` raised to `+0` if below) has
//! slab `σ(w) = min(max(bits(w) >> s, base) - base, 55)`, `base = bits(lo) >> s`, with `bits`
//! the f32 bit pattern (monotone in `w >= 0`, negative `w` taken as 0): slabs `2^s` bit
//! patterns wide, i.e. `2^(23 - s)` per octave of depth, piecewise linear in `log2 w`, slab 0
//! at `lo`. `s` is the smallest shift whose 56 slabs reach `hi`: a cell's slabs are a few
//! ulps to a few hundred ulps wide (finer than its buckets), the top texel's about an eighth
//! of an octave. The texel keeps the mask in bits 0-55 of a `u64` and `s` in its top byte
//! (16 bytes with the bounds).
//!
//! **Why a skip is exact.** Let the walk trace level-0 cell `c` over the computed reciprocal
//! depth range `[w0, w1]`: it overlaps the cell's widened bounds `[lo, hi]` and some non-empty
//! bucket group `[b0, b1]` lies between the eq. 1 buckets of `fl(1 / w1)` and `fl(1 / w0)`.
//! Every depth `z` with `bucket(z) >= b0` has `z >= Zl = zmin + b0 / scale (1 - 2^-20)`
//! (the f32 subtraction and product each err by at most `2^-24` relatively), every one with
//! `bucket(z) <= b1 < B - 1` has `z < Zu = zmin + (b1 + 1) / scale (1 + 2^-20)`, so `[w0, w1]`
//! overlaps `W = [(1 - 2^-20) / Zu, (1 + 2^-20) / Zl]` (bucket 0: up to `+inf`; bucket
//! `B - 1`: down to 0). `[w0, w1]`, `[lo, hi]` and `W` pairwise overlap, so (Helly, in one
//! dimension) `[w0, w1]` holds a `w` of `W ∩ [lo, hi]`, whose slabs are in the cell's mask.
//! Up the chain: slab `k` of a texel is exactly the bit patterns
//! `[(base + k) << s, ((base + k + 1) << s) - 1]` (slab 0 from `bits(lo)`, slab 55 up to
//! `bits(hi)`), so the parent marks the slabs (in its partition) of that integer range cut to
//! the child's bounds, run by run of occupied child slabs; that `w` lies in the bounds of
//! every texel above the cell (min-max mips), so its slab is marked at every level. A texel's
//! computed range over its `λ` interval contains the range of every cell under it over that
//! cell's sub-interval (the walk's `w` is monotone in `λ`), so it holds that `w`, and `σ` is
//! monotone: the slabs of the ray's range meet the texel's mask. So a texel whose mask the
//! ray's slabs miss holds no cell the walk would trace there: skipping it tests no triangle
//! fewer. (Where `W ∩ [lo, hi]` is empty or the scale degenerate, the whole `[lo, hi]` is
//! marked.)
//!
//! | parameter | value | meaning |
//! |---|---|---|
//! | [`SLABS`] per texel | 56 | bits 0-55 of one `u64` per texel, beside its reciprocal bounds |
//! | shift `s` | per texel, 0-31 | slab width `2^s` f32 bit patterns: the finest reaching `hi` |
//! | margin | `2^-20` relative | widening of a bucket's depth interval (f32 rounding of eq. 1) |

use parallax_raster::dirt::DirtCapture;

/// Slabs per texel (mask bits `0..SLABS`; the bits above hold the texel's shift).
pub(crate) const SLABS: u32 = 56;

/// Relative widening of a bucket's depth interval and of its reciprocal.
const MARGIN: f64 = 1.0 / (1u64 << 20) as f64;

/// A mip texel as the walk reads it: reciprocal bounds `[lo, hi]` (`lo >= 0` or empty) and
/// `slabs`: the mask of occupied slabs in bits `0..SLABS`, the texel's partition shift in the
/// top byte.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(crate) struct Texel {
    pub lo: f32,
    pub hi: f32,
    pub slabs: u64,
}

impl Texel {
    /// The texel's partition shift.
    #[inline(always)]
    pub fn shift(&self) -> u32 {
        (self.slabs >> 56) as u32
    }

    /// Slab of reciprocal depth `w` in this texel's partition (module docs).
    #[inline(always)]
    pub fn slab(&self, w: f32) -> u32 {
        let s = self.shift();
        slab(w, s, self.lo.to_bits() >> s)
    }

    /// The slabs of `[w0, w1]` (`w0 <= w1`) as a mask.
    pub fn range_mask(&self, w0: f32, w1: f32) -> u64 {
        let (a, b) = (self.slab(w0), self.slab(w1));
        (u64::MAX >> (63 - (b - a))) << a
    }

    /// Whether an occupied slab lies in the slabs of `[w0, w1]` (`w0 <= w1`): the walk's test.
    #[inline(always)]
    pub fn meets(&self, w0: f32, w1: f32) -> bool {
        let s = self.shift();
        let base = self.lo.to_bits() >> s;
        let (a, b) = (slab(w0, s, base), slab(w1, s, base));
        // Bits above `b <= SLABS - 1` (the shift among them) are shifted out.
        (self.slabs >> a) << (63 - (b - a)) != 0
    }

    /// The bit patterns of the reciprocal depths of slab `k` inside `[lo, hi]` (as `u64`, an
    /// inclusive range).
    fn slab_bits(&self, k: u32) -> (u64, u64) {
        let s = self.shift();
        let base = (self.lo.to_bits() >> s) as u64;
        let a = if k == 0 {
            self.lo.to_bits() as u64
        } else {
            (base + k as u64) << s
        };
        let b = if k + 1 >= SLABS {
            self.hi.to_bits() as u64
        } else {
            (((base + k as u64 + 1) << s) - 1).min(self.hi.to_bits() as u64)
        };
        (a.max(self.lo.to_bits() as u64), b)
    }

    /// The slabs of the bit patterns `a..=b` as a mask.
    fn bits_mask(&self, a: u64, b: u64) -> u64 {
        let s = self.shift();
        let base = (self.lo.to_bits() >> s) as u64;
        let slab = |x: u64| ((x >> s).max(base) - base).min(SLABS as u64 - 1) as u32;
        let (a, b) = (slab(a), slab(b));
        (u64::MAX >> (63 - (b - a))) << a
    }

    /// A texel over `[lo, hi]` with no slab occupied: `lo` raised to `+0` if below, the
    /// finest shift whose slabs from `lo`'s cover `hi`.
    fn new(lo: f32, hi: f32) -> Texel {
        if lo > hi || lo.is_nan() || hi.is_nan() {
            return Texel { lo, hi, slabs: 0 };
        }
        let lo = if lo > 0.0 { lo } else { 0.0 };
        let (a, b) = (lo.to_bits(), hi.to_bits());
        let mut s = first_shift(a, b);
        while s < 31 && (b >> s) - (a >> s) >= SLABS {
            s += 1;
        }
        Texel {
            lo,
            hi,
            slabs: (s as u64) << 56,
        }
    }

    /// The occupied slabs.
    pub fn mask(&self) -> u64 {
        self.slabs & ((1 << SLABS) - 1)
    }
}

/// The slab-masked texels of one view (layout of `DirtCapture::recip_mip`).
#[derive(Clone, Debug)]
pub(crate) struct Slabs {
    pub texels: Vec<Texel>,
}

impl Slabs {
    /// The slab masks of every texel of `cap`.
    pub fn new(cap: &DirtCapture) -> Slabs {
        let recip = cap.recip_mip();
        let (levels, _) = cap.mip_arrays();
        let mut texels: Vec<Texel> = recip.iter().map(|&[lo, hi]| Texel::new(lo, hi)).collect();
        let nb = cap.buckets();
        let g = if nb <= 32 { 1 } else { nb.div_ceil(32) };
        for (t, rec) in texels.iter_mut().zip(cap.cell_records()) {
            let (lo, hi) = (t.lo, t.hi);
            if !(lo <= hi) {
                continue;
            }
            let full = t.range_mask(lo, hi);
            let scale = rec.scale as f64;
            if !(scale > 0.0 && scale.is_finite()) {
                t.slabs |= full;
                continue;
            }
            let mut m = 0u64;
            let mut bits = rec.mask;
            while bits != 0 {
                let k = bits.trailing_zeros();
                bits &= bits - 1;
                let b0 = k * g;
                let b1 = ((k + 1) * g).min(nb) - 1;
                let zmin = rec.zmin as f64;
                // The bucket group's depths (module docs), as reciprocal depths.
                let w_hi = if b0 == 0 {
                    f64::INFINITY
                } else {
                    let zl = zmin + b0 as f64 / scale * (1.0 - MARGIN);
                    if zl > 0.0 {
                        (1.0 + MARGIN) / zl
                    } else {
                        f64::INFINITY
                    }
                };
                let w_lo = if b1 + 1 >= nb {
                    0.0
                } else {
                    let zu = zmin + (b1 + 1) as f64 / scale * (1.0 + MARGIN);
                    if zu > 0.0 { (1.0 - MARGIN) / zu } else { 0.0 }
                };
                let (a, b) = ((w_lo as f32).max(lo), (w_hi as f32).min(hi));
                m |= if a <= b { t.range_mask(a, b) } else { full };
            }
            t.slabs |= m;
        }
        // A parent's slabs: every child's occupied slab (its reciprocal depths inside the
        // child's bounds, exact bit-pattern ranges) in the parent's partition.
        for k in 1..levels.len() {
            let (c, p) = (levels[k - 1], levels[k]);
            for y in 0..p.height {
                for x in 0..p.width {
                    let pi = p.offset + (y * p.width + x) as usize;
                    let parent = texels[pi];
                    let mut m = 0u64;
                    for cy in 2 * y..(2 * y + 2).min(c.height) {
                        for cx in 2 * x..(2 * x + 2).min(c.width) {
                            let child = texels[c.offset + (cy * c.width + cx) as usize];
                            let mut bits = child.mask();
                            while bits != 0 {
                                // One run of consecutive occupied slabs at a time.
                                let k0 = bits.trailing_zeros();
                                let run = (bits >> k0).trailing_ones();
                                let k1 = k0 + run - 1;
                                bits &= !((u64::MAX >> (64 - run)) << k0);
                                let (a, _) = child.slab_bits(k0);
                                let (_, b) = child.slab_bits(k1);
                                if a <= b {
                                    m |= parent.bits_mask(a, b);
                                }
                            }
                        }
                    }
                    texels[pi].slabs |= m;
                }
            }
        }
        Slabs { texels }
    }
}

/// Where [`Texel::new`]'s search for the finest shift may start (the same shift as from 0):
/// for `s < bitlen(b - a) - 6`, `(b >> s) - (a >> s) >= (b - a) >> s >= 2^6 > SLABS`, so every
/// step below it continues the search.
#[inline(always)]
fn first_shift(a: u32, b: u32) -> u32 {
    const _: () = assert!(SLABS <= 64);
    if b >= a {
        (32 - (b - a).leading_zeros()).saturating_sub(6)
    } else {
        0
    }
}

/// `σ(w)` for a partition `(shift, base)` (module docs).
#[inline(always)]
pub(crate) fn slab(w: f32, shift: u32, base: u32) -> u32 {
    let b = (w.to_bits() as i32).max(0) as u32;
    ((b >> shift).max(base) - base).min(SLABS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The search for the finest shift started at `first_shift` ends where the search from 0
    /// does, on random bounds of every magnitude and on zeros, subnormals and infinities.
    #[test]
    fn first_shift_skips_only_continuing_steps() {
        let reference = |a: u32, b: u32| {
            let mut s = 0;
            while s < 31 && (b >> s) - (a >> s) >= SLABS {
                s += 1;
            }
            s
        };
        let mut rng = parallax_core::sampling::Rng::for_pixel(1, 2, 3, 4);
        let mut v = vec![0.0f32, -0.0, 1e-45, 1e-38, 1.0, 3.0e38, f32::INFINITY];
        for _ in 0..2000 {
            let m = [1e-30, 1e-3, 1.0, 1e4, 1e30][rng.next_u32() as usize % 5];
            let x = rng.next_f32() * m;
            v.extend([x, x.next_up(), f32::from_bits(x.to_bits() + 55)]);
        }
        let mut checked = 0u64;
        for &lo in &v {
            for k in 0..60 {
                let hi = v[(lo.to_bits() as usize + k * 7919) % v.len()];
                if lo > hi {
                    continue;
                }
                // As `Texel::new` clamps it: -0.0 (and any lower bound <= 0) becomes +0.0.
                let lo = if lo > 0.0 { lo } else { 0.0 };
                let (a, b) = (lo.to_bits(), hi.to_bits());
                let mut s = first_shift(a, b);
                while s < 31 && (b >> s) - (a >> s) >= SLABS {
                    s += 1;
                }
                assert_eq!(s, reference(a, b), "[{lo}, {hi}]");
                checked += 1;
            }
        }
        assert!(checked > 50_000, "{checked}");
    }

    /// `σ` is monotone over non-negative `w`, puts `lo` in slab 0 and `hi` in the last slab at
    /// most, and each slab's bit-pattern range holds exactly the reciprocal depths of the
    /// texel's bounds in that slab.
    #[test]
    fn slab_is_monotone() {
        for (lo, hi) in [
            (0.01f32, 2.0f32),
            (1e-3, 1e3),
            (0.5, 0.5),
            (1e-30, 1e30),
            (0.25, 0.2500001),
            (-1.0, 3.0),
            (0.0, f32::INFINITY),
        ] {
            let t = Texel::new(lo, hi);
            assert!(t.lo >= 0.0 && t.shift() <= 31);
            assert_eq!(t.slab(t.lo), 0);
            assert!(t.slab(hi) < SLABS);
            let mut prev = 0;
            let mut w = 0.0f32;
            while w < 1e6 {
                let k = t.slab(w);
                assert!(k >= prev && k < SLABS, "w {w}: {k} after {prev}");
                if w >= t.lo && w <= t.hi {
                    let (a, b) = t.slab_bits(k);
                    assert!((a..=b).contains(&(w.to_bits() as u64)), "w {w} slab {k}");
                }
                prev = k;
                w = if w == 0.0 { 1e-6 } else { w * 1.0007 };
            }
            assert_eq!(t.slab(-1.0), 0);
            assert!(t.slab(f32::INFINITY) >= t.slab(hi));
            assert_eq!(t.mask(), 0);
        }
        // The finest partition covering the range: a 1% range gets slabs a few ulps wide.
        assert!(Texel::new(1.0, 1.01).shift() < 12);
        assert!(Texel::new(1.0, 200.0).shift() >= 20);
    }

    /// The skip is conservative: on a random soup's cube faces (B = 16 and B = 48, grouped mask
    /// bits), every reciprocal depth range `[w0, w1]` for which the walk's level-0 test would
    /// trace a cell (overlap with the cell's bounds and a non-empty bucket between the buckets
    /// of `1 / w1` and `1 / w0`) meets the slab mask of the cell and of every texel above it;
    /// and the masks skip most of the ranges the bounds alone would not.
    #[test]
    fn skips_only_cells_the_walk_would_not_trace() {
        use parallax_raster::dirt::{DirtOptions, DirtViews, DirtViewsOptions, bucket_index};
        let mut rng = parallax_core::sampling::Rng::for_pixel(3, 5, 7, 11);
        let m = super::super::test_soup::random_soup(&mut rng, 300);
        let mut r = |s: f32| (rng.next_f32() - 0.5) * s;
        let (mut traced, mut bounds_only, mut skipped) = (0u64, 0u64, 0u64);
        for buckets in [16u32, 48] {
            let opts = DirtViewsOptions {
                face_size: 32,
                capture: DirtOptions {
                    tile_size: 2,
                    buckets,
                    ..DirtOptions::default()
                },
                camera_tile_size: None,
            };
            let views = DirtViews::build(&m, None, glam::Vec3::ZERO, &opts).expect("build");
            for cap in &views.cube.faces {
                let s = Slabs::new(cap);
                let (levels, _) = cap.mip_arrays();
                let (cw, _) = cap.cells();
                for (i, rec) in cap.cell_records().iter().enumerate() {
                    let [lo, hi] = cap.recip_mip()[i];
                    if !(lo <= hi) {
                        continue;
                    }
                    let (x, y) = (i as u32 % cw, i as u32 / cw);
                    for _ in 0..200 {
                        // Ranges around the cell's bounds, some far outside.
                        let mut w = [0.0f32; 2].map(|_| lo + (hi - lo) * (r(3.0) + 0.5));
                        w.sort_by(f32::total_cmp);
                        let [w0, w1] = w.map(|v| v.max(1e-6));
                        if !(w1 >= lo && w0 <= hi) {
                            continue;
                        }
                        let b = |w: f32| bucket_index(rec.zmin, rec.scale, buckets, 1.0 / w);
                        let (b0, b1) = (b(w1), b(w0));
                        let trace = rec.mask
                            & parallax_raster::dirt::bucket_mask(b0.min(b1), b0.max(b1), buckets)
                            != 0;
                        for (k, l) in levels.iter().enumerate() {
                            let t = l.offset + ((y >> k) * l.width + (x >> k)) as usize;
                            let hit = s.texels[t].meets(w0, w1);
                            assert!(!trace || hit, "cell {i} level {k} [{w0}, {w1}]");
                            if k == 0 {
                                traced += trace as u64;
                                bounds_only += !trace as u64;
                                skipped += (!trace && !hit) as u64;
                            }
                        }
                    }
                }
            }
        }
        assert!(traced > 1000, "{traced}");
        // Measured: 4 401 of the 4 815 ranges the bounds let through needlessly are skipped
        // (3 024 with one partition of 64 slabs per view).
        assert!(
            skipped * 10 > bounds_only * 8,
            "{skipped} of {bounds_only} skipped"
        );
    }
}
