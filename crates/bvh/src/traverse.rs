//! Single-ray traversal of the 4-wide BVH: closest hit, any hit, all hits.
//!
//! One kernel ([`Bvh::traverse`]) serves all three queries; the leaf action is a closure and the
//! work counter a generic ([`Counter`]), so each query compiles to its own specialised loop
//! without runtime switches. The loop is the explicit-stack wide traversal of Wald et al. 2008 /
//! Embree (Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray tracing", §4):
//! test the four child boxes of a node with one SIMD slab test, continue with the nearest hit
//! child, push the others far-to-near with their entry distance, and on pop skip entries that
//! start beyond the closest hit found so far.
//!
//! The stack is a fixed array of [`STACK_SIZE`] entries: a node pushes at most 3 entries, and
//! the build bounds the depth (`build.rs`), so `3 * depth < STACK_SIZE` (checked at build).

use std::mem::MaybeUninit;

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::ROBUST_FAR_SCALE;
use parallax_core::math::WatertightRay;

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::node::{Node4, is_leaf, leaf_count, leaf_first};
use crate::stats::{Counter, NoStats, TraversalStats};
use crate::tri4::{Tri4, Tri4Ray, blocks_for, lane_mask};
use parallax_core::simd::{max_or_rhs, min_or_rhs};

/// Traversal stack entries.
pub(crate) const STACK_SIZE: usize = 256;

/// The four children of `node` as stack keys `t_near_bits << 32 | child`; lanes the ray misses
/// get `u64::MAX`.
#[inline(always)]
fn child_keys(node: &Node4, t_near: Vec4) -> [u64; 4] {
    let t = t_near.to_array();
    let mut k = [0u64; 4];
    for i in 0..4 {
        k[i] = (t[i].to_bits() as u64) << 32 | node.child[i] as u64;
    }
    k
}

/// A ray prepared for the 4-wide slab test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    /// Byte offset into `Node4::bounds` of the near / far plane per axis
    /// (`16 * (2 * axis + sign)`).
    near: [usize; 3],
    far: [usize; 3],
    t_min: Vec4,
}

impl RayBoxes {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        // 1 / ±0 = ±inf; see `intersect` for how the resulting 0 * inf = NaN is handled.
        let inv = ray.dir.recip();
        let o = ray.origin;
        let neg = |x: f32| x.is_sign_negative() as usize;
        let (sx, sy, sz) = (neg(inv.x), neg(inv.y), neg(inv.z));
        Self {
            org: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [16 * sx, 16 * (2 + sy), 16 * (4 + sz)],
            far: [16 * (1 - sx), 16 * (3 - sy), 16 * (5 - sz)],
            t_min: Vec4::splat(ray.t_min),
        }
    }

    /// Slab test of the four children (Kay & Kajiya 1986), ordered form: per axis the ray's sign
    /// picks the near and far plane, so
    ///
    /// ```text
    /// t_near = max(t_min, (near_x - o_x) / d_x, (near_y - o_y) / d_y, (near_z - o_z) / d_z)
    /// t_far  = min(t_max, (far_x - o_x) / d_x, ...) * (1 + 2 gamma(3))   (Ize 2013, robust)
    /// hit    = t_near <= t_far
    /// ```
    ///
    /// Empty lanes (`min = +inf, max = -inf`) give `t_near = +inf`, `t_far = -inf`: never hit.
    /// A zero direction component with the origin exactly on a plane gives `0 * inf = NaN`; the
    /// ray then lies in the closed slab, and `max_or_rhs` / `min_or_rhs` ignore the NaN (the
    /// accumulators on the right stay NaN-free). Returns the hit mask (bit i = lane i) and the
    /// entry distances (all-ones bits, a NaN, in missed lanes).
    #[inline(always)]
    pub fn intersect(&self, node: &Node4, t_max: f32) -> (u32, Vec4) {
        let base = node.bounds.as_ptr() as *const u8;
        // SAFETY: the offsets are `16 * i` with `i < 6` (`new`), inside `bounds: [Vec4; 6]`.
        let b = |off: usize| unsafe { *(base.add(off) as *const Vec4) };
        let tnx = (b(self.near[0]) - self.org[0]) * self.inv[0];
        let tny = (b(self.near[1]) - self.org[1]) * self.inv[1];
        let tnz = (b(self.near[2]) - self.org[2]) * self.inv[2];
        let tfx = (b(self.far[0]) - self.org[0]) * self.inv[0];
        let tfy = (b(self.far[1]) - self.org[1]) * self.inv[1];
        let tfz = (b(self.far[2]) - self.org[2]) * self.inv[2];
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, self.t_min)));
        // The closest hit so far (`t_max`) is scaled too: a triangle on a box face can be hit at
        // a `t` a few ulps below the box's computed entry distance, and culling against the
        // bare `t_max` then depends on the visiting order (found on random Sponza rays). It
        // starts the (NaN-free) accumulator: one `min` fewer than `min(t_far, t_max)`.
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, Vec4::splat(t_max))));
        let t_far = t_far * ROBUST_FAR_SCALE;
        let hit = t_near.cmple(t_far);
        // Missed lanes get all-ones bits, so their stack keys (`child_keys`) sort last.
        let t_near = Vec4::select(hit, t_near, Vec4::splat(f32::from_bits(u32::MAX)));
        (hit.bitmask(), t_near)
    }
}

/// Whether a ray can hit anything: finite origin and direction, non-zero direction, and a
/// non-empty, non-NaN interval (`ray.is_valid() && ray.t_min <= ray.t_max`, the reference the
/// tests hold it to). Without branches per component: `x - x` is `0` for finite `x` and NaN for
/// infinities and NaN, so the sum of the six differences is `0` exactly when all six are finite.
#[inline(always)]
pub(crate) fn ray_ok(ray: &Ray) -> bool {
    let (o, d) = (ray.origin, ray.dir);
    // `x - x` on purpose: 0 or NaN, the finiteness test (doc above).
    #[allow(clippy::eq_op)]
    let z = (o - o) + (d - d);
    (z.x + z.y + z.z == 0.0) & (d.length_squared() > 0.0) & (ray.t_min <= ray.t_max)
}

impl Bvh {
    /// The traversal kernel. `leaf(first, count, t_max, stats)` tests a leaf's triangles, may
    /// shrink `t_max` (closest hit), and returns `true` to stop (any hit). With `ORDERED`,
    /// children are visited near-to-far; otherwise in lane order.
    ///
    /// Stack entries are `u64` keys `t_bits << 32 | child`: for the non-negative entry distances
    /// of rays with `t_min >= 0` the integer order of the keys is the order of `t`, so a
    /// branch-free sorting network on integers orders 3-4 hit children (a negative `t_min` only
    /// changes the visiting order, never the answer: the closest hit is the lexicographic
    /// minimum of `(t, index)` over all hits whatever the order).
    #[inline(always)]
    fn traverse<C: Counter, const ORDERED: bool>(
        &self,
        rb: &RayBoxes,
        mut t_max: f32,
        stats: &mut C,
        mut leaf: impl FnMut(u32, u32, &mut f32, &mut C) -> bool,
    ) {
        // Uninitialised: saves a 2 KB memset per ray. Four spare slots: the branch-free pushes
        // below may write (but never count) up to three entries past the live top.
        let mut stack = [MaybeUninit::<u64>::uninit(); STACK_SIZE + 4];
        let mut sp = 0usize;
        let mut cur = 0u32; // the root
        let nodes = self.nodes.as_ptr();
        loop {
            if !is_leaf(cur) {
                debug_assert!((cur as usize) < self.nodes.len());
                // SAFETY: inner child references index the node array (build invariant; refit
                // keeps the topology).
                let node = unsafe { &*nodes.add(cur as usize) };
                stats.node(node.num_children);
                let (mask, t_near) = rb.intersect(node, t_max);
                if mask != 0 {
                    let rest = mask & (mask - 1);
                    if rest == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    let keys = child_keys(node, t_near);
                    debug_assert!(sp + 4 <= stack.len());
                    // SAFETY: `sp + 3 < STACK_SIZE + 4` (a node pushes at most 3 entries and
                    // `3 * depth < STACK_SIZE`, checked at build).
                    let push = |stack: &mut [MaybeUninit<u64>], sp: usize, k: u64| unsafe {
                        *stack.get_unchecked_mut(sp) = MaybeUninit::new(k);
                    };
                    if !ORDERED {
                        let c0 = mask.trailing_zeros() as usize;
                        let mut m = rest;
                        while m != 0 {
                            let c = m.trailing_zeros() as usize;
                            m &= m - 1;
                            push(&mut stack, sp, keys[c]);
                            sp += 1;
                        }
                        cur = node.child[c0];
                        continue;
                    }
                    let rest2 = rest & (rest - 1);
                    if rest2 == 0 {
                        let (a, b) = (
                            keys[mask.trailing_zeros() as usize],
                            keys[rest.trailing_zeros() as usize],
                        );
                        push(&mut stack, sp, a.max(b));
                        sp += 1;
                        cur = a.min(b) as u32;
                        continue;
                    }
                    // Three or four children: non-hit lanes have all-ones keys and sort last;
                    // a 5-comparator network on the four keys, push far-to-near, continue with
                    // the nearest.
                    let [mut k0, mut k1, mut k2, mut k3] = keys;
                    let sort2 = |a: &mut u64, b: &mut u64| {
                        let (x, y) = (*a, *b);
                        *a = x.min(y);
                        *b = x.max(y);
                    };
                    sort2(&mut k0, &mut k1);
                    sort2(&mut k2, &mut k3);
                    sort2(&mut k0, &mut k2);
                    sort2(&mut k1, &mut k3);
                    sort2(&mut k1, &mut k2);
                    push(&mut stack, sp, k3);
                    sp += (rest2 & (rest2 - 1) != 0) as usize;
                    push(&mut stack, sp, k2);
                    push(&mut stack, sp + 1, k1);
                    sp += 2;
                    cur = k0 as u32;
                    continue;
                }
            } else {
                stats.leaf();
                if leaf(leaf_first(cur), leaf_count(cur), &mut t_max, stats) {
                    return;
                }
            }
            // Pop the next entry that can still hold a closer hit.
            match pop_closer(&stack, &mut sp, t_max) {
                Some(next) => cur = next,
                None => return,
            }
        }
    }

    /// Closest hit with the SIMD leaf test (`tri4.rs`), or the scalar per-triangle test
    /// (`SIMD = false`, the slow twin kept for tests). Both break exact ties in `t` towards the
    /// lower primitive id (the scene's triangle index), so the answer is the lexicographic
    /// minimum of `(t, primitive id)` over all hits, whatever the tree (with or without spatial
    /// splits) and whatever order the leaves are visited in (the packet traversal relies on
    /// this to return exactly the single-ray answer): brute force's answer.
    #[inline(always)]
    fn closest_impl<C: Counter, const SIMD: bool>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return None;
        }
        let rb = RayBoxes::new(ray);
        let r4 = Tri4Ray::new(WatertightRay::new(ray));
        let mut best = Best::new();
        self.traverse::<C, true>(&rb, ray.t_max, stats, |first, count, t_max, stats| {
            if SIMD {
                self.leaf_closest(&r4, first, count, t_max, &mut best, stats);
            } else {
                for i in self.leaf_triangles(first, count) {
                    let tri = &self.tris[i];
                    let h = r4
                        .wt
                        .intersect_within(tri.p0, tri.p1, tri.p2, best.limit(*t_max));
                    stats.triangle(h.is_some());
                    if let Some(h) = h {
                        best.offer(h.t, self.prim_ids[i], h.u, h.v, t_max);
                    }
                }
            }
            false
        });
        best.hit()
    }

    /// Tests the blocks of a leaf against one ray and keeps the closest hit in `best`.
    #[inline(always)]
    pub(crate) fn leaf_closest<C: Counter>(
        &self,
        r4: &Tri4Ray,
        first: u32,
        count: u32,
        t_max: &mut f32,
        best: &mut Best,
        stats: &mut C,
    ) {
        for k in 0..blocks_for(count) {
            let b = &self.blocks[(first + k) as usize];
            let mask = lane_mask(count, k);
            let h = r4.intersect(b, mask, best.limit(*t_max));
            stats.triangles(mask, h.hit);
            if h.hit != 0 {
                let (t, u, v) = (h.t.to_array(), h.u.to_array(), h.v.to_array());
                let mut m = h.hit;
                while m != 0 {
                    let l = m.trailing_zeros() as usize;
                    m &= m - 1;
                    best.offer(t[l], b.tri[l], u[l], v[l], t_max);
                }
            }
            let mut m = h.exact;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                offer_exact(r4, b, l, best, t_max);
            }
        }
    }

    /// Whether any triangle of a leaf is hit by one ray in `(t_min, t_max)` (SIMD blocks,
    /// exact-zero lanes by the scalar test).
    #[inline(always)]
    pub(crate) fn leaf_any<C: Counter>(
        &self,
        r4: &Tri4Ray,
        first: u32,
        count: u32,
        t_max: f32,
        stats: &mut C,
    ) -> bool {
        for k in 0..blocks_for(count) {
            let b = &self.blocks[(first + k) as usize];
            let mask = lane_mask(count, k);
            let h = r4.intersect(b, mask, t_max);
            stats.triangles(mask, h.hit);
            if h.hit != 0 {
                return true;
            }
            let mut m = h.exact;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                let (p0, p1, p2) = (b.vertex(l, 0), b.vertex(l, 1), b.vertex(l, 2));
                if r4.wt.intersect_within(p0, p1, p2, t_max).is_some() {
                    return true;
                }
            }
        }
        false
    }

    /// Every hit of one ray with a leaf's triangles, appended to `out` (scalar test).
    #[inline(always)]
    pub(crate) fn leaf_all<C: Counter>(
        &self,
        wt: &WatertightRay,
        first: u32,
        count: u32,
        out: &mut Vec<Hit>,
        stats: &mut C,
    ) {
        for i in self.leaf_triangles(first, count) {
            let tri = &self.tris[i];
            let h = wt.intersect(tri.p0, tri.p1, tri.p2);
            stats.triangle(h.is_some());
            if let Some(h) = h {
                out.push(Hit {
                    prim: self.prim_ids[i],
                    t: h.t,
                    u: h.u,
                    v: h.v,
                });
            }
        }
    }

    #[inline(always)]
    fn any_impl<C: Counter, const SIMD: bool>(&self, ray: &Ray, stats: &mut C) -> bool {
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return false;
        }
        let rb = RayBoxes::new(ray);
        let r4 = Tri4Ray::new(WatertightRay::new(ray));
        let mut found = false;
        self.traverse::<C, false>(&rb, ray.t_max, stats, |first, count, t_max, stats| {
            found = if SIMD {
                self.leaf_any(&r4, first, count, *t_max, stats)
            } else {
                self.tris[self.leaf_triangles(first, count)]
                    .iter()
                    .any(|tri| {
                        let h = r4.wt.intersect_within(tri.p0, tri.p1, tri.p2, *t_max);
                        stats.triangle(h.is_some());
                        h.is_some()
                    })
            };
            found
        });
        found
    }

    #[inline(always)]
    fn all_impl<C: Counter>(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut C) {
        out.clear();
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return;
        }
        let rb = RayBoxes::new(ray);
        let wt = WatertightRay::new(ray);
        self.traverse::<C, false>(&rb, ray.t_max, stats, |first, count, _, stats| {
            self.leaf_all(&wt, first, count, out, stats);
            false
        });
        sort_dedup_hits(out);
    }

    /// [`Bvh::closest_hit`] over the 4-wide tree (the twin of the 8-wide traversal; same
    /// answer bit for bit: both return the lexicographic minimum of `(t, primitive id)`).
    pub fn closest_hit4(&self, ray: &Ray) -> Option<Hit> {
        self.closest_impl::<_, true>(ray, &mut NoStats)
    }

    /// [`Self::closest_hit4`], adding the work done (in 4-wide nodes) to `stats`.
    pub fn closest_hit4_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        self.closest_impl::<_, true>(ray, stats)
    }

    /// [`Self::closest_hit4`] with the scalar triangle test on each leaf triangle instead of
    /// the 4-wide one: the slow twin the tests hold the SIMD leaf test against (same answer,
    /// bit for bit).
    pub fn closest_hit_scalar(&self, ray: &Ray) -> Option<Hit> {
        self.closest_impl::<_, false>(ray, &mut NoStats)
    }

    /// [`Bvh::any_hit`] over the 4-wide tree.
    pub fn any_hit4(&self, ray: &Ray) -> bool {
        self.any_impl::<_, true>(ray, &mut NoStats)
    }

    /// [`Self::any_hit4`] with the scalar triangle test (the slow twin kept for tests).
    pub fn any_hit_scalar(&self, ray: &Ray) -> bool {
        self.any_impl::<_, false>(ray, &mut NoStats)
    }

    /// [`Bvh::all_hits`] over the 4-wide tree.
    pub fn all_hits4(&self, ray: &Ray, out: &mut Vec<Hit>) {
        self.all_impl(ray, out, &mut NoStats)
    }
}

/// Sorts hits by `t`, then by primitive (allocation-free).
pub(crate) fn sort_hits(hits: &mut [Hit]) {
    hits.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
}

/// Sorts hits as [`sort_hits`] and drops repeats of a primitive: a triangle that spatial
/// splits put in several leaves is hit at the same `t` in each (same triangle, same ray),
/// so its repeats end up next to each other.
pub(crate) fn sort_dedup_hits(hits: &mut Vec<Hit>) {
    sort_hits(hits);
    hits.dedup_by(|a, b| a.prim == b.prim && a.t == b.t);
}

/// Lane `i` of block `b`, which the SIMD test left to the scalar watertight test (its
/// exact-zero lanes): tested against `best`'s limit and offered to it.
#[inline(always)]
fn offer_exact(r4: &Tri4Ray, b: &Tri4, i: usize, best: &mut Best, t_max: &mut f32) {
    let (p0, p1, p2) = (b.vertex(i, 0), b.vertex(i, 1), b.vertex(i, 2));
    if let Some(h) = r4.wt.intersect_within(p0, p1, p2, best.limit(*t_max)) {
        best.offer(h.t, b.tri[i], h.u, h.v, t_max);
    }
}

/// The closest hit so far: `(t, primitive id)` compared lexicographically, so that on an exact
/// `t` tie the scene's lowest triangle index wins whatever the tree and the visiting order (the
/// rule of `reference::brute_force_closest`; copies of one triangle give the same hit record).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Best {
    pub t: f32,
    pub tri: u32,
    pub u: f32,
    pub v: f32,
}

impl Best {
    #[inline(always)]
    pub fn new() -> Self {
        Self {
            t: f32::INFINITY,
            tri: u32::MAX,
            u: 0.0,
            v: 0.0,
        }
    }

    /// The exclusive upper bound for the next triangle test, given the traversal's `t_max`
    /// (the ray's `t_max`, or `best.t` once something was hit): once a hit exists, a triangle
    /// at exactly the same `t` must still be tested for the tie-break, so the bound is the next
    /// float above.
    #[inline(always)]
    pub fn limit(&self, t_max: f32) -> f32 {
        if self.tri == u32::MAX {
            t_max
        } else {
            t_max.next_up()
        }
    }

    /// Offers a hit with `t` below [`Self::limit`]; keeps it if it is closer, or as close with a
    /// lower primitive id, and then shrinks `t_max` to it.
    #[inline(always)]
    pub fn offer(&mut self, t: f32, tri: u32, u: f32, v: f32, t_max: &mut f32) {
        if t < self.t || (t == self.t && tri < self.tri) || self.tri == u32::MAX {
            *self = Best { t, tri, u, v };
            *t_max = t;
        }
    }

    #[inline(always)]
    pub fn hit(&self) -> Option<Hit> {
        (self.tri != u32::MAX).then_some(Hit {
            prim: self.tri,
            t: self.t,
            u: self.u,
            v: self.v,
        })
    }
}

/// Pops stack entries (`near t` bits in the high half, the node in the low half) until one can
/// still hold a hit closer than `t_max` (with the robust far scaling), and returns its node;
/// `None` when the stack runs empty. Entries below `*sp` must have been written.
#[inline(always)]
pub(crate) fn pop_closer(stack: &[MaybeUninit<u64>], sp: &mut usize, t_max: f32) -> Option<u32> {
    while *sp > 0 {
        *sp -= 1;
        // SAFETY: the caller wrote every entry below `*sp` (the pushes of its traversal).
        let e = unsafe { stack.get_unchecked(*sp).assume_init() };
        if f32::from_bits((e >> 32) as u32) <= t_max * ROBUST_FAR_SCALE {
            return Some(e as u32);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::ray_ok;
    use glam::Vec3;
    use parallax_core::Ray;

    /// `ray_ok` against its reference on every special value in every field, alone and in
    /// pairs of fields (zeros, subnormals whose squares underflow, the largest finite values,
    /// infinities, NaN).
    #[test]
    fn ray_ok_matches_reference() {
        let vals = [
            0.0,
            -0.0,
            1.0,
            -2.5,
            1e-30,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let base = [0.5, -1.0, 2.0, 0.3, -0.4, 0.8, 0.0, 10.0];
        let ray = |f: &[f32; 8]| {
            Ray::segment(
                Vec3::new(f[0], f[1], f[2]),
                Vec3::new(f[3], f[4], f[5]),
                f[6],
                f[7],
            )
        };
        let (mut ok, mut not_ok) = (0, 0);
        for i in 0..8 {
            for j in i..8 {
                for &a in &vals {
                    for &b in &vals {
                        let mut f = base;
                        f[i] = a;
                        f[j] = b;
                        let r = ray(&f);
                        let reference = r.is_valid() && r.t_min <= r.t_max;
                        assert_eq!(ray_ok(&r), reference, "{f:?}");
                        if reference { ok += 1 } else { not_ok += 1 }
                    }
                }
            }
        }
        assert!(ok > 1000 && not_ok > 1000, "{ok} / {not_ok}");
    }
}
