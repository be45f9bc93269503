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

use crate::build::{BNode, BTree, PrimRef};
use crate::node::{ChildRef, Node4};
use crate::tri::Tri;
use crate::tri4::{Tri4, blocks_for};

/// The children of a `W`-wide node whose binary children are `start`: repeatedly replaces the
/// inner child of largest surface area by its two children, until there are `W` children or
/// only leaves (module docs). Returns the children (the first `len` are set) and `len`.
pub(crate) fn open_largest<'a, const W: usize>(
    tree: &'a BTree,
    start: &[&'a BNode],
) -> ([Option<&'a BNode>; W], usize) {
    let mut kids: [Option<&BNode>; W] = [None; W];
    for (k, s) in kids.iter_mut().zip(start) {
        *k = Some(s);
    }
    let mut len = start.len();
    while len < W {
        let pick = (0..len)
            .filter(|&i| matches!(kids[i], Some(BNode::Inner { .. })))
            .max_by(|&a, &b| {
                let area = |i: usize| kids[i].map_or(0.0, |k| k.bounds().surface_area());
                area(a).total_cmp(&area(b))
            });
        let Some(i) = pick else { break };
        let Some(BNode::Inner { children, .. }) = kids[i] else {
            unreachable!()
        };
        kids[i] = Some(tree.node(children[0]));
        kids[len] = Some(tree.node(children[1]));
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
    /// Depth of the deepest wide node (root = 1).
    pub depth: u32,
    /// The first block of each binary leaf, indexed by the leaf's first reference (`start`):
    /// the 8-wide collapse (`collapse8.rs`) points its leaves at the same blocks.
    pub leaf_blocks: Vec<u32>,
}

/// Collapses `root` (built over `refs`) into 4-wide nodes; `corners(id)` gives a triangle's
/// vertices.
pub(crate) fn collapse(
    tree: &BTree,
    refs: &[PrimRef],
    corners: impl Fn(u32) -> [Vec3; 3],
) -> Collapsed {
    let mut out = Collapsed {
        nodes: Vec::new(),
        tris: Vec::with_capacity(refs.len()),
        prim_ids: Vec::with_capacity(refs.len()),
        blocks: Vec::with_capacity(refs.len() / 2),
        depth: 0,
        leaf_blocks: vec![u32::MAX; refs.len()],
    };
    let mut ctx = Ctx {
        out: &mut out,
        tree,
        refs,
        corners: &corners,
    };
    let root = tree.node(tree.root);
    match root {
        // A tiny mesh: a root node with a single leaf lane.
        BNode::Leaf { .. } => ctx.emit(&[root], 1),
        BNode::Inner { children, .. } => {
            ctx.emit(&[tree.node(children[0]), tree.node(children[1])], 1)
        }
    };
    out
}

struct Ctx<'a, F> {
    out: &'a mut Collapsed,
    tree: &'a BTree,
    refs: &'a [PrimRef],
    corners: &'a F,
}

impl<F: Fn(u32) -> [Vec3; 3]> Ctx<'_, F> {
    /// Emits a node whose binary children are `start`; returns its index.
    fn emit(&mut self, start: &[&BNode], depth: u32) -> u32 {
        let index = self.out.nodes.len();
        self.out.nodes.push(Node4::EMPTY);
        self.out.depth = self.out.depth.max(depth);

        let (kids, len) = open_largest::<4>(self.tree, start);

        // Leaves first (HVVR §5), then inner children, each group in build order.
        let mut lane = 0;
        let mut node = Node4::EMPTY;
        for k in kids[..len].iter().flatten() {
            if let BNode::Leaf { start, count, .. } = k {
                let first = self.out.blocks.len() as u32;
                self.out.leaf_blocks[*start as usize] = first;
                self.out
                    .blocks
                    .extend((0..blocks_for(*count)).map(|_| Tri4::EMPTY));
                for (j, r) in self.refs[*start as usize..(*start + *count) as usize]
                    .iter()
                    .enumerate()
                {
                    let tri = Tri::new((self.corners)(r.id()));
                    let index = self.out.tris.len() as u32;
                    self.out.blocks[first as usize + j / 4].set(j % 4, &tri, index);
                    self.out.tris.push(tri);
                    self.out.prim_ids.push(r.id());
                }
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
        self.out.nodes[index] = node;
        for k in kids[..len].iter().flatten() {
            if let BNode::Inner { children, bounds } = k {
                let (c0, c1) = (self.tree.node(children[0]), self.tree.node(children[1]));
                let child = self.emit(&[c0, c1], depth + 1);
                let n = &mut self.out.nodes[index];
                n.child[lane] = ChildRef::Inner(child).encode();
                n.set_child_bounds(lane, *bounds);
                lane += 1;
            }
        }
        self.out.nodes[index].num_children = lane as u32;
        index as u32
    }
}
