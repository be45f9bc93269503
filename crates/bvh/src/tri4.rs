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
//! caller runs the scalar [`WatertightRay::intersect_within`] on them. glam's `Vec4` is SSE2 on
//! x86_64 and plain scalar f32 elsewhere (the portable fallback, same arithmetic).

use glam::{Vec3, Vec4};
use parallax_core::math::{WatertightRay, shear_vertex, watertight_lanes};

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
