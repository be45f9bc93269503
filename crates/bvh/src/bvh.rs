//! The BVH itself: the 4-wide and 8-wide trees over the same leaves, the triangle copies and
//! their map to the scene's indices, and read access to them (layouts in `node.rs`, `node8.rs`,
//! `tri4.rs`; the build in `construct.rs`).

use std::sync::OnceLock;
use std::time::Duration;

use parallax_core::Aabb;

use crate::node::Node4;
use crate::node8::Node8;
use crate::tri::Tri;
use crate::tri4::{self, Tri4};

/// A bounding volume hierarchy over a [`TriangleMesh`](parallax_scene::TriangleMesh): a 4-wide and an 8-wide tree over the
/// same leaves (see the crate docs).
#[derive(Clone, Debug)]
pub struct Bvh {
    pub(crate) nodes: Vec<Node4>,
    /// The 8-wide traversal tree over the same leaves (`node8.rs`).
    pub(crate) nodes8: Vec<Node8>,
    pub(crate) tris: Vec<Tri>,
    pub(crate) prim_ids: Vec<u32>,
    pub(crate) blocks: Vec<tri4::Tri4>,
    /// The index in `tris` of each block's lane 0 (blocks hold primitive ids, `tri4.rs`).
    pub(crate) block_tris: Vec<u32>,
    pub(crate) bounds: Aabb,
    pub(crate) depth: u32,
    /// Triangles of the mesh (the triangle copies can be more: spatial splits duplicate).
    pub(crate) prim_count: usize,
    pub(crate) build_time: Duration,
    /// [`Bvh::block_copies`], made on first use.
    pub(crate) block_copies: OnceLock<Vec<u8>>,
}

impl Bvh {
    /// Number of 4-wide nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The 8-wide traversal tree, root first, in depth-first preorder (layout in [`crate::node8`]).
    pub fn nodes8(&self) -> &[Node8] {
        &self.nodes8
    }

    /// Number of triangles indexed (the mesh's triangles).
    pub fn triangle_count(&self) -> usize {
        self.prim_count
    }

    /// Number of triangle copies in the leaves ([`Bvh::triangles`]): the triangle count, plus
    /// the duplicates of a build with spatial splits.
    pub fn reference_count(&self) -> usize {
        self.tris.len()
    }

    /// Memory held by nodes, triangle copies (plain and in blocks of four) and the primitive
    /// map, in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node4>()
            + self.nodes8.len() * size_of::<Node8>()
            + self.tris.len() * size_of::<Tri>()
            + self.blocks.len() * size_of::<Tri4>()
            + self.block_tris.len() * size_of::<u32>()
            + self.prim_ids.len() * size_of::<u32>()
    }

    /// Bounds of all triangles (empty for an empty mesh).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Depth in 4-wide nodes (root = 1; 0 when empty).
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Wall time of the build (including the collapse and the triangle gather).
    pub fn build_time(&self) -> Duration {
        self.build_time
    }

    /// The nodes, root first, in depth-first preorder (layout in [`crate::node`]).
    pub fn nodes(&self) -> &[Node4] {
        &self.nodes
    }

    /// The triangle copies in leaf order; leaf `(first, count)` refers to
    /// `triangles()[leaf_triangles(first, count)]`.
    pub fn triangles(&self) -> &[Tri] {
        &self.tris
    }

    /// The leaves' triangles in blocks of four, leaf order (layout in `tri4.rs`).
    pub fn blocks(&self) -> &[Tri4] {
        &self.blocks
    }

    /// The range in [`Bvh::triangles`] of the leaf `ChildRef::Leaf { first, count }` (`first`
    /// is its first block). Panics on a reference that is not a leaf of this BVH.
    pub fn leaf_triangles(&self, first: u32, count: u32) -> std::ops::Range<usize> {
        if count == 0 {
            return 0..0;
        }
        let start = self.block_tris[first as usize] as usize;
        start..start + count as usize
    }

    /// The scene's triangle index of each entry of [`Bvh::triangles`].
    pub fn prim_ids(&self) -> &[u32] {
        &self.prim_ids
    }

    /// Per block of [`Bvh::blocks`], the lanes (bits 0-3) whose triangle sits in more than one
    /// leaf (spatial splits put a triangle in every leaf that holds a piece of it); empty when
    /// no triangle does (every object-split tree). A tile list that gathers leaves can meet such
    /// a triangle twice, any other once. Made on the first call, outside the build's time
    /// (one pass over the blocks, ~0.1 ms per 100 k triangles), then kept: refit keeps the
    /// leaves, so the masks stay valid.
    pub fn block_copies(&self) -> &[u8] {
        self.block_copies.get_or_init(|| {
            if self.tris.len() == self.prim_count {
                return Vec::new();
            }
            let mut count = vec![0u8; self.prim_count];
            for id in self.blocks.iter().flat_map(|b| b.tri) {
                if id != u32::MAX {
                    count[id as usize] = count[id as usize].saturating_add(1);
                }
            }
            let copies = |id: u32| id != u32::MAX && count[id as usize] > 1;
            self.blocks
                .iter()
                .map(|b| (0..4).fold(0u8, |m, l| m | (copies(b.tri[l]) as u8) << l))
                .collect()
        })
    }
}
