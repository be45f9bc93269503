//! Conservatively quantised 8-wide nodes: the [`Node8`] tree with each child box stored as
//! 8-bit offsets from a per-node origin, in steps of a scale per axis (the
//! compressed nodes of Ylitie, Karras & Laine 2017 §3.1 and Embree's `BVH8` quantised node,
//! Wald et al. 2014 §3.1), derived from the 8-wide tree after the build and after a refit. A
//! node is two cache lines instead of four.
//!
//! ## Layout (128 bytes, two cache lines, 64-byte aligned)
//!
//! | bytes | field | meaning |
//! |---|---|---|
//! | 0..48 | `q: [[u8; 8]; 6]` | `min_x, max_x, min_y, max_y, min_z, max_z` in steps, one lane per child |
//! | 48..60 | `origin: [f32; 3]` | the node's box minimum |
//! | 60..64 | `valid` | bit `i` set iff lane `i` is used (the first `num_children` lanes) |
//! | 64..76 | `scale: [f32; 3]` | the step per axis |
//! | 76..80 | `leaf_mask` | as [`Node8::leaf_mask`] |
//! | 80..112 | `child: [u32; 8]` | as [`Node8::child`] (same references, same node indices) |
//! | 112..116 | `num_children` | as [`Node8::num_children`] |
//! | 116..128 | padding | zero |
//!
//! The plane of row `r`, lane `i` is `dequantise(origin[axis], scale[axis], q[r][i])`
//! `= fma(q, scale, origin)` in f32, one rounding (a fused multiply-add in both node tests). The quantisation rounds outward and checks each plane
//! with that same function (lower planes `<=` the exact minimum, upper planes `>=` the exact
//! maximum), so every dequantised box **contains** its child's exact box: a slab test on the
//! dequantised boxes only culls less, and a traversal over them returns what the exact tree
//! returns. Unused lanes are masked by `valid` (their `q` rows are `255` / `0`). A node whose
//! extent cannot be stepped in 255 normal-float steps (non-finite or beyond `f32::MAX`) makes
//! the whole quantised tree unavailable ([`quantise_tree`] returns an empty vector).

use crate::node::EMPTY;
use crate::node8::{Node8, Node8Refs, WIDTH8};

/// The smallest step (a flat node needs none; any positive step serves).
const MIN_SCALE: f32 = 1.0 / (1u64 << 60) as f32 / (1u64 << 40) as f32; // 2^-100

/// A quantised 8-wide node (layout in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node8Q {
    /// Plane rows in steps: `[min_x, max_x, min_y, max_y, min_z, max_z]`, lane `i` = child `i`.
    pub q: [[u8; 8]; 6],
    pub origin: [f32; 3],
    /// Bit `i` set iff lane `i` is used.
    pub valid: u32,
    /// The step per axis.
    pub scale: [f32; 3],
    pub leaf_mask: u32,
    pub child: [u32; 8],
    pub num_children: u32,
    pub reserved: [u32; 3],
}

const _: () = assert!(std::mem::size_of::<Node8Q>() == 128);
const _: () = assert!(std::mem::offset_of!(Node8Q, origin) == 48);
const _: () = assert!(std::mem::offset_of!(Node8Q, scale) == 64);
const _: () = assert!(std::mem::offset_of!(Node8Q, child) == 80);

/// The plane `origin + q * scale` (module docs: exact product, one rounding).
#[inline(always)]
pub fn dequantise(origin: f32, scale: f32, q: u8) -> f32 {
    (q as f32).mul_add(scale, origin)
}

/// The smallest step `s >= MIN_SCALE` with `dequantise(lo, s, 255) >= hi`, if it is
/// finite.
fn axis_scale(lo: f32, hi: f32) -> Option<f32> {
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return None;
    }
    let mut s = (((hi as f64 - lo as f64) / 255.0) as f32).max(MIN_SCALE);
    if !s.is_finite() {
        return None;
    }
    // Rounding of the estimate either way: settle on the smallest step that reaches `hi`.
    while s.is_finite() && dequantise(lo, s, 255) < hi {
        s = s.next_up();
    }
    while s.next_down() >= MIN_SCALE && dequantise(lo, s.next_down(), 255) >= hi {
        s = s.next_down();
    }
    (s.is_finite() && dequantise(lo, s, 255).is_finite()).then_some(s)
}

/// The largest step `q` with `dequantise(o, s, q) <= x` (`q = 0` qualifies: `o <= x`).
fn step_below(o: f32, s: f32, x: f32) -> u8 {
    let mut q = ((x as f64 - o as f64) / s as f64).floor().clamp(0.0, 255.0) as u8;
    while q > 0 && dequantise(o, s, q) > x {
        q -= 1;
    }
    while q < 255 && dequantise(o, s, q + 1) <= x {
        q += 1;
    }
    q
}

/// The smallest step `q` with `dequantise(o, s, q) >= x` (`q = 255` qualifies by the scale).
fn step_above(o: f32, s: f32, x: f32) -> u8 {
    let mut q = ((x as f64 - o as f64) / s as f64).ceil().clamp(0.0, 255.0) as u8;
    while q < 255 && dequantise(o, s, q) < x {
        q += 1;
    }
    while q > 0 && dequantise(o, s, q - 1) >= x {
        q -= 1;
    }
    q
}

impl Node8Q {
    /// The quantised form of `n` (module docs), or `None` where an axis cannot be stepped.
    pub fn quantise(n: &Node8) -> Option<Node8Q> {
        let used = n.num_children as usize;
        debug_assert!((1..=WIDTH8).contains(&used));
        let mut out = Node8Q {
            q: [[255; 8], [0; 8], [255; 8], [0; 8], [255; 8], [0; 8]],
            origin: [0.0; 3],
            valid: (1u32 << used) - 1,
            scale: [1.0; 3],
            leaf_mask: n.leaf_mask,
            child: n.child,
            num_children: n.num_children,
            reserved: [0; 3],
        };
        for a in 0..3 {
            let (mins, maxs) = (&n.bounds[2 * a][..used], &n.bounds[2 * a + 1][..used]);
            let lo = mins.iter().fold(f32::INFINITY, |m, &x| m.min(x));
            let hi = maxs.iter().fold(f32::NEG_INFINITY, |m, &x| m.max(x));
            let s = axis_scale(lo, hi)?;
            out.origin[a] = lo;
            out.scale[a] = s;
            for i in 0..used {
                if mins[i] > maxs[i] {
                    return None;
                }
                out.q[2 * a][i] = step_below(lo, s, mins[i]);
                out.q[2 * a + 1][i] = step_above(lo, s, maxs[i]);
                debug_assert!(self::dequantise(lo, s, out.q[2 * a][i]) <= mins[i]);
                debug_assert!(self::dequantise(lo, s, out.q[2 * a + 1][i]) >= maxs[i]);
            }
        }
        Some(out)
    }

    /// The dequantised plane of row `row` (`2 axis + is_max`), lane `lane`.
    #[inline]
    pub fn plane(&self, row: usize, lane: usize) -> f32 {
        dequantise(self.origin[row / 2], self.scale[row / 2], self.q[row][lane])
    }
}

impl Node8Refs for Node8Q {
    #[inline(always)]
    fn child(&self) -> &[u32; 8] {
        &self.child
    }
    #[inline(always)]
    fn leaf_mask(&self) -> u32 {
        self.leaf_mask
    }
    #[inline(always)]
    fn num_children(&self) -> u32 {
        self.num_children
    }
}

/// The quantised tree of `nodes` (same indices), or an empty vector where a node cannot be
/// quantised (the traversal then uses the exact tree).
pub(crate) fn quantise_tree(nodes: &[Node8]) -> Vec<Node8Q> {
    use rayon::prelude::*;
    let q: Option<Vec<Node8Q>> = nodes
        .par_iter()
        .with_min_len(512)
        .map(|n| {
            if n.child[..n.num_children as usize].contains(&EMPTY) {
                return None;
            }
            Node8Q::quantise(n)
        })
        .collect();
    q.unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::Aabb;

    /// Boxes with negative, tiny, huge, flat and tied coordinates: every quantised lane contains
    /// its box, no plane could step inward, and the used lanes are the valid ones.
    #[test]
    fn quantised_boxes_contain_the_exact_ones() {
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let (mut checked, mut tight) = (0, 0);
        for case in 0..4000 {
            let mut n = Node8::EMPTY;
            let used = 1 + (next() % 8) as usize;
            let mag = [1e-30f32, 1e-3, 1.0, 1e3, 1e20][case % 5];
            let base = (next() % 2001) as f32 - 1000.0;
            for i in 0..used {
                let mut c = [0.0f32; 6];
                for a in 0..3 {
                    let x = base * mag + ((next() % 1000) as f32 - 500.0) * mag * 1e-3;
                    let w = if case % 7 == 0 {
                        0.0
                    } else {
                        (next() % 100) as f32 * mag * 1e-3
                    };
                    c[2 * a] = x;
                    c[2 * a + 1] = x + w;
                }
                let b = Aabb {
                    min: glam::Vec3::new(c[0], c[2], c[4]),
                    max: glam::Vec3::new(c[1], c[3], c[5]),
                };
                n.set_child_bounds(i, b);
                n.child[i] = i as u32 + 1;
            }
            n.num_children = used as u32;
            let q = Node8Q::quantise(&n).expect("finite");
            assert_eq!(q.valid, (1 << used) - 1);
            for a in 0..3 {
                let s = q.scale[a];
                assert!(s >= MIN_SCALE);
                for i in 0..used {
                    let (lo, hi) = (n.bounds[2 * a][i], n.bounds[2 * a + 1][i]);
                    let (ql, qh) = (q.plane(2 * a, i), q.plane(2 * a + 1, i));
                    assert!(ql <= lo && qh >= hi, "{a} {i}: {ql} {lo} {qh} {hi}");
                    // Tight: the next step inward would not contain the box.
                    let ql1 = q.q[2 * a][i];
                    let qh1 = q.q[2 * a + 1][i];
                    assert!(ql1 == 255 || dequantise(q.origin[a], s, ql1 + 1) > lo);
                    assert!(qh1 == 0 || dequantise(q.origin[a], s, qh1 - 1) < hi);
                    tight += (ql == lo && qh == hi) as u32;
                    checked += 1;
                }
            }
        }
        assert!(checked > 30_000, "{checked}");
        assert!(tight > 100, "{tight}");
    }

    /// A non-finite extent cannot be stepped: no quantised node; `[-f32::MAX, f32::MAX]` can.
    #[test]
    fn non_finite_extent_is_refused() {
        let mut n = Node8::EMPTY;
        n.set_child_bounds(
            0,
            Aabb {
                min: glam::Vec3::splat(-f32::MAX),
                max: glam::Vec3::splat(f32::MAX),
            },
        );
        n.child[0] = 1;
        n.num_children = 1;
        let q = Node8Q::quantise(&n).expect("finite extent");
        assert!(q.plane(0, 0) <= -f32::MAX && q.plane(1, 0) >= f32::MAX);
        n.bounds[1][0] = f32::INFINITY;
        assert!(Node8Q::quantise(&n).is_none());
        assert!(quantise_tree(&[n]).is_empty());
    }
}
