//! Block and tile culling (module docs in `beam/mod.rs`).

use glam::Vec4;
use parallax_bvh::Bvh;
use parallax_bvh::node::{EMPTY, Node4, is_leaf, leaf_count};
use parallax_core::Aabb;

use super::shape::{BeamTest, PreparedBeam};

/// HVVR's entry-point budget of a block cull (§5.3, `α = 64`).
pub const BLOCK_ENTRIES: usize = 64;

/// An entry point: a child reference (inner node index or encoded leaf, `node.rs`), its box and
/// its near depth along the beam's dominant axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub child: u32,
    pub bounds: Aabb,
    pub near: f32,
}

/// A leaf of a tile's list: the encoded leaf reference (`node::leaf_first` = first block in
/// [`Bvh::blocks`], `node::leaf_count` = triangles) and its box's near depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafRef {
    pub leaf: u32,
    pub near: f32,
}

/// Per-thread scratch of the cull stages (no allocation once grown).
#[derive(Clone, Debug, Default)]
pub struct CullScratch {
    pub stack: Vec<Entry>,
    pub nodes: Vec<u32>,
    pub entries: Vec<Entry>,
    pub leaves: Vec<LeafRef>,
    /// The sort keys of `leaves` ([`sort_leaves`]).
    pub keys: Vec<u64>,
}

/// Classifies the four children of a node against a beam: `(miss mask, contained mask)`, bit
/// `i` = lane `i`; lanes in neither mask are Partial.
pub trait Classify4 {
    fn beam(&self) -> &PreparedBeam;
    fn classify4(&self, node: &Node4) -> (u32, u32);
}

/// The plain scalar twin: [`PreparedBeam::test_box`] per lane.
pub struct ScalarBeam<'a>(pub &'a PreparedBeam);

impl Classify4 for ScalarBeam<'_> {
    fn beam(&self) -> &PreparedBeam {
        self.0
    }
    fn classify4(&self, node: &Node4) -> (u32, u32) {
        let (mut miss, mut inside) = (0, 0);
        for l in 0..4 {
            match self.0.test_box(&node.child_bounds(l)) {
                BeamTest::Miss => miss |= 1 << l,
                BeamTest::Contained => inside |= 1 << l,
                BeamTest::Partial => {}
            }
        }
        (miss, inside)
    }
}

/// The 4-wide test: per plane, the box corner maximising / minimising `f` is picked per axis by
/// the sign of the (uniform) coefficient, so each plane costs two multiplies and one add per
/// bound on four boxes at once. The same f32 operations as [`PreparedBeam::test_box`], lane by
/// lane.
pub struct SimdBeam<'a> {
    beam: &'a PreparedBeam,
    /// Per plane: indices into `Node4::bounds` of the maximising / minimising bound of axis a
    /// and of the second axis.
    hi_a: [usize; 5],
    lo_a: [usize; 5],
    hi_x: [usize; 5],
    lo_x: [usize; 5],
    ca: [Vec4; 5],
    cx: [Vec4; 5],
    k_miss: [Vec4; 5],
    k_in: [Vec4; 5],
}

impl<'a> SimdBeam<'a> {
    pub fn new(beam: &'a PreparedBeam) -> Self {
        let pick = |c: f32, axis: usize| {
            if c >= 0.0 {
                (2 * axis + 1, 2 * axis)
            } else {
                (2 * axis, 2 * axis + 1)
            }
        };
        let mut s = SimdBeam {
            beam,
            hi_a: [0; 5],
            lo_a: [0; 5],
            hi_x: [0; 5],
            lo_x: [0; 5],
            ca: [Vec4::ZERO; 5],
            cx: [Vec4::ZERO; 5],
            k_miss: [Vec4::ZERO; 5],
            k_in: [Vec4::ZERO; 5],
        };
        for i in 0..5 {
            (s.hi_a[i], s.lo_a[i]) = pick(beam.ca[i], beam.axis);
            (s.hi_x[i], s.lo_x[i]) = pick(beam.cx[i], beam.x[i]);
            s.ca[i] = Vec4::splat(beam.ca[i]);
            s.cx[i] = Vec4::splat(beam.cx[i]);
            s.k_miss[i] = Vec4::splat(beam.k_miss[i]);
            s.k_in[i] = Vec4::splat(beam.k_in[i]);
        }
        s
    }
}

impl Classify4 for SimdBeam<'_> {
    fn beam(&self) -> &PreparedBeam {
        self.beam
    }
    #[inline(always)]
    fn classify4(&self, node: &Node4) -> (u32, u32) {
        if self.beam.everything {
            return (0, 0);
        }
        let b = &node.bounds;
        let mut miss = 0u32;
        let mut inside = 0xFu32;
        for i in 0..5 {
            let mut fmax = self.ca[i] * b[self.hi_a[i]];
            let mut fmin = self.ca[i] * b[self.lo_a[i]];
            if i > 0 {
                fmax += self.cx[i] * b[self.hi_x[i]];
                fmin += self.cx[i] * b[self.lo_x[i]];
            }
            miss |= fmax.cmplt(self.k_miss[i]).bitmask();
            inside &= fmin.cmpge(self.k_in[i]).bitmask();
        }
        (miss, inside & !miss)
    }
}

/// Most node visits of one cull (a hard bound on the loops; a cull visits each node at most
/// once, so `node_count + 1` would do).
fn step_bound(bvh: &Bvh) -> usize {
    4 * bvh.node_count() + 16
}

/// Block cull (§5.3; module docs): fills `s.entries` with at most `max_entries` entry points
/// (more only if a single refinement step overshoots, by at most 3), sorted by near depth.
pub fn block_cull<C: Classify4>(bvh: &Bvh, cls: &C, max_entries: usize, s: &mut CullScratch) {
    s.entries.clear();
    s.stack.clear();
    let beam = cls.beam();
    if bvh.node_count() == 0 {
        return;
    }
    let root = bvh.bounds();
    match beam.test_box(&root) {
        BeamTest::Miss => return,
        t => {
            let e = Entry {
                child: 0,
                bounds: root,
                near: beam.near(&root),
            };
            if t == BeamTest::Contained {
                s.entries.push(e);
                return;
            }
            s.stack.push(e);
        }
    }
    let a = beam.axis;
    let nodes = bvh.nodes();
    for _ in 0..step_bound(bvh) {
        if s.stack.is_empty() || s.stack.len() + s.entries.len() >= max_entries {
            break;
        }
        // The thickest box along the dominant axis first (HVVR §5.3).
        let mut best = 0;
        let mut thick = f32::NEG_INFINITY;
        for (i, e) in s.stack.iter().enumerate() {
            let t = e.bounds.max[a] - e.bounds.min[a];
            if t > thick {
                thick = t;
                best = i;
            }
        }
        let e = s.stack.swap_remove(best);
        if is_leaf(e.child) {
            s.entries.push(e);
            continue;
        }
        let node = &nodes[e.child as usize];
        let (miss, inside) = cls.classify4(node);
        for l in 0..4 {
            let c = node.child[l];
            if c == EMPTY || miss >> l & 1 != 0 {
                continue;
            }
            let bounds = node.child_bounds(l);
            let ce = Entry {
                child: c,
                bounds,
                near: beam.near(&bounds),
            };
            if inside >> l & 1 != 0 || is_leaf(c) {
                s.entries.push(ce);
            } else {
                s.stack.push(ce);
            }
        }
    }
    s.entries.append(&mut s.stack);
    s.entries
        .sort_unstable_by(|x, y| x.near.total_cmp(&y.near).then(x.child.cmp(&y.child)));
}

/// Tile cull (§5.4; module docs): from `entries` (a block's entry points) to the tile's leaves in
/// `s.leaves`, sorted by near depth. `s.entries` is not touched (pass the block's list).
pub fn tile_cull<C: Classify4>(bvh: &Bvh, cls: &C, entries: &[Entry], s: &mut CullScratch) {
    s.leaves.clear();
    s.nodes.clear();
    let beam = cls.beam();
    let nodes = bvh.nodes();
    let bound = step_bound(bvh);
    let mut steps = 0usize;
    let push_leaf = |leaves: &mut Vec<LeafRef>, c: u32, b: &Aabb| {
        if leaf_count(c) != 0 {
            leaves.push(LeafRef {
                leaf: c,
                near: beam.near(b),
            });
        }
    };
    for e in entries {
        let t = beam.test_box(&e.bounds);
        if t == BeamTest::Miss {
            continue;
        }
        if is_leaf(e.child) {
            push_leaf(&mut s.leaves, e.child, &e.bounds);
            continue;
        }
        let contained_root = t == BeamTest::Contained;
        s.nodes.push(e.child);
        while let Some(n) = s.nodes.pop() {
            steps += 1;
            if steps > bound {
                break;
            }
            let node = &nodes[n as usize];
            let (miss, inside) = if contained_root {
                (0, 0xF)
            } else {
                cls.classify4(node)
            };
            for l in 0..4 {
                let c = node.child[l];
                if c == EMPTY || miss >> l & 1 != 0 {
                    continue;
                }
                if is_leaf(c) {
                    push_leaf(&mut s.leaves, c, &node.child_bounds(l));
                } else if inside >> l & 1 != 0 {
                    // A contained subtree: every leaf, no more tests.
                    collect_all(bvh, c, beam, &mut s.leaves, &mut steps, bound);
                } else {
                    s.nodes.push(c);
                }
            }
        }
    }
    sort_leaves(&mut s.leaves, &mut s.keys);
}

/// Sorts `leaves` by `near` (`total_cmp`), then `leaf`: each as one integer key
/// ([`total_order_key`] and the leaf), the keys sorted as plain `u64` (no key computed per
/// comparison) and the leaves read back from them (the key is a bijection), so the list is
/// the one `sort_unstable_by_key` on the same key gives.
fn sort_leaves(leaves: &mut [LeafRef], keys: &mut Vec<u64>) {
    keys.clear();
    keys.extend(
        leaves
            .iter()
            .map(|x| (total_order_key(x.near) as u64) << 32 | x.leaf as u64),
    );
    keys.sort_unstable();
    for (x, &k) in leaves.iter_mut().zip(keys.iter()) {
        *x = LeafRef {
            leaf: k as u32,
            near: from_total_order_key((k >> 32) as u32),
        };
    }
}

/// The inverse of [`total_order_key`] (bit for bit, NaN payloads included).
#[inline(always)]
fn from_total_order_key(k: u32) -> f32 {
    let b = (k ^ 0x8000_0000) as i32;
    f32::from_bits((b ^ ((((b >> 31) as u32) >> 1) as i32)) as u32)
}

/// An unsigned key whose order is [`f32::total_cmp`]'s (its sign-magnitude to two's-complement
/// flip, then the sign bit flipped for an unsigned comparison).
#[inline(always)]
fn total_order_key(x: f32) -> u32 {
    let b = x.to_bits() as i32;
    ((b ^ ((((b >> 31) as u32) >> 1) as i32)) as u32) ^ 0x8000_0000
}

/// Every leaf under inner node `root` (a subtree the beam contains).
fn collect_all(
    bvh: &Bvh,
    root: u32,
    beam: &PreparedBeam,
    leaves: &mut Vec<LeafRef>,
    steps: &mut usize,
    bound: usize,
) {
    let nodes = bvh.nodes();
    let mut stack = [0u32; 256];
    let mut sp = 1;
    stack[0] = root;
    while sp > 0 {
        sp -= 1;
        *steps += 1;
        if *steps > bound {
            return;
        }
        let node = &nodes[stack[sp] as usize];
        for l in 0..4 {
            let c = node.child[l];
            if c == EMPTY {
                continue;
            }
            if is_leaf(c) {
                if leaf_count(c) != 0 {
                    leaves.push(LeafRef {
                        leaf: c,
                        near: beam.near(&node.child_bounds(l)),
                    });
                }
            } else if sp < stack.len() {
                stack[sp] = c;
                sp += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{LeafRef, from_total_order_key, sort_leaves, total_order_key};

    /// The key sort gives the list of `sort_unstable_by_key` on the same key, and the key
    /// reads back bit for bit.
    #[test]
    fn sort_leaves_equals_sort_by_key() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let special = [0.0f32, -0.0, f32::INFINITY, f32::NAN, -f32::NAN, 1e-45, 2.5];
        let mut keys = Vec::new();
        for n in [0usize, 1, 2, 7, 33, 200, 1000] {
            let mut a: Vec<LeafRef> = (0..n)
                .map(|_| {
                    let r = next();
                    let near = if r % 4 == 0 {
                        special[(r >> 8) as usize % special.len()]
                    } else {
                        f32::from_bits((r >> 16) as u32)
                    };
                    // Few distinct leaves: equal keys occur.
                    LeafRef {
                        leaf: (r >> 48) as u32 % 50,
                        near,
                    }
                })
                .collect();
            for v in &a {
                let k = total_order_key(v.near);
                assert_eq!(from_total_order_key(k).to_bits(), v.near.to_bits());
            }
            let mut b = a.clone();
            b.sort_unstable_by_key(|x| (total_order_key(x.near) as u64) << 32 | x.leaf as u64);
            sort_leaves(&mut a, &mut keys);
            let bits = |v: &[LeafRef]| -> Vec<(u32, u32)> {
                v.iter().map(|x| (x.leaf, x.near.to_bits())).collect()
            };
            assert_eq!(bits(&a), bits(&b), "n = {n}");
        }
    }

    /// The key orders like `f32::total_cmp` on zeros, subnormals, infinities, NaNs of both
    /// signs and random bit patterns.
    #[test]
    fn total_order_key_is_total_cmp() {
        let mut v = vec![
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1e-45,
            -1e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
        ];
        let mut x = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..2000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            v.push(f32::from_bits(x as u32));
        }
        for a in &v {
            for b in v.iter().step_by(7) {
                assert_eq!(
                    a.total_cmp(b),
                    total_order_key(*a).cmp(&total_order_key(*b)),
                    "{a} {b}"
                );
            }
        }
    }
}
