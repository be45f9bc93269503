//! Collapsing the binary build tree into the 8-wide layout of [`crate::node8`], the same way as
//! the 4-wide collapse (`collapse.rs`: open the inner child of largest surface area until the
//! node has eight children; Wald, Benthin & Boulos 2008), in depth-first preorder, leaf
//! children first. Leaves are the binary tree's leaves, so they reuse the blocks of triangles
//! the 4-wide collapse laid out (`Collapsed::leaf_blocks` maps a leaf to its first block), and
//! both trees answer every query from the same triangle array. The collapse reads only the
//! binary tree, so it runs next to the 4-wide one: its leaf lanes first hold the leaf's first
//! reference, and [`Collapsed8::point_leaves_at_blocks`] then swaps in the first block.

use crate::build::{BNode, BTree};
use crate::collapse::open_largest;
use crate::node::ChildRef;
use crate::node8::Node8;
use parallax_core::huge_pages::huge_vec;
use rayon::prelude::*;

/// The 8-wide tree: nodes (root first) and the depth of the deepest node (root = 1).
pub(crate) struct Collapsed8 {
    pub nodes: Vec<Node8>,
    pub depth: u32,
}

impl Collapsed8 {
    /// Rewrites every leaf lane's first reference `start` into the leaf's first block,
    /// `leaf_blocks[start]` (`Collapsed::leaf_blocks`).
    pub fn point_leaves_at_blocks(&mut self, leaf_blocks: &[u32]) {
        self.nodes.par_iter_mut().with_min_len(512).for_each(|n| {
            for c in &mut n.child[..n.num_children as usize] {
                if let ChildRef::Leaf { first, count } = ChildRef::decode(*c) {
                    let first = leaf_blocks[first as usize];
                    debug_assert_ne!(first, u32::MAX, "leaf without blocks");
                    *c = ChildRef::Leaf { first, count }.encode();
                }
            }
        });
    }
}

/// Collapses `tree` into 8-wide nodes whose leaf lanes hold the leaf's first reference in
/// place of its first block (module docs).
pub(crate) fn collapse8(tree: &BTree, node_hint: usize) -> Collapsed8 {
    let mut out = Collapsed8 {
        nodes: huge_vec(node_hint),
        depth: 0,
    };
    let root = tree.node(tree.root);
    match root {
        BNode::Leaf { .. } => emit(&mut out, tree, &[root], 1),
        BNode::Inner { children, .. } => emit(&mut out, tree, &tree.children(*children), 1),
    };
    out
}

fn emit(out: &mut Collapsed8, tree: &BTree, start: &[&BNode], depth: u32) -> u32 {
    let index = out.nodes.len();
    out.nodes.push(Node8::EMPTY);
    out.depth = out.depth.max(depth);
    let (kids, len) = open_largest::<8>(tree, start);
    let mut node = Node8::EMPTY;
    let mut lane = 0;
    for k in kids[..len].iter().flatten() {
        if let BNode::Leaf {
            bounds,
            start,
            count,
        } = k
        {
            node.child[lane] = ChildRef::Leaf {
                first: *start,
                count: *count,
            }
            .encode();
            node.set_child_bounds(lane, *bounds);
            lane += 1;
        }
    }
    node.leaf_mask = (1u32 << lane) - 1;
    out.nodes[index] = node;
    for k in kids[..len].iter().flatten() {
        if let BNode::Inner { children, bounds } = k {
            let child = emit(out, tree, &tree.children(*children), depth + 1);
            let n = &mut out.nodes[index];
            n.child[lane] = ChildRef::Inner(child).encode();
            n.set_child_bounds(lane, *bounds);
            lane += 1;
        }
    }
    out.nodes[index].num_children = lane as u32;
    index as u32
}
