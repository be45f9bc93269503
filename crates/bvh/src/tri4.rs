//! Leaf triangles in SIMD-friendly blocks of four, and the watertight test of Woop, Benthin &
//! Wald 2013 run on four triangles at once for one ray.
//!
//! ## Layout
//!
//! A leaf of `count` triangles owns `ceil(count / 4)` consecutive [`Tri4`] blocks; lane `l` of
//! block `k` of the leaf is its triangle `4 k + l`. A block stores the nine coordinates of its
//! triangles as `[vertex][axis]` lanes (`p[0][0]` = the x of vertex 0 of all four triangles), so
//! the ray's axis permutation `(kx, ky, kz)` picks whole `Vec4`s by address, with no dynamic
//! `Vec3` component index in the hot code. `tri[l]` is the scene's index of the lane's triangle
//! (its primitive id, the same for every copy of a triangle split by spatial splits; `u32::MAX`
//! for padding lanes, whose coordinates are zero and which the leaf's count masks off), so the
//! closest-hit tie rule on `(t, tri)` is the tree-independent `(t, primitive id)`. 160 bytes per block, as Embree's `Triangle4`
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
    /// The scene's triangle index (primitive id) per lane, `u32::MAX` for padding.
    pub tri: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Tri4>() == 160);

impl Tri4 {
    /// A block of four padding lanes.
    pub const EMPTY: Tri4 = Tri4 {
        p: [[Vec4::ZERO; 3]; 3],
        tri: [u32::MAX; 4],
    };

    /// Sets lane `l` to triangle `t`, the scene's triangle `prim`.
    #[inline]
    pub fn set(&mut self, l: usize, t: &Tri, prim: u32) {
        for (v, p) in [t.p0, t.p1, t.p2].into_iter().enumerate() {
            self.p[v][0][l] = p.x;
            self.p[v][1][l] = p.y;
            self.p[v][2][l] = p.z;
        }
        self.tri[l] = prim;
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

/// A ray prepared for the 4-triangle test: the permutation and shear of Woop et al. 2013, §3
/// ([`WatertightRay`]) and the origin in permuted order (`org[i]` = origin axis `k[i]`), all
/// scalars: the tests broadcast them into lanes where they use them (a broadcast load costs
/// what a vector load does, and the per-ray set-up stores 4 bytes per value, not 16).
#[derive(Clone, Copy, Debug)]
pub struct Tri4Ray {
    /// `kx, ky, kz < 3` (checked once in [`Tri4Ray::new`] / [`Tri4Ray::new_avx2`]).
    pub wt: WatertightRay,
    org: [f32; 3],
}

impl Tri4Ray {
    #[inline(always)]
    pub fn new(wt: WatertightRay) -> Self {
        let o = wt.origin.to_array();
        assert!(wt.kx < 3 && wt.ky < 3 && wt.kz < 3);
        Self {
            org: [o[wt.kx], o[wt.ky], o[wt.kz]],
            wt,
        }
    }

    /// `Tri4Ray::new(WatertightRay::new(ray))` with the permutation applied in registers
    /// (`vpermilps` on the direction and the origin, no stack array indexed by `k`) and the
    /// three shear constants by one division `(d[kx], d[ky], 1) / d[kz]` (the same IEEE
    /// quotients as the scalar divisions). Bit-identical fields (tested below).
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    pub unsafe fn new_avx2(ray: &parallax_core::Ray) -> Self {
        use std::arch::x86_64::*;
        let (d, o) = (ray.dir, ray.origin);
        let kz = parallax_core::math::dominant_axis(d);
        // SAFETY: AVX is available (caller); register operations only.
        unsafe {
            let d4 = _mm_setr_ps(d.x, d.y, d.z, 0.0);
            let o4 = _mm_setr_ps(o.x, o.y, o.z, 0.0);
            // `d[kz] < 0.0` from the lanes' compare mask (a NaN lane compares false).
            let neg = _mm_movemask_ps(_mm_cmplt_ps(d4, _mm_setzero_ps())) as usize;
            let swap = (neg >> kz) & 1 != 0;
            let kx0 = (kz + 1) % 3;
            let ky0 = (kx0 + 1) % 3;
            let (kx, ky) = if swap { (ky0, kx0) } else { (kx0, ky0) };
            assert!(kx < 3 && ky < 3 && kz < 3);
            let ctrl = _mm_setr_epi32(kx as i32, ky as i32, kz as i32, kz as i32);
            let pd = _mm_permutevar_ps(d4, ctrl);
            let po = _mm_permutevar_ps(o4, ctrl);
            let num = _mm_blend_ps::<0b0100>(pd, _mm_set1_ps(1.0));
            let s = _mm_div_ps(num, _mm_permute_ps::<0b1010_1010>(pd));
            let mut sv = [0.0f32; 4];
            _mm_storeu_ps(sv.as_mut_ptr(), s);
            let mut ov = [0.0f32; 4];
            _mm_storeu_ps(ov.as_mut_ptr(), po);
            Self {
                wt: WatertightRay {
                    origin: o,
                    kx,
                    ky,
                    kz,
                    sx: sv[0],
                    sy: sv[1],
                    sz: sv[2],
                    t_min: ray.t_min,
                    t_max: ray.t_max,
                },
                org: [ov[0], ov[1], ov[2]],
            }
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
        let wt = &self.wt;
        let [kx, ky, kz] = [wt.kx, wt.ky, wt.kz];
        let o = [
            L::splat(self.org[0]),
            L::splat(self.org[1]),
            L::splat(self.org[2]),
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
        let wt = &self.wt;
        let [kx, ky, kz] = [wt.kx, wt.ky, wt.kz];
        let shear = [wt.sx, wt.sy, wt.sz].map(Vec4::splat);
        let org = self.org.map(Vec4::splat);
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
            shear_vertex(q, org, shear)
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
        let in_range = (d.t.cmpgt(Vec4::splat(wt.t_min)) & d.t.cmplt(Vec4::splat(t_lim))).bitmask();
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

    /// `Tri4Ray::new_avx2` against `Tri4Ray::new(WatertightRay::new(ray))`: every field
    /// bit-identical, on directions with zero, negative-zero and tied components (every
    /// branch of the permutation) and random ones. Returns how many rays took each `kz` and
    /// how many swapped `kx, ky`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn check_new_avx2() -> ([u32; 3], u32) {
        let mut rng = Rng::new(23, 5);
        let special = [0.0f32, -0.0, 1.0, -1.0, 0.5, -0.5, 3.0, -3.0, 1e-30, -1e-30];
        let (mut per_kz, mut swaps) = ([0u32; 3], 0u32);
        for i in 0..20_000 {
            let mut c = || {
                if i % 2 == 0 {
                    special[rng.next_bounded(special.len() as u32) as usize]
                } else {
                    rng.next_f32() * 4.0 - 2.0
                }
            };
            let d = Vec3::new(c(), c(), c());
            let o = Vec3::new(c() * 7.0, c() - 1.0, c() * 0.3);
            let mut ray = Ray::new(o, d);
            ray.t_min = rng.next_f32();
            ray.t_max = 10.0 * rng.next_f32();
            let a = Tri4Ray::new(WatertightRay::new(&ray));
            // SAFETY: AVX is enabled for this function.
            let b = unsafe { Tri4Ray::new_avx2(&ray) };
            let (wa, wb) = (&a.wt, &b.wt);
            assert_eq!([wa.kx, wa.ky, wa.kz], [wb.kx, wb.ky, wb.kz], "{ray:?}");
            let bits = |w: &WatertightRay, org: [f32; 3]| {
                let f = [
                    w.origin.x, w.origin.y, w.origin.z, w.sx, w.sy, w.sz, w.t_min, w.t_max,
                ];
                (f.map(f32::to_bits), org.map(f32::to_bits))
            };
            assert_eq!(bits(wa, a.org), bits(wb, b.org), "{ray:?}");
            per_kz[wa.kz] += 1;
            swaps += (wa.kx != (wa.kz + 1) % 3) as u32;
        }
        (per_kz, swaps)
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn new_avx2_matches_new() {
        if !std::is_x86_feature_detected!("avx") {
            return;
        }
        // SAFETY: AVX detected above.
        let (per_kz, swaps) = unsafe { check_new_avx2() };
        assert!(per_kz.iter().all(|&n| n > 4000), "{per_kz:?}");
        assert!((7000..13_000).contains(&swaps), "{swaps}");
    }
}
