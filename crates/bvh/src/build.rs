//! Binned SAH build of a binary BVH (Wald 2007, "On fast Construction of SAH-based Bounding
//! Volume Hierarchies", IEEE RT'07), parallel with rayon.
//!
//! Per node: one pass computes the node bounds and the bounds of the triangle centroids; a second
//! pass drops every centroid into one of `bins` equal-width bins on each of the three axes at once
//! (Wald 2007 §3.1), recording a count and a box per bin; a sweep over the bin boundaries
//! evaluates the surface area heuristic (Goldsmith & Salmon 1987, MacDonald & Booth 1990)
//!
//! ```text
//! cost(split) = C_trav * A(node) + C_isect * (A(left) * N(left) + A(right) * N(right))
//! cost(leaf)  = C_isect * A(node) * N(node)
//! ```
//!
//! where `N` counts a node's triangles in blocks of `sah_block_size` (`ceil(n / 4)` by
//! default, as Embree's `sahBlockSize`): the traversal tests a leaf four triangles at a time
//! (`tri4.rs`), so a leaf of four costs what a leaf of one does, and the SAH keeps leaves of
//! up to four (and, where cheaper, eight) triangles instead of splitting them into
//! half-empty blocks (about 40% fewer nodes and blocks on the scenes, `docs/notes/bvh.md`).
//! (left unnormalised so that zero-area nodes of degenerate triangles need no division), and the
//! triangle references are partitioned in place. Parallelism (Wald 2007 §4): the two children of
//! a node with more than `parallel_threshold` triangles are built with `rayon::join`, and the two
//! passes over a node with more than [`PAR_BIN_THRESHOLD`] triangles run over rayon chunks.
//!
//! Robustness: when all centroids coincide (no bin split exists), or below depth
//! [`MAX_SAH_DEPTH`], the node is split at the object median instead, so the depth is at most
//! `MAX_SAH_DEPTH + log2(n)` and the traversal stack bound of `traverse.rs` holds.

use glam::{Vec3, Vec3A, Vec4};
use parallax_core::Aabb;
use rayon::prelude::*;

use crate::options::{BuildOptions, MAX_BINS};

mod spatial;
pub(crate) use spatial::build_binary_spatial;

/// Below this depth the binned SAH decides; deeper nodes split at the object median.
pub(crate) const MAX_SAH_DEPTH: u32 = 48;
/// Nodes with more triangles than this are binned in parallel chunks.
pub(crate) const PAR_BIN_THRESHOLD: usize = 32 * 1024;

/// The `w` bits of [`PrimRef::lo`] are `id + ID_BIAS`: a normal float for every id below
/// 2^27 (exponent field 1..=16), so the centroid's `w` lane (`lo + hi`, `hi.w = 0`) never
/// computes with a denormal (which would cost a microcode assist per addition).
const ID_BIAS: u32 = 1 << 23;

/// A triangle reference, 32 bytes: its bounds as two 4-lane vectors (SSE min / max per
/// reference and bin, as Embree's `PrimRef`) with its index in the scene's mesh in the
/// fourth lane of `lo`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

const _: () = assert!(std::mem::size_of::<PrimRef>() == 32);

impl PrimRef {
    pub fn new(min: Vec3, max: Vec3, id: u32) -> Self {
        debug_assert!((id as usize) < crate::node::MAX_TRIANGLES);
        Self {
            lo: min.extend(f32::from_bits(id + ID_BIAS)),
            hi: max.extend(0.0),
        }
    }

    /// The triangle's index in the mesh.
    #[inline(always)]
    pub fn id(&self) -> u32 {
        self.lo.w.to_bits() - ID_BIAS
    }

    #[inline(always)]
    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    #[inline(always)]
    fn max(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }

    /// The same triangle with the box `b` (a clipped piece, `spatial.rs`).
    #[inline(always)]
    fn with_box(&self, b: BoxA) -> Self {
        Self {
            lo: b.min.extend(self.lo.w),
            hi: b.max.extend(0.0),
        }
    }

    /// Twice the box centre (the factor 2 cancels in binning). Lane `w` is a normal float.
    #[inline(always)]
    fn centroid2(&self) -> Vec3A {
        self.min() + self.max()
    }
}

/// A node of the binary build tree, in a flat arena ([`BTree`]). Leaves index the
/// partitioned reference array; inner nodes index their two children in the arena.
#[derive(Clone, Copy, Debug)]
pub(crate) enum BNode {
    Leaf {
        bounds: Aabb,
        start: u32,
        count: u32,
    },
    Inner {
        bounds: Aabb,
        children: [u32; 2],
    },
}

impl BNode {
    pub fn bounds(&self) -> Aabb {
        match self {
            BNode::Leaf { bounds, .. } | BNode::Inner { bounds, .. } => *bounds,
        }
    }
}

/// The binary build tree: `2 n - 1` arena slots for `n` references (a subtree over the
/// references `offset..offset + m` owns the slots `2 offset..2 (offset + m) - 1`, an inner
/// node split after `k` of them sits at slot `2 (offset + k) - 1`, between its children's
/// ranges, so the parallel recursion writes disjoint slices and no node is boxed). Slots
/// of ranges that end as one leaf stay unused.
pub(crate) struct BTree {
    pub nodes: Vec<BNode>,
    pub root: u32,
}

impl BTree {
    #[inline(always)]
    pub fn node(&self, i: u32) -> &BNode {
        &self.nodes[i as usize]
    }

    /// The two nodes of an inner node's `children`.
    #[inline(always)]
    pub fn children(&self, [a, b]: [u32; 2]) -> [&BNode; 2] {
        [self.node(a), self.node(b)]
    }
}

const UNUSED: BNode = BNode::Leaf {
    bounds: Aabb::EMPTY,
    start: 0,
    count: 0,
};

/// Builds the binary tree over `refs` (not empty), reordering them so that every leaf is a
/// contiguous range.
pub(crate) fn build_binary(refs: &mut [PrimRef], opts: &BuildOptions) -> BTree {
    let mut nodes = vec![UNUSED; 2 * refs.len() - 1];
    let root = build_rec(refs, 0, &mut nodes, 0, opts, &mut new_bins());
    BTree { nodes, root }
}

/// Builds the subtree over `refs` (the references from `offset` on) into `arena`, the
/// `2 refs.len() - 1` slots from `2 offset` on ([`BTree`]); returns its root's slot.
/// `scratch` holds the bins of the serial binning pass; one per thread of the recursion, so
/// that a node neither zeroes nor copies all `3 * MAX_BINS` bins (only its own `nb` are reset).
fn build_rec(
    refs: &mut [PrimRef],
    offset: u32,
    arena: &mut [BNode],
    depth: u32,
    opts: &BuildOptions,
    scratch: &mut Bins,
) -> u32 {
    let n = refs.len();
    debug_assert_eq!(arena.len(), 2 * n - 1);
    let (bounds, cbounds) = node_bounds(refs);
    let mut leaf = || {
        arena[0] = BNode::Leaf {
            bounds,
            start: offset,
            count: n as u32,
        };
        2 * offset
    };
    if n <= 1 {
        return leaf();
    }
    let mid = if depth >= MAX_SAH_DEPTH || cbounds.extent().max_element() <= 0.0 {
        if n <= opts.max_leaf_size {
            return leaf();
        }
        median_split(refs, &cbounds)
    } else {
        match sah_split(refs, &bounds, &cbounds, opts, scratch) {
            Some(mid) => mid,
            None => return leaf(),
        }
    };
    let (l, r) = refs.split_at_mut(mid);
    let off_r = offset + mid as u32;
    let (arena_l, rest) = arena.split_at_mut(2 * mid - 1);
    let (slot, arena_r) = rest.split_first_mut().expect("2 n - 1 slots");
    let (a, b) = if n > opts.parallel_threshold {
        rayon::join(
            || build_rec(l, offset, arena_l, depth + 1, opts, scratch),
            || build_rec(r, off_r, arena_r, depth + 1, opts, &mut new_bins()),
        )
    } else {
        (
            build_rec(l, offset, arena_l, depth + 1, opts, scratch),
            build_rec(r, off_r, arena_r, depth + 1, opts, scratch),
        )
    };
    *slot = BNode::Inner {
        bounds,
        children: [a, b],
    };
    2 * off_r - 1
}

/// Bounds of the references and of their (doubled) centroids.
fn node_bounds(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let (b, c) = node_bounds_a(refs);
    (b.aabb(), c.aabb())
}

/// A box in 4-lane vectors (lane `w` ignored). Its `min` / `max` are glam's `a < b ? a : b`
/// and `a > b ? a : b` per lane, as `Vec3`'s, so the boxes equal those of `Aabb` bit for bit.
#[derive(Clone, Copy)]
struct BoxA {
    min: Vec3A,
    max: Vec3A,
}

impl BoxA {
    const EMPTY: BoxA = BoxA {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, o: BoxA) -> BoxA {
        BoxA {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn grow(self, p: Vec3A) -> BoxA {
        BoxA {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline(always)]
    fn aabb(self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

fn node_bounds_a(refs: &[PrimRef]) -> (BoxA, BoxA) {
    let fold = |(b, c): (BoxA, BoxA), r: &PrimRef| {
        let p = r.centroid2();
        (
            BoxA {
                min: b.min.min(r.min()),
                max: b.max.max(r.max()),
            },
            BoxA {
                min: c.min.min(p),
                max: c.max.max(p),
            },
        )
    };
    let union = |(b0, c0): (BoxA, BoxA), (b1, c1): (BoxA, BoxA)| (b0.union(b1), c0.union(c1));
    let empty = (BoxA::EMPTY, BoxA::EMPTY);
    if refs.len() > PAR_BIN_THRESHOLD {
        refs.par_chunks(8192)
            .map(|c| c.iter().fold(empty, fold))
            .reduce(|| empty, union)
    } else {
        refs.iter().fold(empty, fold)
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: BoxA,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    bounds: BoxA::EMPTY,
    count: 0,
};

/// Bins of the three axes.
#[derive(Clone, Copy)]
struct Bins([[Bin; MAX_BINS]; 3]);

fn new_bins() -> Bins {
    Bins([[EMPTY_BIN; MAX_BINS]; 3])
}

/// Maps doubled centroids to bin indices: `bin = floor((c - min) * scale)`, clamped.
#[derive(Clone, Copy)]
struct Binner {
    /// `w` = 0, so that the centroid's `w` lane stays a normal float (or 0) in `bin`.
    min: Vec3A,
    scale: Vec3A,
    /// `bins - 1` in every lane.
    last: Vec3A,
    bins: usize,
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
    fn bin_axis(&self, c: Vec3A, axis: usize) -> usize {
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
fn trunc3(g: Vec3A) -> [i32; 4] {
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

/// The SAH's intersection count of `cnt` triangles in leaves tested `block` triangles at a
/// time: `ceil(cnt / block)` (`block = 1`: the triangle count).
#[inline(always)]
pub(crate) fn sah_count(cnt: u32, block: usize) -> f32 {
    cnt.div_ceil(block as u32) as f32
}

/// The best binned object split of a node: its unnormalised SAH cost (`A(left) N(left) +
/// A(right) N(right)`, infinite when no bin boundary separates the centroids), its axis, the
/// first bin of its right side and the binner. The bins stay in the caller's scratch.
struct ObjectSplit {
    cost: f32,
    axis: usize,
    split: usize,
    binner: Binner,
}

/// Bins `refs` by centroid into `scratch` and sweeps the bin boundaries (module docs).
fn find_object_split(
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

/// Partitions `refs` by the object split `o` (whose cost is finite); returns the size of the
/// left side, falling back to the object median when one side would be empty.
fn object_partition(refs: &mut [PrimRef], o: &ObjectSplit, cbounds: &Aabb) -> usize {
    let n = refs.len();
    let (binner, axis, split) = (&o.binner, o.axis, o.split);
    let mid = partition(refs, |r| binner.bin_axis(r.centroid2(), axis) < split);
    if mid == 0 || mid == n {
        return median_split(refs, cbounds);
    }
    mid
}

/// Finds the best binned SAH split and partitions `refs`; returns the split position, or `None`
/// when a leaf is cheaper (and allowed by the leaf size).
fn sah_split(
    refs: &mut [PrimRef],
    bounds: &Aabb,
    cbounds: &Aabb,
    opts: &BuildOptions,
    scratch: &mut Bins,
) -> Option<usize> {
    let n = refs.len();
    let o = find_object_split(refs, cbounds, opts, scratch);
    let area = bounds.surface_area();
    let split_cost = opts.traversal_cost * area + opts.intersection_cost * o.cost;
    let leaf_cost = opts.intersection_cost * area * sah_count(n as u32, opts.sah_block_size);
    if n <= opts.max_leaf_size && leaf_cost <= split_cost {
        return None;
    }
    if !o.cost.is_finite() {
        // No split separates the centroids (cannot happen with a non-zero centroid extent, but
        // keep the build total): fall back to the median.
        return Some(median_split(refs, cbounds));
    }
    Some(object_partition(refs, &o, cbounds))
}

/// In-place partition: elements satisfying `left` first; returns their count.
fn partition(refs: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool) -> usize {
    let (mut i, mut j) = (0usize, refs.len());
    loop {
        while i < j && left(&refs[i]) {
            i += 1;
        }
        while i < j && !left(&refs[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        refs.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Object-median split along the largest centroid axis (ties broken by triangle id so that the
/// result is deterministic).
fn median_split(refs: &mut [PrimRef], cbounds: &Aabb) -> usize {
    let axis = cbounds.largest_axis();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| {
        a.centroid2()[axis]
            .total_cmp(&b.centroid2()[axis])
            .then(a.id().cmp(&b.id()))
    });
    mid
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refs_of(points: &[Vec3]) -> Vec<PrimRef> {
        points
            .iter()
            .enumerate()
            .map(|(i, &p)| PrimRef::new(p, p + Vec3::splat(0.01), i as u32))
            .collect()
    }

    fn check(
        tree: &BTree,
        node: u32,
        refs: &[PrimRef],
        max_leaf: usize,
        depth: u32,
    ) -> (usize, u32) {
        match tree.node(node) {
            BNode::Leaf {
                bounds,
                start,
                count,
            } => {
                assert!(*count as usize <= max_leaf.max(1));
                for r in &refs[*start as usize..(*start + *count) as usize] {
                    assert!(bounds.contains(r.min().into()) && bounds.contains(r.max().into()));
                }
                (*count as usize, depth)
            }
            BNode::Inner { bounds, children } => {
                let [c0, c1] = *children;
                let u = tree.node(c0).bounds().union(tree.node(c1).bounds());
                assert_eq!(u, *bounds);
                let (a, da) = check(tree, c0, refs, max_leaf, depth + 1);
                let (b, db) = check(tree, c1, refs, max_leaf, depth + 1);
                (a + b, da.max(db))
            }
        }
    }

    #[test]
    fn every_reference_lands_in_exactly_one_leaf_with_bounded_size() {
        let mut s = 7u32;
        let mut rnd = || {
            s = s.wrapping_mul(747796405).wrapping_add(2891336453);
            (s >> 8) as f32 / (1 << 24) as f32
        };
        let pts: Vec<Vec3> = (0..5000).map(|_| Vec3::new(rnd(), rnd(), rnd())).collect();
        let mut refs = refs_of(&pts);
        let opts = BuildOptions::default();
        let root = build_binary(&mut refs, &opts);
        let (count, _) = check(&root, root.root, &refs, opts.max_leaf_size, 0);
        assert_eq!(count, 5000);
        let mut ids: Vec<u32> = refs.iter().map(|r| r.id()).collect();
        ids.sort_unstable();
        assert!(ids.iter().enumerate().all(|(i, &id)| id == i as u32));
    }

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

    #[test]
    fn reference_ids_round_trip() {
        for id in [0u32, 1, 12345, (1 << 23) - 1, 1 << 23, (1 << 27) - 1] {
            let r = PrimRef::new(Vec3::ZERO, Vec3::ONE, id);
            assert_eq!(r.id(), id);
            assert!(r.centroid2().to_array().iter().all(|x| x.is_normal()));
        }
    }

    #[test]
    fn coincident_centroids_split_at_the_median_with_log_depth() {
        let pts = vec![Vec3::ONE; 1000];
        let mut refs = refs_of(&pts);
        let opts = BuildOptions::default();
        let root = build_binary(&mut refs, &opts);
        let (count, depth) = check(&root, root.root, &refs, opts.max_leaf_size, 0);
        assert_eq!(count, 1000);
        assert!(depth <= 10, "depth {depth}");
    }
}
