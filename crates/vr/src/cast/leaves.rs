//! A tile's leaf list packed for the sample tests (Hunt et al. 2018, §5.5): the tile cull's
//! leaves ([`LeafRef`], near-depth order) with the boxes of their triangles, as single boxes
//! ([`LeafBox`], for the packet kernels) and in SoA groups of four ([`LeafGroup`], for the
//! one-ray kernel's 4-wide slab test).
//!
//! **Invariant:** the order of the list is kept (groups are consecutive runs of four), so the
//! kernels' front-to-back early exit stays valid.

use glam::Vec4;
use parallax_bvh::Bvh;
use parallax_bvh::Node4;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::Aabb;

use crate::beam::LeafRef;

/// Four leaves of a tile's list with their boxes in SoA lanes (`[min_x, max_x, min_y, max_y,
/// min_z, max_z]`, as `Node4`), so a ray tests four leaf boxes with one slab test before it
/// tests their triangles. Padding lanes hold the empty box (never hit) and leaf `EMPTY`.
#[derive(Clone, Copy, Debug)]
pub struct LeafGroup {
    pub bounds: [Vec4; 6],
    pub leaf: [u32; 4],
    /// Smallest near depth of the four leaves (the first one's: lists are sorted).
    pub near: f32,
}

/// A leaf of a tile's list with the box of its triangles.
#[derive(Clone, Copy, Debug)]
pub struct LeafBox {
    pub bounds: Aabb,
    pub leaf: u32,
    pub near: f32,
}

/// Packs a near-sorted leaf list into groups of four (`out`) and into boxed leaves (`boxes`).
pub fn group_leaves(
    bvh: &Bvh,
    leaves: &[LeafRef],
    out: &mut Vec<LeafGroup>,
    boxes: &mut Vec<LeafBox>,
) {
    out.clear();
    boxes.clear();
    let tris = bvh.triangles();
    for chunk in leaves.chunks(4) {
        let mut g = LeafGroup {
            bounds: Node4::EMPTY.bounds,
            leaf: [parallax_bvh::node::EMPTY; 4],
            near: chunk[0].near,
        };
        for (l, r) in chunk.iter().enumerate() {
            let mut b = Aabb::EMPTY;
            for t in bvh.leaf_triangles(leaf_first(r.leaf), leaf_count(r.leaf)) {
                b = b.union(tris[t].bounds());
            }
            g.bounds[0][l] = b.min.x;
            g.bounds[1][l] = b.max.x;
            g.bounds[2][l] = b.min.y;
            g.bounds[3][l] = b.max.y;
            g.bounds[4][l] = b.min.z;
            g.bounds[5][l] = b.max.z;
            g.leaf[l] = r.leaf;
            g.near = g.near.min(r.near);
            boxes.push(LeafBox {
                bounds: b,
                leaf: r.leaf,
                near: r.near,
            });
        }
        out.push(g);
    }
}
