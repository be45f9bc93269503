//! Leaf triangles in SIMD-friendly blocks of four, and the watertight test of Woop, Benthin &
//! Wald 2013 run on four triangles at once for one ray.
//!
//! ## Layout
//!
//! A leaf of `count` triangles owns `ceil(count / 4)` consecutive [`Tri4`] blocks; lane `l` of
//! block `k` of the leaf is its triangle `4 k + l`. A block stores the nine coordinates of its
//! triangles as `[vertex][axis]` lanes (`p[0][0]` = the x of vertex 0 of all four triangles), so
//! the ray's axis permutation `(kx, ky, kz)` picks whole `Vec4`s by address, with no dynamic
//! `Vec3` component index in the hot code. `tri[l]` is the index of the lane's triangle in
//! [`crate::Bvh::triangles`] (`u32::MAX` for padding lanes; padding coordinates are zero and the
//! lane is masked off by the leaf's count). 160 bytes per block, as Embree's `Triangle4`
//! (176 bytes with precomputed edges), 32-byte aligned: 160 = 5 x 32, so every block of the
//! array spans exactly three cache lines (16-byte alignment let every other block straddle
//! four).
//!
//! ## Exactness
//!
//! [`Tri4Ray::intersect`] performs, lane by lane, the very f32 operations of
//! [`WatertightRay::intersect_within`] (projection `a[kx] - sx * a[kz]`, edge functions
//! `u = cx by - cy bx` ..., `det = (u + v) + w`, `t = (u az + v bz + w cz) * (1 / det)`); IEEE
//! SSE lanes round exactly like scalar f32 and Rust never contracts to FMA, so every lane
//! computes bit-identical `u, v, w, t`. Lanes where an edge function is exactly `0.0` need the
//! double-precision recompute and the edge tie-break rule: they are reported in a mask and the
//! caller runs the scalar [`WatertightRay::intersect_within`] on them. `Tri4Ray::intersect2`
//! runs the same generic arithmetic on the two blocks of a leaf at once in eight lanes
//! (`lanes8.rs`: one AVX register, or the portable `F8`), lane for lane the bits of the two
//! 4-lane tests (tested below against them, on grid coordinates where many edge functions are
//! exactly zero). glam's `Vec4` is SSE2 on
//! x86_64 and plain scalar f32 elsewhere (the portable fallback, same arithmetic).

use glam::{Vec3, Vec4};
use parallax_core::math::{WatertightRay, shear_vertex, watertight_lanes};

use crate::lanes8::Pair8;

use crate::tri::Tri;

/// Four triangles, structure of arrays (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct Tri4 {
    /// `p[vertex][axis]`, lane `l` = triangle `l` of the block.
    pub p: [[Vec4; 3]; 3],
    /// Index into the BVH's triangle array per lane, `u32::MAX` for padding.
    pub tri: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Tri4>() == 160);

impl Tri4 {
    /// A block of four padding lanes.
    pub const EMPTY: Tri4 = Tri4 {
        p: [[Vec4::ZERO; 3]; 3],
        tri: [u32::MAX; 4],
    };

    /// Sets lane `l` to triangle `t`, index `index` in the BVH's triangle array.
    #[inline]
    pub fn set(&mut self, l: usize, t: &Tri, index: u32) {
        for (v, p) in [t.p0, t.p1, t.p2].into_iter().enumerate() {
            self.p[v][0][l] = p.x;
            self.p[v][1][l] = p.y;
            self.p[v][2][l] = p.z;
        }
        self.tri[l] = index;
    }

    /// Vertex `v` of lane `l` (the same f32 values the block was filled with).
    #[inline(always)]
    pub fn vertex(&self, l: usize, v: usize) -> Vec3 {
        Vec3::new(self.p[v][0][l], self.p[v][1][l], self.p[v][2][l])
    }
}

/// Row `axis` of vertex `v` of two blocks as one lane value (lanes `0..4` from `b0`).
/// `v < 3`, `axis < 3` (the callers' permutation, checked in [`Tri4Ray::new`]).
#[inline(always)]
fn pair_row<L: Pair8>(b0: &Tri4, b1: &Tri4, v: usize, axis: usize) -> L {
    debug_assert!(v < 3 && axis < 3);
    // SAFETY: `v < 3` and `axis < 3` (above) index `p: [[Vec4; 3]; 3]`.
    unsafe {
        L::halves(
            b0.p.get_unchecked(v).get_unchecked(axis),
            b1.p.get_unchecked(v).get_unchecked(axis),
        )
    }
}

/// Number of blocks a leaf of `count` triangles occupies.
#[inline(always)]
pub const fn blocks_for(count: u32) -> u32 {
    count.div_ceil(4)
}

/// Bit mask of the lanes of block `k` of a leaf of `count` triangles that hold triangles.
#[inline(always)]
pub fn lane_mask(count: u32, k: u32) -> u32 {
    let left = count - 4 * k;
    if left >= 4 { 0xF } else { (1 << left) - 1 }
}

/// Lane-wise results of [`Tri4Ray::intersect`].
#[derive(Clone, Copy, Debug)]
pub struct Tri4Hits {
    /// Lanes hit with `t_min < t < t_lim` (decided in f32, no edge function exactly zero).
    pub hit: u32,
    /// Lanes that need the scalar test (an edge function is exactly zero).
    pub exact: u32,
    pub t: Vec4,
    pub u: Vec4,
    pub v: Vec4,
}

/// Lane-wise results of [`Tri4Ray::intersect2`]: lanes `0..4` are block 0, `4..8` block 1.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri8Hits {
    /// Lanes hit with `t_min < t < t_lim` (decided in f32, no edge function exactly zero).
    pub hit: u32,
    /// Lanes that need the scalar test (an edge function is exactly zero).
    pub exact: u32,
    pub t: [f32; 8],
    pub u: [f32; 8],
    pub v: [f32; 8],
}

/// A ray prepared for the 4-triangle test: the permutation and shear of Woop et al. 2013, §3,
/// splatted into lanes, the origin already in permuted order (`org[i]` = origin axis `k[i]`).
#[derive(Clone, Copy, Debug)]
pub struct Tri4Ray {
    pub wt: WatertightRay,
    org: [Vec4; 3],
    /// `[kx, ky, kz]`, each `< 3` (checked once in [`Tri4Ray::new`]).
    k: [usize; 3],
    sx: Vec4,
    sy: Vec4,
    sz: Vec4,
    t_min: Vec4,
}

impl Tri4Ray {
    #[inline(always)]
    pub fn new(wt: WatertightRay) -> Self {
        let o = wt.origin.to_array();
        assert!(wt.kx < 3 && wt.ky < 3 && wt.kz < 3);
        Self {
            org: [
                Vec4::splat(o[wt.kx]),
                Vec4::splat(o[wt.ky]),
                Vec4::splat(o[wt.kz]),
            ],
            k: [wt.kx, wt.ky, wt.kz],
            sx: Vec4::splat(wt.sx),
            sy: Vec4::splat(wt.sy),
            sz: Vec4::splat(wt.sz),
            t_min: Vec4::splat(wt.t_min),
            wt,
        }
    }

    /// [`Self::intersect`] on two blocks at once, in eight lanes `L` (`lanes8.rs`: one AVX
    /// register in the AVX2 kernel): lane `l < 4` is lane `l` of `b0`, lane `l + 4` lane `l`
    /// of `b1`; `mask` has eight bits. Per lane the very f32 operations of [`Self::intersect`]
    /// (the same generic `shear_vertex`, `watertight_lanes` and `distance`), so `t, u, v` are
    /// bit-identical to those of the two 4-lane tests. No closures (module docs of
    /// `lanes8.rs`).
    #[inline(always)]
    pub(crate) fn intersect2<L: Pair8>(
        &self,
        b0: &Tri4,
        b1: &Tri4,
        mask: u32,
        t_lim: f32,
    ) -> Tri8Hits {
        let [kx, ky, kz] = self.k;
        let wt = &self.wt;
        let o = [
            L::splat(self.org[0].x),
            L::splat(self.org[1].x),
            L::splat(self.org[2].x),
        ];
        let shear = [L::splat(wt.sx), L::splat(wt.sy), L::splat(wt.sz)];
        // `kx, ky, kz < 3` (`new`): in bounds.
        let va = shear_vertex(
            [
                pair_row(b0, b1, 0, kx),
                pair_row(b0, b1, 0, ky),
                pair_row(b0, b1, 0, kz),
            ],
            o,
            shear,
        );
        let vb = shear_vertex(
            [
                pair_row(b0, b1, 1, kx),
                pair_row(b0, b1, 1, ky),
                pair_row(b0, b1, 1, kz),
            ],
            o,
            shear,
        );
        let vc = shear_vertex(
            [
                pair_row(b0, b1, 2, kx),
                pair_row(b0, b1, 2, ky),
                pair_row(b0, b1, 2, kz),
            ],
            o,
            shear,
        );
        let r = watertight_lanes::<L>(va, vb, vc);
        let exact = r.exact & mask;
        if r.same_sign & mask & !exact == 0 {
            // No lane can hit: skip the division (the common case).
            return Tri8Hits {
                hit: 0,
                exact,
                t: [0.0; 8],
                u: [0.0; 8],
                v: [0.0; 8],
            };
        }
        let d = r.distance(va[2], vb[2], vc[2]);
        let in_range = L::bits(L::and(d.t.gt(L::splat(wt.t_min)), d.t.lt(L::splat(t_lim))));
        Tri8Hits {
            hit: r.same_sign & d.nonzero & in_range & mask & !exact,
            exact,
            t: d.t.to_array(),
            u: (r.e[1] * d.inv_det).to_array(),
            v: (r.e[2] * d.inv_det).to_array(),
        }
    }

    /// The watertight test on the lanes `mask` of `b` for `t` in `(t_min, t_lim)`. Lanes with
    /// an exactly-zero edge function are only reported in `exact` (module docs).
    ///
    /// ```text
    /// a = p - o;  A = (a[kx] - sx a[kz], a[ky] - sy a[kz], sz a[kz])   per vertex A, B, C
    /// u = Cx By - Cy Bx,  v = Ax Cy - Ay Cx,  w = Bx Ay - By Ax
    /// inside = all of u, v, w >= 0 or all <= 0;  det = u + v + w != 0
    /// t = (u Az + v Bz + w Cz) * (1 / det)
    /// ```
    #[inline(always)]
    pub fn intersect(&self, b: &Tri4, mask: u32, t_lim: f32) -> Tri4Hits {
        let [kx, ky, kz] = self.k;
        let shear = [self.sx, self.sy, self.sz];
        let proj = |v: usize| {
            let p = &b.p[v];
            // SAFETY: `kx, ky, kz < 3` (`new`).
            let q = unsafe {
                [
                    *p.get_unchecked(kx),
                    *p.get_unchecked(ky),
                    *p.get_unchecked(kz),
                ]
            };
            shear_vertex(q, self.org, shear)
        };
        let (va, vb, vc) = (proj(0), proj(1), proj(2));
        let r = watertight_lanes(va, vb, vc);
        let exact = r.exact & mask;
        if r.same_sign & mask & !exact == 0 {
            // No lane can hit: skip the division (the common case).
            let zero = Vec4::ZERO;
            return Tri4Hits {
                hit: 0,
                exact,
                t: zero,
                u: zero,
                v: zero,
            };
        }
        let d = r.distance(va[2], vb[2], vc[2]);
        let in_range = (d.t.cmpgt(self.t_min) & d.t.cmplt(Vec4::splat(t_lim))).bitmask();
        Tri4Hits {
            hit: r.same_sign & d.nonzero & in_range & mask & !exact,
            exact,
            t: d.t,
            u: r.e[1] * d.inv_det,
            v: r.e[2] * d.inv_det,
        }
    }
}

#[cfg(test)]
mod pair_tests {
    use glam::Vec3;
    use parallax_core::Ray;
    use parallax_core::math::WatertightRay;
    use parallax_core::sampling::Rng;
    use parallax_core::simd::F8;

    use super::{Tri4, Tri4Ray};
    use crate::lanes8::Pair8;
    use crate::tri::Tri;

    /// Coordinates on a coarse grid (many exactly-zero edge functions) or anywhere.
    fn coord(rng: &mut Rng, grid: bool) -> f32 {
        if grid {
            rng.next_bounded(5) as f32 - 2.0
        } else {
            rng.next_f32() * 4.0 - 2.0
        }
    }

    /// `intersect2::<L>` against the two 4-lane tests it replaces: the same hit and exact
    /// masks, and bit-identical `t, u, v` on hit lanes. Returns the numbers of hit and exact
    /// lanes seen.
    fn check<L: Pair8>() -> (u32, u32) {
        let mut rng = Rng::new(17, 3);
        let (mut hits, mut exact) = (0, 0);
        for case in 0..4000 {
            let grid = case % 2 == 0;
            let mut blocks = [Tri4::EMPTY; 2];
            for (k, b) in blocks.iter_mut().enumerate() {
                for l in 0..4 {
                    let mut v = || {
                        let (x, y) = (coord(&mut rng, grid), coord(&mut rng, grid));
                        Vec3::new(x, y, coord(&mut rng, grid))
                    };
                    let t = Tri::new([v(), v(), v()]);
                    b.set(l, &t, (4 * k + l) as u32);
                }
            }
            let o = Vec3::new(coord(&mut rng, grid), coord(&mut rng, grid), -5.0);
            let d = if grid {
                [Vec3::Z, Vec3::X, Vec3::new(0.0, -1.0, 1.0)][case / 2 % 3]
            } else {
                Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 1.0)
            };
            let r4 = Tri4Ray::new(WatertightRay::new(&Ray::new(o, d)));
            let count = 5 + rng.next_bounded(4);
            let mask = 0xF | ((1 << (count - 4)) - 1) << 4;
            let t_lim = if case % 3 == 0 { 6.0 } else { f32::INFINITY };
            let h = r4.intersect2::<L>(&blocks[0], &blocks[1], mask, t_lim);
            for (k, block) in blocks.iter().enumerate() {
                let q = r4.intersect(block, mask >> (4 * k) & 0xF, t_lim);
                assert_eq!(h.hit >> (4 * k) & 0xF, q.hit, "case {case} block {k} hit");
                assert_eq!(
                    h.exact >> (4 * k) & 0xF,
                    q.exact,
                    "case {case} block {k} exact"
                );
                for l in 0..4 {
                    if q.hit >> l & 1 != 0 {
                        let i = 4 * k + l;
                        assert_eq!(h.t[i].to_bits(), q.t[l].to_bits(), "case {case} t {i}");
                        assert_eq!(h.u[i].to_bits(), q.u[l].to_bits(), "case {case} u {i}");
                        assert_eq!(h.v[i].to_bits(), q.v[l].to_bits(), "case {case} v {i}");
                    }
                }
            }
            hits += h.hit.count_ones();
            exact += h.exact.count_ones();
        }
        (hits, exact)
    }

    #[test]
    fn pair_test_matches_two_block_tests_portable() {
        let (hits, exact) = check::<F8>();
        assert!(
            hits > 500 && exact > 2000,
            "{hits} hits, {exact} exact lanes"
        );
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn pair_test_matches_two_block_tests_avx2() {
        if !std::is_x86_feature_detected!("avx2") {
            return;
        }
        #[target_feature(enable = "avx2")]
        unsafe fn run() -> (u32, u32) {
            check::<crate::lanes8::A8>()
        }
        // SAFETY: AVX2 detected above.
        let (hits, exact) = unsafe { run() };
        assert!(
            hits > 500 && exact > 2000,
            "{hits} hits, {exact} exact lanes"
        );
    }
}
