//! The 4-wide node layout and the child-reference encoding.
//!
//! ## Layout (128 bytes, two cache lines, 64-byte aligned)
//!
//! | bytes | field | meaning |
//! |---|---|---|
//! | 0..96 | `bounds: [Vec4; 6]` | `min_x, max_x, min_y, max_y, min_z, max_z`, one lane per child (SoA) |
//! | 96..112 | `child: [u32; 4]` | child references, see [`ChildRef`] encoding below |
//! | 112..116 | `num_children` | number of used lanes (1..=4); used lanes come first |
//! | 116..128 | `reserved` | zero; free for the beam traversal (HVVR §5.3-5.4) |
//!
//! Structure of arrays over the four children lets one SIMD slab test (SSE `Vec4`, or half an
//! AVX register for the later beam traversal) test all children at once. Storing the bounds as
//! `[min, max]` pairs per axis lets a ray pick its near and far plane per axis by an index
//! (`2 * axis + sign`) instead of a per-lane min/max: see `traverse.rs`.
//!
//! Unused lanes hold the empty box (`min = +inf`, `max = -inf`): with the ordered slab test its
//! entry distance is `+inf` and its exit distance `-inf`, so it is never hit, and it is the
//! identity of the box union, so a node's bounds are the union of its four lanes.
//!
//! ## Child references (`u32`)
//!
//! - bit 31 clear: inner node, bits 0..31 = index into the node array;
//! - bit 31 set: leaf, bits 27..31 = triangle count (0..=15), bits 0..27 = the leaf's first
//!   block of four triangles in the BVH's block array (`tri4.rs`; a leaf of `count` triangles
//!   owns `ceil(count / 4)` blocks; [`crate::Bvh::leaf_triangles`] gives its range in
//!   [`crate::Bvh::triangles`]). [`EMPTY`] = a leaf of zero triangles, so an unused lane is
//!   harmless even if it were visited.
//!
//! ## Order (HVVR §5, "Our implementation lays the BVH out in memory in depth-first preorder")
//!
//! Nodes are stored in depth-first preorder (node 0 is the root; a child always has a larger
//! index than its parent, so a reverse sweep refits bottom-up without recursion), triangles in
//! the order a depth-first traversal touches them, and a node's leaf children come before its
//! inner children.

use glam::Vec4;
use parallax_core::Aabb;

/// Leaf flag of a child reference.
pub const LEAF_FLAG: u32 = 1 << 31;
/// Bits below the count field: the first triangle of a leaf.
pub const LEAF_FIRST_BITS: u32 = 27;
/// Largest leaf (the count field has 4 bits).
pub const MAX_LEAF_SIZE: usize = 15;
/// Most triangles a BVH can index (27 bits of leaf start).
pub const MAX_TRIANGLES: usize = 1 << LEAF_FIRST_BITS;
/// An unused child lane: a leaf of zero triangles.
pub const EMPTY: u32 = LEAF_FLAG;

/// Decoded child reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChildRef {
    /// Index of an inner node.
    Inner(u32),
    /// A leaf: `count` triangles in blocks `first..` of the block array
    /// ([`crate::Bvh::leaf_triangles`] maps it to the triangle array).
    Leaf { first: u32, count: u32 },
}

impl ChildRef {
    /// Encodes (see the module docs). Panics on out-of-range fields (a build invariant).
    #[inline]
    pub fn encode(self) -> u32 {
        match self {
            ChildRef::Inner(i) => {
                assert!(i < LEAF_FLAG, "node index overflow");
                i
            }
            ChildRef::Leaf { first, count } => {
                assert!((count as usize) <= MAX_LEAF_SIZE && (first as usize) < MAX_TRIANGLES);
                LEAF_FLAG | (count << LEAF_FIRST_BITS) | first
            }
        }
    }

    #[inline(always)]
    pub fn decode(r: u32) -> ChildRef {
        if is_leaf(r) {
            ChildRef::Leaf {
                first: leaf_first(r),
                count: leaf_count(r),
            }
        } else {
            ChildRef::Inner(r)
        }
    }
}

#[inline(always)]
pub fn is_leaf(r: u32) -> bool {
    r & LEAF_FLAG != 0
}

#[inline(always)]
pub fn leaf_first(r: u32) -> u32 {
    r & ((1 << LEAF_FIRST_BITS) - 1)
}

#[inline(always)]
pub fn leaf_count(r: u32) -> u32 {
    (r >> LEAF_FIRST_BITS) & 0xF
}

/// A 4-wide BVH node (layout in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node4 {
    /// `[min_x, max_x, min_y, max_y, min_z, max_z]`, lane `i` = child `i`.
    pub bounds: [Vec4; 6],
    pub child: [u32; 4],
    pub num_children: u32,
    pub reserved: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<Node4>() == 128);
const _: () = assert!(std::mem::align_of::<Node4>() == 64);

impl Node4 {
    /// A node with four unused lanes.
    pub const EMPTY: Node4 = Node4 {
        bounds: [
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
            Vec4::INFINITY,
            Vec4::NEG_INFINITY,
        ],
        child: [EMPTY; 4],
        num_children: 0,
        reserved: [0; 3],
    };

    /// Bounds of lane `i`.
    #[inline]
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: glam::Vec3::new(b[0][i], b[2][i], b[4][i]),
            max: glam::Vec3::new(b[1][i], b[3][i], b[5][i]),
        }
    }

    /// Sets the bounds of lane `i`.
    #[inline]
    pub fn set_child_bounds(&mut self, i: usize, a: Aabb) {
        self.bounds[0][i] = a.min.x;
        self.bounds[1][i] = a.max.x;
        self.bounds[2][i] = a.min.y;
        self.bounds[3][i] = a.max.y;
        self.bounds[4][i] = a.min.z;
        self.bounds[5][i] = a.max.z;
    }

    /// The union of the four lanes (unused lanes are empty boxes, the identity).
    #[inline]
    pub fn bounds(&self) -> Aabb {
        let b = &self.bounds;
        Aabb {
            min: glam::Vec3::new(b[0].min_element(), b[2].min_element(), b[4].min_element()),
            max: glam::Vec3::new(b[1].max_element(), b[3].max_element(), b[5].max_element()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn child_refs_round_trip() {
        for r in [
            ChildRef::Inner(0),
            ChildRef::Inner(123_456),
            ChildRef::Leaf { first: 0, count: 1 },
            ChildRef::Leaf {
                first: (MAX_TRIANGLES - 1) as u32,
                count: MAX_LEAF_SIZE as u32,
            },
        ] {
            assert_eq!(ChildRef::decode(r.encode()), r);
        }
        assert_eq!(
            ChildRef::decode(EMPTY),
            ChildRef::Leaf { first: 0, count: 0 }
        );
    }

    #[test]
    fn empty_lanes_are_union_identity() {
        let mut n = Node4::EMPTY;
        assert!(n.bounds().is_empty());
        let a = Aabb::new(
            glam::Vec3::new(-1.0, 0.0, 2.0),
            glam::Vec3::new(1.0, 3.0, 4.0),
        );
        n.set_child_bounds(2, a);
        assert_eq!(n.child_bounds(2), a);
        assert_eq!(n.bounds(), a);
    }
}
