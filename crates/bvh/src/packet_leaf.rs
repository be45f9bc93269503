//! The leaf step of the packet traversals (`packet8.rs`, `packet64.rs`): a leaf's triangles
//! against the rays of a packet that enter it, with the watertight test of Woop, Benthin & Wald
//! 2013 run over 16 rays per triangle (one SIMD lane per ray).
//!
//! - **Per block, then per triangle.** When all rays share the axis permutation `k` of the
//!   watertight test, each leaf block ([`Tri4`], four triangles) is first laid out for the
//!   packet ([`block_lanes`]): `q[v][i]` holds coordinate `k[i]` of vertex `v` of the block's
//!   four triangles and, when every ray has the same origin `o` bit for bit (a pinhole camera's
//!   tile), that coordinate minus `o[k[i]]`. The subtraction `p - o` of the shear
//!   (`shear_vertex`) is then one f32 operation for all rays, done here for four triangles in
//!   one SSE lane operation (IEEE lanes round as scalar f32: the same values). Each triangle
//!   then broadcasts its nine values and runs the rest over 16 rays: the shear's multiply and
//!   subtract, the edge functions and, only when some lane is inside, `z = sz az` and the
//!   distance. (Before, every triangle copied its nine coordinates into an array, indexed it by
//!   the permutation, subtracted the origin in scalar and broadcast each result: about 45 of
//!   its ~100 AVX-512 instructions; notes, 2026-12-02 "cheaper packet triangle step".)
//! - Lanes with an exactly-zero edge function go to the scalar test (its double-precision
//!   recompute and edge tie-break). The others are inside when `u, v, w` share their sign bit
//!   (`Lanes16::same_sign`: one `vpternlogd` and one compare with AVX-512), which is the
//!   scalar test's "no negative and positive edge function together" for nonzero values. A
//!   lane with a NaN edge function may be classified otherwise than by the scalar compares,
//!   but its `det` and `t` are then NaN, and a NaN `t` is never accepted (`t > t_min` is
//!   false), as in the scalar test: only the work done differs.
//! - A packet whose rays differ in the permutation tests the leaf ray by ray, four triangles per
//!   test (`tri4.rs`). With a common permutation the lanes are used however few rays enter the
//!   leaf: a triangle over 16 lanes costs less than a 4-triangle block per ray with its set-up
//!   (the threshold was 4 rays; 0, 2 and 4 measured in the notes, 2026-12-02).
//!
//! **Invariant:** every lane performs the f32 operations of
//! [`WatertightRay::intersect_within`] on the same operands (`a = p - o`, `x = a[kx] - sx
//! a[kz]`, ... in that order; Rust does not contract to FMA), so each ray's `t, u, v` and its
//! hit decisions are bit for bit the single-ray ones; each ray keeps the lexicographic minimum
//! of `(t, triangle index)` (`Best::offer`).

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::WatertightRay;

use crate::bvh::Bvh;
use crate::lanes16::Lanes16;
use crate::packet8::Packet;
use crate::stats::NoStats;
use crate::tri4::{Tri4, Tri4Ray, blocks_for, lane_mask};

/// A block laid out for one packet: `q[v][i][j]` is coordinate `k[i]` of vertex `v` of the
/// block's triangle `j`, minus the packet's shared origin's `o[k[i]]` with `SHARED`.
type BlockLanes = [[[f32; 4]; 3]; 3];

/// [`BlockLanes`] of block `b` for permutation `k` (each `< 3`) and shared origin `o` (used
/// with `SHARED` only).
#[inline(always)]
fn block_lanes<const SHARED: bool>(b: &Tri4, k: [usize; 3], o: [f32; 3]) -> BlockLanes {
    let mut q = [[[0.0; 4]; 3]; 3];
    for (qv, pv) in q.iter_mut().zip(&b.p) {
        for (qi, &a) in qv.iter_mut().zip(&k) {
            let c = pv[a];
            *qi = if SHARED {
                (c - Vec4::splat(o[a])).to_array()
            } else {
                c.to_array()
            };
        }
    }
    q
}

impl Packet {
    /// Vertex `v` (its row `q` of [`BlockLanes`]) of triangle `j` in each ray's sheared frame,
    /// without the `z` product: `(a[kx] - sx a[kz], a[ky] - sy a[kz], a[kz])` with
    /// `a = p - o`, the operations of `shear_vertex`. (A method, not a closure: closures do not
    /// inherit the caller's target features, so their intrinsics would not inline.)
    #[inline(always)]
    fn project<L: Lanes16, const SHARED: bool>(
        &self,
        l: L,
        k: [usize; 3],
        q: &[[f32; 4]; 3],
        j: usize,
    ) -> (L::V, L::V, L::V) {
        let (sx, sy) = (l.load(&self.sx), l.load(&self.sy));
        if SHARED {
            // `p - o` is the same f32 subtraction in every lane: done in `block_lanes`.
            let az = l.splat(q[2][j]);
            let x = l.sub(l.splat(q[0][j]), l.mul(sx, az));
            let y = l.sub(l.splat(q[1][j]), l.mul(sy, az));
            return (x, y, az);
        }
        let [kx, ky, kz] = k;
        let az = l.sub(l.splat(q[2][j]), l.load(&self.org[kz]));
        let x = l.sub(
            l.sub(l.splat(q[0][j]), l.load(&self.org[kx])),
            l.mul(sx, az),
        );
        let y = l.sub(
            l.sub(l.splat(q[1][j]), l.load(&self.org[ky])),
            l.mul(sy, az),
        );
        (x, y, az)
    }

    /// The watertight test of triangle `j` of block `b` (laid out as `q`) against the rays of
    /// `mask` (all sharing the axis permutation `k`), keeping each ray's lexicographically
    /// smallest `(t, primitive id)`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn triangle<L: Lanes16, const SHARED: bool>(
        &mut self,
        l: L,
        rays: &[Ray],
        k: [usize; 3],
        q: &BlockLanes,
        b: &Tri4,
        j: usize,
        mask: u32,
    ) {
        let tri = b.tri[j];
        let (ax, ay, a_z) = self.project::<L, SHARED>(l, k, &q[0], j);
        let (bx, by, b_z) = self.project::<L, SHARED>(l, k, &q[1], j);
        let (cx, cy, c_z) = self.project::<L, SHARED>(l, k, &q[2], j);
        let u = l.sub(l.mul(cx, by), l.mul(cy, bx));
        let v = l.sub(l.mul(ax, cy), l.mul(ay, cx));
        let w = l.sub(l.mul(bx, ay), l.mul(by, ax));
        let zero = l.splat(0.0);
        let exact = (l.eq(u, zero) | l.eq(v, zero) | l.eq(w, zero)) & mask;
        // Without zeros, "not both a negative and a positive edge function" is "one sign
        // bit": `same_sign` (module docs, NaN lanes).
        let inside = l.same_sign(u, v, w) & mask & !exact;
        if inside != 0 {
            let sz = l.load(&self.sz);
            let (az, bz, cz) = (l.mul(sz, a_z), l.mul(sz, b_z), l.mul(sz, c_z));
            let det = l.add(l.add(u, v), w);
            let t_scaled = l.add(l.add(l.mul(u, az), l.mul(v, bz)), l.mul(w, cz));
            let inv = l.div(l.splat(1.0), det);
            let t = l.mul(t_scaled, inv);
            let t_cur = l.load(&self.t_max);
            // Rays with a hit already (`best_tri != u32::MAX`) also take a tie at `t_cur`
            // with a lower primitive id (`Best::limit` / `Best::offer`).
            let has_hit = inside & !l.gt_u32(inside, &self.best_tri, u32::MAX - 1);
            let closer = l.lt(t, t_cur) | (l.eq(t, t_cur) & l.gt_u32(has_hit, &self.best_tri, tri));
            let acc = inside & l.ne(det, zero) & l.gt(t, l.load(&self.t_min)) & closer;
            if acc != 0 {
                let t_new = l.select(acc, t, t_cur);
                l.store(t_new, &mut self.t_max);
                let bu = l.select(acc, l.mul(v, inv), l.load(&self.best_u));
                l.store(bu, &mut self.best_u);
                let bv = l.select(acc, l.mul(w, inv), l.load(&self.best_v));
                l.store(bv, &mut self.best_v);
                l.store_u32_masked(acc, &mut self.best_tri, tri);
            }
        }
        let mut m = exact;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let mut best = self.best(i);
            let mut t_max = self.t_max.0[i];
            // SAFETY: rays of the mask are valid, and valid rays were initialised.
            let wt = WatertightRay::new(&rays[i]);
            let (p0, p1, p2) = (b.vertex(j, 0), b.vertex(j, 1), b.vertex(j, 2));
            if let Some(h) = wt.intersect_within(p0, p1, p2, best.limit(t_max)) {
                best.offer(h.t, tri, h.u, h.v, &mut t_max);
            }
            self.set_best(i, best, t_max);
        }
    }
}

impl Bvh {
    /// The leaf of `count` triangles from block `first` against the rays `mask` of `p`
    /// (module docs).
    #[inline(always)]
    pub(crate) fn packet_leaf<L: Lanes16>(
        &self,
        l: L,
        p: &mut Packet,
        rays: &[Ray],
        first: u32,
        count: u32,
        mask: u32,
    ) {
        if let Some(k) = p.perm {
            match p.org0 {
                Some(o) => self.leaf_lanes::<L, true>(l, p, rays, k, o, first, count, mask),
                None => self.leaf_lanes::<L, false>(l, p, rays, k, [0.0; 3], first, count, mask),
            }
            return;
        }
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let mut best = p.best(i);
            let mut t_max = p.t_max.0[i];
            // SAFETY: rays of the mask are valid, and valid rays were initialised.
            let r4 = Tri4Ray::new(WatertightRay::new(&rays[i]));
            self.leaf_closest(&r4, first, count, &mut t_max, &mut best, &mut NoStats);
            p.set_best(i, best, t_max);
        }
    }

    /// The 16-lane test of every triangle of the leaf, block by block ([`block_lanes`]).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn leaf_lanes<L: Lanes16, const SHARED: bool>(
        &self,
        l: L,
        p: &mut Packet,
        rays: &[Ray],
        k: [usize; 3],
        o: [f32; 3],
        first: u32,
        count: u32,
        mask: u32,
    ) {
        assert!(k.iter().all(|&a| a < 3));
        for kb in 0..blocks_for(count) {
            let b = &self.blocks[(first + kb) as usize];
            let q = block_lanes::<SHARED>(b, k, o);
            let lanes = lane_mask(count, kb);
            for j in 0..4 {
                if lanes >> j & 1 != 0 {
                    p.triangle::<L, SHARED>(l, rays, k, &q, b, j, mask);
                }
            }
        }
    }
}
