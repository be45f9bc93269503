//! Work counters of the traversals.
//!
//! The traversal kernels are generic over [`Counter`]; the plain queries use [`NoStats`], whose
//! methods are empty and vanish after inlining, so counting costs nothing unless asked for.

use std::iter::Sum;
use std::ops::{Add, AddAssign};

/// What a traversal did: summed over rays with `+=` or `.sum()`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalStats {
    /// Rays traced.
    pub rays: u64,
    /// Inner nodes whose children were tested.
    pub nodes_visited: u64,
    /// Child boxes tested (used lanes of the visited nodes).
    pub box_tests: u64,
    /// Leaves whose triangles were tested.
    pub leaves_visited: u64,
    /// Ray-triangle tests.
    pub triangle_tests: u64,
    /// Triangle tests that reported a hit (for closest hit: every improvement).
    pub triangle_hits: u64,
}

impl TraversalStats {
    /// Average over rays of a counter (0 when no ray was traced).
    pub fn per_ray(&self, counter: u64) -> f64 {
        if self.rays == 0 {
            0.0
        } else {
            counter as f64 / self.rays as f64
        }
    }
}

impl AddAssign for TraversalStats {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nodes_visited += o.nodes_visited;
        self.box_tests += o.box_tests;
        self.leaves_visited += o.leaves_visited;
        self.triangle_tests += o.triangle_tests;
        self.triangle_hits += o.triangle_hits;
    }
}

impl Add for TraversalStats {
    type Output = Self;
    fn add(mut self, o: Self) -> Self {
        self += o;
        self
    }
}

impl Sum for TraversalStats {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), Add::add)
    }
}

/// Counting hooks of the traversal kernels.
pub trait Counter {
    fn ray(&mut self);
    fn node(&mut self, boxes: u32);
    fn leaf(&mut self);
    fn triangle(&mut self, hit: bool);
    /// One [`Counter::triangle`] per set bit of `tested` (lanes of a SIMD triangle test), hit
    /// where `hit` has the bit too. [`NoStats`] overrides it with an empty body.
    #[inline(always)]
    fn triangles(&mut self, tested: u32, hit: u32) {
        let mut m = tested;
        while m != 0 {
            let l = m.trailing_zeros();
            m &= m - 1;
            self.triangle(hit >> l & 1 != 0);
        }
    }
}

/// The no-op counter of the fast path.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl Counter for NoStats {
    #[inline(always)]
    fn ray(&mut self) {}
    #[inline(always)]
    fn node(&mut self, _: u32) {}
    #[inline(always)]
    fn leaf(&mut self) {}
    #[inline(always)]
    fn triangle(&mut self, _: bool) {}
    /// Empty: the default's loop over the set bits would stay in the kernels (LLVM keeps a
    /// side-effect-free loop whose termination it does not prove).
    #[inline(always)]
    fn triangles(&mut self, _: u32, _: u32) {}
}

impl Counter for TraversalStats {
    #[inline(always)]
    fn ray(&mut self) {
        self.rays += 1;
    }
    #[inline(always)]
    fn node(&mut self, boxes: u32) {
        self.nodes_visited += 1;
        self.box_tests += boxes as u64;
    }
    #[inline(always)]
    fn leaf(&mut self) {
        self.leaves_visited += 1;
    }
    #[inline(always)]
    fn triangle(&mut self, hit: bool) {
        self.triangle_tests += 1;
        self.triangle_hits += hit as u64;
    }
}
