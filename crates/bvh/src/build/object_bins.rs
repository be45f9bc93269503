//! The object binner of the binned SAH build (Wald 2007 §3.1): one pass drops every
//! reference's (doubled) centroid into one of `nb` equal-width bins on each of the three axes
//! at once (the three bin indices computed in SSE lanes), recording a count and a box per bin;
//! a sweep over the bin boundaries evaluates the surface area heuristic of each (module docs
//! of `build.rs`) and returns the cheapest. Nodes with more than [`PAR_BIN_THRESHOLD`]
//! references are binned over rayon chunks whose bins are merged.

use glam::{Vec3, Vec3A};
use parallax_core::Aabb;
use rayon::prelude::*;

use super::prim_ref::{BoxA, PrimRef};
use crate::options::{BuildOptions, MAX_BINS};

/// Nodes with more triangles than this are binned in parallel chunks.
pub(crate) const PAR_BIN_THRESHOLD: usize = 32 * 1024;

/// The SAH's intersection count of `cnt` triangles in leaves tested `block` triangles at a
/// time: `ceil(cnt / block)` (`block = 1`: the triangle count).
#[inline(always)]
pub(crate) fn sah_count(cnt: u32, block: usize) -> f32 {
    cnt.div_ceil(block as u32) as f32
}

#[derive(Clone, Copy)]
pub(super) struct Bin {
    pub(super) bounds: BoxA,
    pub(super) count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: BoxA::EMPTY,
    count: 0,
};

/// Bins of the three axes.
#[derive(Clone, Copy)]
pub(super) struct Bins(pub(super) [[Bin; MAX_BINS]; 3]);

pub(super) fn new_bins() -> Bins {
    Bins([[EMPTY_BIN; MAX_BINS]; 3])
}

/// Maps doubled centroids to bin indices: `bin = floor((c - min) * scale)`, clamped.
#[derive(Clone, Copy)]
pub(super) struct Binner {
    /// `w` = 0, so that the centroid's `w` lane stays a normal float (or 0) in `bin`.
    min: Vec3A,
    scale: Vec3A,
    /// `bins - 1` in every lane.
    last: Vec3A,
    pub(super) bins: usize,
}

impl Binner {
    fn new(cbounds: &Aabb, bins: usize) -> Self {
        let e = cbounds.extent();
        // (1 - 1e-6) keeps the maximum centroid inside the last bin; zero extent -> scale 0.
        let k = bins as f32 * (1.0 - 1e-6);
        let scale = Vec3::select(e.cmpgt(Vec3::ZERO), Vec3::splat(k) / e, Vec3::ZERO);
        Self {
            min: Vec3A::from_vec4(cbounds.min.extend(0.0)),
            scale: Vec3A::from_vec4(scale.extend(0.0)),
            last: Vec3A::splat((bins - 1) as f32),
            bins,
        }
    }

    /// Bin index per axis: `floor(f)` clamped to `0..bins`, NaN -> 0, i.e. the value of
    /// `(f as i32).clamp(0, bins - 1)` ([`Binner::index`]) for every `f`, computed in lanes:
    /// `last < f ? last : f` keeps a NaN, `x > 0 ? x : 0` turns it (and negatives) into 0, and
    /// the truncation of a value in `0..=bins - 1` is its floor.
    #[inline(always)]
    fn bin(&self, c: Vec3A) -> [usize; 3] {
        let f = (c - self.min) * self.scale;
        let g = self.last.min(f).max(Vec3A::ZERO);
        let i = trunc3(g);
        [
            i[0] as usize & (MAX_BINS - 1),
            i[1] as usize & (MAX_BINS - 1),
            i[2] as usize & (MAX_BINS - 1),
        ]
    }

    /// Bin index on one axis (the partition needs only the split axis).
    #[inline(always)]
    pub(super) fn bin_axis(&self, c: Vec3A, axis: usize) -> usize {
        self.index((c[axis] - self.min[axis]) * self.scale[axis])
    }

    #[inline(always)]
    fn index(&self, f: f32) -> usize {
        // `NaN as i32` is 0; the mask (a no-op, bins <= MAX_BINS = 32) drops bounds checks.
        (f as i32).clamp(0, self.bins as i32 - 1) as usize & (MAX_BINS - 1)
    }
}

/// Truncation of three lanes that hold values in `0..=31` (one `cvttps2dq` on x86-64; the
/// portable twin's `as i32` gives the same values there).
#[inline(always)]
pub(super) fn trunc3(g: Vec3A) -> [i32; 4] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, __m128i, _mm_cvttps_epi32};
        let v: __m128 = g.into();
        // SAFETY: SSE2 is part of the x86-64 baseline.
        let i: __m128i = unsafe { _mm_cvttps_epi32(v) };
        // SAFETY: `__m128i` and `[i32; 4]` have the same size; every bit pattern is valid.
        unsafe { std::mem::transmute::<__m128i, [i32; 4]>(i) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        trunc3_portable(g)
    }
}

#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn trunc3_portable(g: Vec3A) -> [i32; 4] {
    [g.x as i32, g.y as i32, g.z as i32, 0]
}

/// Bins `refs` into fresh bins (the parallel chunks of large nodes).
fn bin_refs(refs: &[PrimRef], binner: &Binner) -> Bins {
    let mut bins = new_bins();
    bin_into(refs, binner, &mut bins);
    bins
}

/// Resets the first `binner.bins` bins of each axis and bins `refs` into them.
fn bin_into(refs: &[PrimRef], binner: &Binner, bins: &mut Bins) {
    for axis_bins in bins.0.iter_mut() {
        axis_bins[..binner.bins].fill(EMPTY_BIN);
    }
    for r in refs {
        let b = binner.bin(r.centroid2());
        let (lo, hi) = (r.min(), r.max());
        for (axis_bins, &k) in bins.0.iter_mut().zip(&b) {
            let bin = &mut axis_bins[k];
            bin.count += 1;
            bin.bounds.min = bin.bounds.min.min(lo);
            bin.bounds.max = bin.bounds.max.max(hi);
        }
    }
}

fn merge_bins(mut a: Bins, b: Bins) -> Bins {
    for axis in 0..3 {
        for i in 0..MAX_BINS {
            a.0[axis][i].count += b.0[axis][i].count;
            a.0[axis][i].bounds = a.0[axis][i].bounds.union(b.0[axis][i].bounds);
        }
    }
    a
}

/// The best binned object split of a node: its unnormalised SAH cost (`A(left) N(left) +
/// A(right) N(right)`, infinite when no bin boundary separates the centroids), its axis, the
/// first bin of its right side and the binner. The bins stay in the caller's scratch.
pub(super) struct ObjectSplit {
    pub(super) cost: f32,
    pub(super) axis: usize,
    pub(super) split: usize,
    pub(super) binner: Binner,
}

/// Bins `refs` by centroid into `scratch` and sweeps the bin boundaries (module docs).
pub(super) fn find_object_split(
    refs: &[PrimRef],
    cbounds: &Aabb,
    opts: &BuildOptions,
    scratch: &mut Bins,
) -> ObjectSplit {
    let n = refs.len();
    // Fewer bins for smaller nodes, as Embree's binner (`BinMapping`: `min(BINS, 4 + 0.05 N)`):
    // most nodes are small, and a 32-bin sweep over a few triangles dominated build profiles.
    let nb = opts.bins.min(4 + n / 20).max(2);
    let binner = Binner::new(cbounds, nb);
    if n > PAR_BIN_THRESHOLD {
        *scratch = refs
            .par_chunks(8192)
            .map(|c| bin_refs(c, &binner))
            .reduce(new_bins, merge_bins);
    } else {
        bin_into(refs, &binner, scratch);
    }
    let bins = &*scratch;

    // Sweep: right-to-left accumulated area * count, then left-to-right cost evaluation.
    let mut best = (f32::INFINITY, 0usize, 0usize); // (cost, axis, first bin of the right side)
    for axis in 0..3 {
        if binner.scale[axis] == 0.0 {
            continue;
        }
        let bins = &bins.0[axis][..nb];
        let mut right_cost = [0.0f32; MAX_BINS];
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in (1..nb).rev() {
            acc = acc.union(bins[i].bounds.aabb());
            cnt += bins[i].count;
            right_cost[i] = acc.surface_area() * sah_count(cnt, opts.sah_block_size);
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0u32);
        for i in 1..nb {
            acc = acc.union(bins[i - 1].bounds.aabb());
            cnt += bins[i - 1].count;
            if cnt == 0 || cnt as usize == n {
                continue;
            }
            let cost = acc.surface_area() * sah_count(cnt, opts.sah_block_size) + right_cost[i];
            if cost < best.0 {
                best = (cost, axis, i);
            }
        }
    }
    ObjectSplit {
        cost: best.0,
        axis: best.1,
        split: best.2,
        binner,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_bin_index_equals_the_scalar_clamp() {
        let mut s = 11u32;
        let mut rnd = || {
            s = s.wrapping_mul(747796405).wrapping_add(2891336453);
            s
        };
        let special = [
            0.0,
            -0.0,
            0.5,
            0.999_999_9,
            1.0,
            30.999_998,
            31.0,
            31.5,
            32.0,
            1e9,
            3e9,
            -0.5,
            -1.0,
            -3e9,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::MIN_POSITIVE,
        ];
        for bins in [2usize, 5, 17, 32] {
            let binner = Binner {
                min: Vec3A::ZERO,
                scale: Vec3A::ONE,
                last: Vec3A::splat((bins - 1) as f32),
                bins,
            };
            let check = |f: Vec3A| {
                let b = binner.bin(f);
                for axis in 0..3 {
                    assert_eq!(b[axis], binner.index(f[axis]), "{f:?} {bins}");
                    assert_eq!(b[axis], binner.bin_axis(f, axis), "{f:?} {bins}");
                }
                let g = binner.last.min(f).max(Vec3A::ZERO);
                assert_eq!(trunc3(g)[..3], trunc3_portable(g)[..3], "{g:?}");
            };
            for &x in &special {
                for &y in &special {
                    check(Vec3A::new(x, y, special[(rnd() % 18) as usize]));
                }
            }
            for _ in 0..100_000 {
                let f = f32::from_bits(rnd());
                let g = (rnd() % 4000) as f32 / 100.0 - 2.0;
                check(Vec3A::new(f, g, -g));
            }
        }
    }
}
