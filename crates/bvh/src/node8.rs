//! The 8-wide node layout of the traversal tree (the 4-wide [`crate::Node4`] tree stays for
//! HVVR's beam culling and refit-friendly preorder; both index the same leaf blocks).
//!
//! ## Layout (256 bytes, four cache lines, 64-byte aligned)
//!
//! | bytes | field | meaning |
//! |---|---|---|
//! | 0..192 | `bounds: [[f32; 8]; 6]` | `min_x, max_x, min_y, max_y, min_z, max_z`, one lane per child (SoA) |
//! | 192..224 | `child: [u32; 8]` | child references, encoded as [`crate::ChildRef`] (leaves point into the shared block array) |
//! | 224..228 | `num_children` | used lanes (1..=8); used lanes come first |
//! | 228..232 | `leaf_mask` | bit `i` set iff lane `i` is a leaf child (leaf lanes come first) |
//! | 232..256 | padding | zero |
//!
//! One row of eight lanes is one AVX register (Embree's `BVH8` node, Wald et al. 2014 §3.1,
//! uncompressed), so a ray tests all eight children with six 8-lane loads; the `[min, max]`
//! pairs per axis let a ray pick its near and far plane by a byte offset (`32 * (2 axis +
//! sign)`), as in the 4-wide layout. Unused lanes hold the empty box (`min = +inf, max =
//! -inf`): never hit, and the identity of the box union. Nodes are in depth-first preorder
//! (children after their parent; leaf children first), so a reverse sweep refits bottom-up.

use parallax_core::Aabb;

use crate::node::EMPTY;

/// Lanes of a [`Node8`].
pub const WIDTH8: usize = 8;

/// An 8-wide BVH node (layout in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node8 {
    /// `[min_x, max_x, min_y, max_y, min_z, max_z]`, lane `i` = child `i`.
    pub bounds: [[f32; 8]; 6],
    pub child: [u32; 8],
    pub num_children: u32,
    /// Bit `i` set iff lane `i` holds a leaf child: the traversal prefetches the triangle
    /// blocks of the hit leaf lanes without testing each hit lane's reference.
    pub leaf_mask: u32,
    pub reserved: [u32; 6],
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);
const _: () = assert!(std::mem::offset_of!(Node8, child) == 192);

impl Node8 {
    /// A node with eight unused lanes.
    pub const EMPTY: Node8 = Node8 {
        bounds: [
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
            [f32::INFINITY; 8],
            [f32::NEG_INFINITY; 8],
        ],
        child: [EMPTY; 8],
        num_children: 0,
        leaf_mask: 0,
        reserved: [0; 6],
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

    /// The union of the eight lanes (unused lanes are empty boxes, the identity).
    #[inline]
    pub fn bounds(&self) -> Aabb {
        (0..WIDTH8).fold(Aabb::EMPTY, |a, i| a.union(self.child_bounds(i)))
    }
}
