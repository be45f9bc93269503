//! The object binner of the binned SAH build (Wald 2007 §3.1): one pass drops every
//! reference's (doubled) centroid into one of `nb` equal-width bins on each of the three axes
//! at once (the three bin indices computed in SSE lanes), recording a count and a box per bin;
//! a sweep over the bin boundaries evaluates the surface area heuristic of each (module docs
//! of `build.rs`) and returns the cheapest. Nodes with more than [`PAR_BIN_THRESHOLD`]
//! references are binned over rayon chunks whose bins are merged.
//!
//! A bin keeps its box as a [`NegBox`] (the minimum and the negated maximum, Embree's layout),
//! so that adding a reference is one 8-lane minimum (`bin_into_avx`, AVX at run time, with
//! the portable twin `bin_into_portable` tested equal; nodes of [`AVX_BIN_MAX`] references
//! or more take the portable loop, which bins them faster per reference on Zen 3, see
//! docs/notes/bvh.md) and the sweep's running unions are
//! lane-wise minima; the boxes, areas and costs are bit for bit those of [`BoxA`] and
//! [`Aabb`] unions (tests in `object_bins_tests.rs`).

use glam::{Vec3, Vec3A};
use parallax_core::Aabb;
use rayon::prelude::*;

use super::prim_ref::{BoxA, NegBox, PrimRef};
use crate::options::{BuildOptions, MAX_BINS};

/// Nodes with more triangles than this are binned in parallel chunks.
pub(crate) const PAR_BIN_THRESHOLD: usize = 32 * 1024;

/// Nodes (or parallel chunks) with fewer references than this are binned by `bin_into_avx`;
/// larger ones by `bin_into_portable` (the same bins bit for bit).
pub(crate) const AVX_BIN_MAX: usize = 1024;

/// The SAH's intersection count of `cnt` triangles in leaves tested `block` triangles at a
/// time: `ceil(cnt / block)` (`block = 1`: the triangle count).
#[inline(always)]
pub(crate) fn sah_count(cnt: u32, block: usize) -> f32 {
    cnt.div_ceil(block as u32) as f32
}

/// Bins of the three axes: per bin a count and the union of its references' boxes as a
/// [`NegBox`] (minimum and negated maximum), so that adding a reference's box is one 8-lane
/// minimum.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
pub(super) struct Bins {
    pub(super) boxes: [[NegBox; MAX_BINS]; 3],
    /// Per bin, the counts of the three axes (lane 3 unused), so the sweep loads them at once.
    pub(super) counts: [[u32; 4]; MAX_BINS],
}

pub(super) fn new_bins() -> Bins {
    Bins {
        boxes: [[NegBox::EMPTY; MAX_BINS]; 3],
        counts: [[0; 4]; MAX_BINS],
    }
}

impl Bins {
    /// The union of the boxes of bins `range` of `axis`, in bin order.
    pub(super) fn union(&self, axis: usize, range: std::ops::Range<usize>) -> BoxA {
        let b = &self.boxes[axis][range];
        b.iter().fold(NegBox::EMPTY, |u, x| u.union(*x)).boxa()
    }
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
        let i = trunc3(self.clamped(c));
        [
            i[0] as usize & (MAX_BINS - 1),
            i[1] as usize & (MAX_BINS - 1),
            i[2] as usize & (MAX_BINS - 1),
        ]
    }

    /// `f` clamped to `0..=bins - 1` per lane, NaN -> 0 ([`Binner::bin`] before the truncation).
    #[inline(always)]
    fn clamped(&self, c: Vec3A) -> Vec3A {
        let f = (c - self.min) * self.scale;
        self.last.min(f).max(Vec3A::ZERO)
    }

    /// Bin index on one axis: the scalar definition, which the tests hold [`Binner::bin`] and
    /// [`Binner::left_of`] to.
    #[cfg(test)]
    pub(super) fn bin_axis(&self, c: Vec3A, axis: usize) -> usize {
        self.index((c[axis] - self.min[axis]) * self.scale[axis])
    }

    /// The partition's side test of a split before bin `split` (in `1..bins`) on `axis`: true
    /// when the reference's centroid bins before `split` ([`Binner::bin_axis`]). That is the
    /// case exactly when `!(f >= split)`, with `f` the same sum, subtraction and product (the
    /// truncation of `f < split` is below `split`, a NaN bins to 0 and compares false), so
    /// the test needs neither the conversion nor the clamp.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN `f` must give true
    #[inline(always)]
    pub(super) fn left_of(&self, axis: usize, split: usize) -> impl Fn(&PrimRef) -> bool {
        debug_assert!(axis < 3 && (1..self.bins).contains(&split));
        let (m, s, sp) = (self.min[axis], self.scale[axis], split as f32);
        move |r: &PrimRef| {
            let (lo, hi) = r.axis_min_max(axis);
            !((lo + hi - m) * s >= sp)
        }
    }

    #[cfg(test)]
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

/// Resets the first `binner.bins` bins of each axis and bins `refs` into them:
/// [`bin_into_avx`] where the CPU has AVX and `refs` has fewer than [`AVX_BIN_MAX`]
/// references, else [`bin_into_portable`] (tested equal).
fn bin_into(refs: &[PrimRef], binner: &Binner, bins: &mut Bins) {
    for axis in 0..3 {
        bins.boxes[axis][..binner.bins].fill(NegBox::EMPTY);
    }
    bins.counts[..binner.bins].fill([0; 4]);
    #[cfg(target_arch = "x86_64")]
    if refs.len() < AVX_BIN_MAX && std::is_x86_feature_detected!("avx") {
        // SAFETY: AVX is present.
        return unsafe { bin_into_avx(refs, binner, bins) };
    }
    bin_into_portable(refs, binner, bins)
}

fn bin_into_portable(refs: &[PrimRef], binner: &Binner, bins: &mut Bins) {
    for r in refs {
        let b = binner.bin(r.centroid2());
        let bx = NegBox::of(r);
        for (axis, &k) in b.iter().enumerate() {
            bins.counts[k][axis] += 1;
            bins.boxes[axis][k] = bins.boxes[axis][k].union(bx);
        }
    }
}

/// [`bin_into_portable`] with each box union as one 8-lane `vminps` (and the reference's
/// [`NegBox`] as one load and one sign flip; the operand order of [`NegBox::union`]), and
/// the three axes' bin indices ([`Binner::bin`]: the same clamp and truncation, masked to
/// `0..MAX_BINS`) turned into byte offsets of the boxes and counts in lanes.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn bin_into_avx(refs: &[PrimRef], binner: &Binner, bins: &mut Bins) {
    use std::arch::x86_64::*;
    const AXIS_BYTES: usize = MAX_BINS * std::mem::size_of::<NegBox>();
    let neg_hi = _mm256_setr_ps(0.0, 0.0, 0.0, 0.0, -0.0, -0.0, -0.0, -0.0);
    let mask = _mm_set1_epi32(MAX_BINS as i32 - 1);
    let boxes = bins.boxes.as_mut_ptr() as *mut u8;
    let counts = bins.counts.as_mut_ptr() as *mut u8;
    for r in refs {
        // SAFETY: `PrimRef` is `lo`, `hi` in 32 aligned bytes (`repr(C, align(32))`), as
        // `NegBox`. The masked indices are below `MAX_BINS`, so the offsets stay inside the
        // axis' `MAX_BINS` boxes (32 bytes each, aligned) and counts rows (16 bytes each).
        unsafe {
            let v = _mm256_xor_ps(_mm256_load_ps(r as *const PrimRef as *const f32), neg_hi);
            let i = _mm_and_si128(_mm_cvttps_epi32(binner.clamped(r.centroid2()).into()), mask);
            let (ob, oc) = (_mm_slli_epi32::<5>(i), _mm_slli_epi32::<4>(i));
            let add = |ob: i32, oc: i32, axis: usize| {
                let c = counts.add(oc as usize + 4 * axis) as *mut u32;
                *c += 1;
                let p = boxes.add(axis * AXIS_BYTES + ob as usize) as *mut f32;
                _mm256_store_ps(p, _mm256_min_ps(_mm256_load_ps(p), v));
            };
            add(_mm_cvtsi128_si32(ob), _mm_cvtsi128_si32(oc), 0);
            add(_mm_extract_epi32::<1>(ob), _mm_extract_epi32::<1>(oc), 1);
            add(_mm_extract_epi32::<2>(ob), _mm_extract_epi32::<2>(oc), 2);
        }
    }
}

fn merge_bins(mut a: Bins, b: &Bins) -> Bins {
    for axis in 0..3 {
        for i in 0..MAX_BINS {
            a.counts[i][axis] += b.counts[i][axis];
            a.boxes[axis][i] = a.boxes[axis][i].union(b.boxes[axis][i]);
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
            .reduce(new_bins, |a, b| merge_bins(a, &b));
    } else {
        bin_into(refs, &binner, scratch);
    }
    let skip = [0, 1, 2].map(|a| binner.scale[a] == 0.0);
    let block = opts.sah_block_size;
    #[cfg(target_arch = "x86_64")]
    let best = if block.is_power_of_two() && std::is_x86_feature_detected!("avx") {
        // SAFETY: AVX is present.
        unsafe { sweep_avx(scratch, nb, n, skip, block) }
    } else {
        sweep_portable(scratch, nb, n, skip, block)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let best = sweep_portable(scratch, nb, n, skip, block);
    ObjectSplit {
        cost: best.0,
        axis: best.1,
        split: best.2,
        binner,
    }
}

/// The SAH sweep over the first `nb` bins of the axes not in `skip`, for a node of `n`
/// references: right-to-left accumulated area * count, then left-to-right cost evaluation.
/// Returns the least cost, its axis and the first bin of its right side (the first in axis,
/// then bin order among equal costs; `(inf, 0, 0)` when no boundary separates the centroids).
#[allow(clippy::needless_range_loop)] // the axis addresses the boxes, counts and `skip`
fn sweep_portable(
    bins: &Bins,
    nb: usize,
    n: usize,
    skip: [bool; 3],
    block: usize,
) -> (f32, usize, usize) {
    let mut best = (f32::INFINITY, 0usize, 0usize);
    for axis in 0..3 {
        if skip[axis] {
            continue;
        }
        let boxes = &bins.boxes[axis][..nb];
        let mut right_cost = [0.0f32; MAX_BINS];
        let (mut acc, mut cnt) = (NegBox::EMPTY, 0u32);
        for i in (1..nb).rev() {
            acc = acc.union(boxes[i]);
            cnt += bins.counts[i][axis];
            right_cost[i] = acc.area() * sah_count(cnt, block);
        }
        let (mut acc, mut cnt) = (NegBox::EMPTY, 0u32);
        for i in 1..nb {
            acc = acc.union(boxes[i - 1]);
            cnt += bins.counts[i - 1][axis];
            if cnt == 0 || cnt as usize == n {
                continue;
            }
            let cost = acc.area() * sah_count(cnt, block) + right_cost[i];
            if cost < best.0 {
                best = (cost, axis, i);
            }
        }
    }
    best
}

/// [`NegBox::area`] of three boxes (8 lanes each), in lanes 0-2 (lane 3 repeats lane 2): the
/// boxes transposed to one vector per coordinate, then the same operations per lane.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
unsafe fn area3(
    a0: std::arch::x86_64::__m256,
    a1: std::arch::x86_64::__m256,
    a2: std::arch::x86_64::__m256,
) -> std::arch::x86_64::__m128 {
    use std::arch::x86_64::*;
    // Per 128-bit half (minimum, negated maximum): t0 = x0 x1 y0 y1, t1 = z0 z1 w0 w1,
    // t2 = x2 x2 y2 y2, t3 = z2 z2 w2 w2.
    let (t0, t1) = (_mm256_unpacklo_ps(a0, a1), _mm256_unpackhi_ps(a0, a1));
    let (t2, t3) = (_mm256_unpacklo_ps(a2, a2), _mm256_unpackhi_ps(a2, a2));
    let x = _mm256_shuffle_ps::<0b01_00_01_00>(t0, t2);
    let y = _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2);
    let z = _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3);
    let sign = _mm_set1_ps(-0.0);
    let (lx, hx) = (
        _mm256_castps256_ps128(x),
        _mm_xor_ps(_mm256_extractf128_ps::<1>(x), sign),
    );
    let (ly, hy) = (
        _mm256_castps256_ps128(y),
        _mm_xor_ps(_mm256_extractf128_ps::<1>(y), sign),
    );
    let (lz, hz) = (
        _mm256_castps256_ps128(z),
        _mm_xor_ps(_mm256_extractf128_ps::<1>(z), sign),
    );
    let full = _mm_and_ps(
        _mm_and_ps(_mm_cmple_ps(lx, hx), _mm_cmple_ps(ly, hy)),
        _mm_cmple_ps(lz, hz),
    );
    let zero = _mm_setzero_ps();
    let (ex, ey, ez) = (
        _mm_max_ps(_mm_sub_ps(hx, lx), zero),
        _mm_max_ps(_mm_sub_ps(hy, ly), zero),
        _mm_max_ps(_mm_sub_ps(hz, lz), zero),
    );
    let s = _mm_add_ps(
        _mm_add_ps(_mm_mul_ps(ex, ey), _mm_mul_ps(ey, ez)),
        _mm_mul_ps(ez, ex),
    );
    _mm_and_ps(_mm_mul_ps(_mm_set1_ps(2.0), s), full)
}

/// [`sweep_portable`] with the three axes in lanes: per boundary, three 8-lane unions, the
/// areas of [`area3`], the counts of the three axes added at once and [`sah_count`] as a shift
/// (`block` a power of two), then per lane the first least cost, and the first axis among
/// equal least costs.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
unsafe fn sweep_avx(
    bins: &Bins,
    nb: usize,
    n: usize,
    skip: [bool; 3],
    block: usize,
) -> (f32, usize, usize) {
    use std::arch::x86_64::*;
    debug_assert!(block.is_power_of_two() && (2..=MAX_BINS).contains(&nb));
    let (round, shift) = (
        _mm_set1_epi32(block as i32 - 1),
        _mm_cvtsi32_si128(block.trailing_zeros() as i32),
    );
    // SAFETY: `Bins` is aligned to 32 bytes and its `NegBox`es are 32 bytes; the counts are
    // 16-byte rows. Indices are below `nb <= MAX_BINS`.
    unsafe {
        // `ceil(cnt / block)` as a float, as `sah_count`.
        let sah = |c: __m128i| _mm_cvtepi32_ps(_mm_srl_epi32(_mm_add_epi32(c, round), shift));
        let bx =
            |a: usize, i: usize| _mm256_load_ps(&bins.boxes[a][i] as *const NegBox as *const f32);
        let cnt_at = |i: usize| _mm_loadu_si128(bins.counts[i].as_ptr() as *const __m128i);
        let mut right_cost = [_mm_setzero_ps(); MAX_BINS];
        let inf = _mm256_set1_ps(f32::INFINITY);
        let (mut a0, mut a1, mut a2, mut cnt) = (inf, inf, inf, _mm_setzero_si128());
        for i in (1..nb).rev() {
            a0 = _mm256_min_ps(a0, bx(0, i));
            a1 = _mm256_min_ps(a1, bx(1, i));
            a2 = _mm256_min_ps(a2, bx(2, i));
            cnt = _mm_add_epi32(cnt, cnt_at(i));
            right_cost[i] = _mm_mul_ps(area3(a0, a1, a2), sah(cnt));
        }
        let (zero, all) = (_mm_setzero_si128(), _mm_set1_epi32(n as i32));
        let (mut best_c, mut best_i) = (_mm_set1_ps(f32::INFINITY), _mm_setzero_ps());
        let (mut a0, mut a1, mut a2, mut cnt) = (inf, inf, inf, _mm_setzero_si128());
        for i in 1..nb {
            a0 = _mm256_min_ps(a0, bx(0, i - 1));
            a1 = _mm256_min_ps(a1, bx(1, i - 1));
            a2 = _mm256_min_ps(a2, bx(2, i - 1));
            cnt = _mm_add_epi32(cnt, cnt_at(i - 1));
            let cost = _mm_add_ps(_mm_mul_ps(area3(a0, a1, a2), sah(cnt)), right_cost[i]);
            // `cnt == 0 || cnt == n`: no split here; its cost becomes infinite (never `<`).
            let none = _mm_or_si128(_mm_cmpeq_epi32(cnt, zero), _mm_cmpeq_epi32(cnt, all));
            let cost = _mm_blendv_ps(cost, _mm_set1_ps(f32::INFINITY), _mm_castsi128_ps(none));
            let better = _mm_cmplt_ps(cost, best_c);
            best_c = _mm_blendv_ps(best_c, cost, better);
            best_i = _mm_blendv_ps(best_i, _mm_castsi128_ps(_mm_set1_epi32(i as i32)), better);
        }
        let c: [f32; 4] = std::mem::transmute(best_c);
        let k: [u32; 4] = std::mem::transmute(best_i);
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for axis in 0..3 {
            if !skip[axis] && c[axis] < best.0 {
                best = (c[axis], axis, k[axis] as usize);
            }
        }
        best
    }
}

#[cfg(test)]
#[path = "object_bins_tests.rs"]
mod tests;
