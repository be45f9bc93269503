//! Collapsing the binary build tree into the 4-wide layout of [`crate::node`].
//!
//! Wald, Benthin & Boulos 2008 ("Getting Rid of Packets") and Ernst & Greiner 2008 ("Multi
//! Bounding Volume Hierarchies"): a wide node starts with the two children of a binary node and
//! repeatedly replaces the inner child of largest surface area by its two children, until it has
//! four children or only leaves are left. Opening the largest child first removes the boxes that
//! rays most likely enter, i.e. the SAH-cheapest collapse.
//!
//! Nodes are emitted in depth-first preorder, leaf children first, and triangles in the order
//! that preorder walk reaches them (HVVR §5, see `node.rs`).

use glam::Vec3;
use rayon::prelude::*;

use crate::build::{BNode, BTree, PrimRef};
use crate::node::{ChildRef, Node4};
use crate::tri::Tri;
use crate::tri4::{Tri4, blocks_for};
use parallax_core::huge_pages::huge_vec;

/// The children of a `W`-wide node whose binary children are `start`: repeatedly replaces the
/// inner child of largest surface area by its two children, until there are `W` children or
/// only leaves (module docs). Returns the children (the first `len` are set) and `len`.
pub(crate) fn open_largest<'a, const W: usize>(
    tree: &'a BTree,
    start: &[&'a BNode],
) -> ([Option<&'a BNode>; W], usize) {
    let mut kids: [Option<&BNode>; W] = [None; W];
    // The surface area of each inner child (computed once per child), `None` for leaves.
    let mut area = [None; W];
    let inner_area = |k: &BNode| match k {
        BNode::Inner { bounds, .. } => Some(bounds.surface_area()),
        BNode::Leaf { .. } => None,
    };
    for ((k, a), s) in kids.iter_mut().zip(&mut area).zip(start) {
        *k = Some(s);
        *a = inner_area(s);
    }
    let mut len = start.len();
    while len < W {
        // The last inner child of largest area (as `Iterator::max_by` picks among equals).
        let mut pick: Option<(usize, f32)> = None;
        for (i, a) in area[..len].iter().enumerate() {
            if let Some(a) = *a
                && pick.is_none_or(|(_, b)| a.total_cmp(&b).is_ge())
            {
                pick = Some((i, a));
            }
        }
        let Some((i, _)) = pick else { break };
        let Some(BNode::Inner { children, .. }) = kids[i] else {
            unreachable!()
        };
        let [c0, c1] = tree.children(*children);
        kids[i] = Some(c0);
        area[i] = inner_area(c0);
        kids[len] = Some(c1);
        area[len] = inner_area(c1);
        len += 1;
    }
    (kids, len)
}

pub(crate) struct Collapsed {
    pub nodes: Vec<Node4>,
    pub tris: Vec<Tri>,
    pub prim_ids: Vec<u32>,
    /// The leaves' triangles in blocks of four (`tri4.rs`); leaf references index these.
    pub blocks: Vec<Tri4>,
    /// The index in `tris` of each block's lane 0.
    pub block_tris: Vec<u32>,
    /// Depth of the deepest wide node (root = 1).
    pub depth: u32,
    /// The first block of each binary leaf, indexed by the leaf's first reference (`start`):
    /// the 8-wide collapse (`collapse8.rs`) points its leaves at the same blocks.
    pub leaf_blocks: Vec<u32>,
}

/// Collapses `tree` (built over `refs`) into 4-wide nodes (room for `node_hint` reserved);
/// `corners(id)` gives a triangle's vertices. A serial pass lays out the nodes and numbers the leaves' triangles and blocks in
/// the order the preorder walk reaches them; the triangles and blocks are then gathered in
/// parallel (each triangle and block is a function of its number alone, so the result does
/// not depend on the threads).
pub(crate) fn collapse(
    tree: &BTree,
    refs: &[PrimRef],
    node_hint: usize,
    corners: impl Fn(u32) -> [Vec3; 3] + Sync,
) -> Collapsed {
    let mut leaf_blocks = huge_vec(refs.len());
    leaf_blocks.resize(refs.len(), u32::MAX);
    let mut ctx = Ctx {
        tree,
        nodes: huge_vec(node_hint),
        depth: 0,
        leaf_blocks,
        order: huge_vec(refs.len()),
        block_starts: huge_vec(refs.len() / 2),
    };
    let root = tree.node(tree.root);
    match root {
        // A tiny mesh: a root node with a single leaf lane.
        BNode::Leaf { .. } => ctx.emit(&[root], 1),
        BNode::Inner { children, .. } => ctx.emit(&tree.children(*children), 1),
    };
    let Ctx {
        nodes,
        depth,
        leaf_blocks,
        order,
        block_starts,
        ..
    } = ctx;
    let mut tris: Vec<Tri> = huge_vec(order.len());
    tris.par_extend(
        order
            .par_iter()
            .with_min_len(1024)
            .map(|&k| Tri::new(corners(refs[k as usize].id()))),
    );
    let mut prim_ids: Vec<u32> = huge_vec(order.len());
    prim_ids.par_extend(
        order
            .par_iter()
            .with_min_len(4096)
            .map(|&k| refs[k as usize].id()),
    );
    let mut blocks: Vec<Tri4> = huge_vec(block_starts.len());
    blocks.par_extend(
        block_starts
            .par_iter()
            .with_min_len(256)
            .map(|&(first, count)| {
                let mut b = Tri4::EMPTY;
                for l in 0..count as usize {
                    let index = (first + l as u32) as usize;
                    b.set(l, &tris[index], prim_ids[index]);
                }
                b
            }),
    );
    let block_tris = block_starts.iter().map(|&(first, _)| first).collect();
    Collapsed {
        nodes,
        tris,
        prim_ids,
        blocks,
        block_tris,
        depth,
        leaf_blocks,
    }
}

struct Ctx<'a> {
    tree: &'a BTree,
    nodes: Vec<Node4>,
    depth: u32,
    leaf_blocks: Vec<u32>,
    /// The reference of each triangle, in leaf order.
    order: Vec<u32>,
    /// Per block: its first triangle and its number of used lanes (1..=4).
    block_starts: Vec<(u32, u32)>,
}

impl Ctx<'_> {
    /// Emits a node whose binary children are `start`; returns its index.
    fn emit(&mut self, start: &[&BNode], depth: u32) -> u32 {
        let index = self.nodes.len();
        self.nodes.push(Node4::EMPTY);
        self.depth = self.depth.max(depth);

        let (kids, len) = open_largest::<4>(self.tree, start);

        // Leaves first (HVVR §5), then inner children, each group in build order.
        let mut lane = 0;
        let mut node = Node4::EMPTY;
        for k in kids[..len].iter().flatten() {
            if let BNode::Leaf { start, count, .. } = k {
                let first = self.block_starts.len() as u32;
                self.leaf_blocks[*start as usize] = first;
                let tri0 = self.order.len() as u32;
                self.order.extend(*start..*start + *count);
                self.block_starts.extend(
                    (0..blocks_for(*count)).map(|b| (tri0 + 4 * b, (*count - 4 * b).min(4))),
                );
                node.child[lane] = ChildRef::Leaf {
                    first,
                    count: *count,
                }
                .encode();
                node.set_child_bounds(lane, k.bounds());
                lane += 1;
            }
        }
        // Record the leaf lanes now; inner lanes are written after their subtrees exist.
        self.nodes[index] = node;
        for k in kids[..len].iter().flatten() {
            if let BNode::Inner { children, bounds } = k {
                let child = self.emit(&self.tree.children(*children), depth + 1);
                let n = &mut self.nodes[index];
                n.child[lane] = ChildRef::Inner(child).encode();
                n.set_child_bounds(lane, *bounds);
                lane += 1;
            }
        }
        self.nodes[index].num_children = lane as u32;
        index as u32
    }
}
