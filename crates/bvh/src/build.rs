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

use parallax_core::Aabb;
use rayon::prelude::*;

use crate::options::BuildOptions;
use parallax_core::huge_pages::HugeBuf;

mod object_bins;
mod prim_ref;
mod spatial;
use object_bins::{Bins, ObjectSplit, PAR_BIN_THRESHOLD, find_object_split, new_bins, sah_count};
use prim_ref::BoxA;
pub(crate) use prim_ref::PrimRef;
pub(crate) use spatial::{build_binary_spatial, reference_capacity};

/// Below this depth the binned SAH decides; deeper nodes split at the object median.
pub(crate) const MAX_SAH_DEPTH: u32 = 48;

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
    pub nodes: HugeBuf<BNode>,
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

/// An arena of `len` unused slots, on huge pages where the system allows (`parallax_core::huge_pages`).
fn new_arena(len: usize) -> HugeBuf<BNode> {
    HugeBuf::new(len, UNUSED)
}

/// Builds the binary tree over `refs` (not empty), reordering them so that every leaf is a
/// contiguous range.
pub(crate) fn build_binary(refs: &mut [PrimRef], opts: &BuildOptions) -> BTree {
    let mut nodes = new_arena(2 * refs.len() - 1);
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

/// Partitions `refs` by the object split `o` (whose cost is finite); returns the size of the
/// left side, falling back to the object median when one side would be empty.
fn object_partition(refs: &mut [PrimRef], o: &ObjectSplit, cbounds: &Aabb) -> usize {
    let n = refs.len();
    let (binner, axis, split) = (&o.binner, o.axis, o.split);
    let mid = partition(refs, binner.left_of(axis, split));
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
    use glam::Vec3;

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
