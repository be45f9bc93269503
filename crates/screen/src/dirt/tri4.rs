//! The ray-triangle tests of DIRT's bucket tracing (Vardis et al. 2017, Algorithm 1 lines
//! 10-16: "for each primitive in the bucket ... hit(r, pr_k)"), four triangles at a time: the
//! watertight test of Woop, Benthin & Wald 2013 on SSE lanes (`parallax_core`'s lane kernel,
//! the one the BVH's leaves run), with the scalar test for lanes whose edge function is exactly
//! zero (they need the double-precision recompute and the edge tie-break).
//!
//! **Exactness.** Lane `l` performs the very f32 operations of
//! [`WatertightRay::intersect_within`] on triangle `l` (IEEE lanes, no FMA contraction), so a
//! lane hit has the scalar test's bit-identical `t`, `u`, `v`. The four lanes of a block are
//! tested against one bound (the closest hit before the block) and offered to [`Best`] in
//! lane order; [`Best::offer`] keeps the smallest `t`, ties to the lower id, an order-free
//! rule, so the answer equals the scalar loop's ([`Query::test_scalar`], the slow twin, tested
//! equal in this module's tests).
//!
//! **Corners.** The four triangles' corners are turned into lanes by three 4x4 transposes of
//! unaligned 16-byte loads (`gather`: SSE, the x86_64 baseline; one component at a time
//! elsewhere, the portable twin, tested bit-equal): moves only, so the lanes hold the very
//! corners.
//!
//! **Mailbox.** Triangles tested lately (direct-mapped by id) are skipped: a triangle listed in
//! many cells and buckets along the ray is tested once per stay in its slot. Its answer would
//! be the same again, and it was offered to `best` already, so skipping it is exact.

use glam::{Vec3, Vec4};
use parallax_core::math::{WatertightRay, shear_vertex, watertight_lanes};
use parallax_raster::dirt::DirtTri;

use super::best::{Best, DirtCounters};
use super::view::Isa;

/// Slots of the per-ray mailbox (a power of two).
const MAILBOX: usize = 64;

/// What a walk needs about the ray and its answer so far.
pub(crate) struct Query<'a> {
    pub wt: WatertightRay,
    /// The ray origin's permuted coordinates `(o[kx], o[ky], o[kz])` and the shear, splatted.
    org: [Vec4; 3],
    shear: [Vec4; 3],
    t_min: Vec4,
    pub tris: &'a [DirtTri],
    /// Occlusion query: stop at the first hit.
    pub any: bool,
    pub best: Best,
    pub counters: DirtCounters,
    mailbox: [u32; MAILBOX],
}

impl<'a> Query<'a> {
    pub fn new(wt: WatertightRay, tris: &'a [DirtTri], any: bool) -> Self {
        let o = wt.origin;
        Query {
            org: [
                Vec4::splat(o[wt.kx]),
                Vec4::splat(o[wt.ky]),
                Vec4::splat(o[wt.kz]),
            ],
            shear: [Vec4::splat(wt.sx), Vec4::splat(wt.sy), Vec4::splat(wt.sz)],
            t_min: Vec4::splat(wt.t_min),
            wt,
            tris,
            any,
            best: Best::NONE,
            counters: DirtCounters::default(),
            mailbox: [u32::MAX; MAILBOX],
        }
    }

    /// True when `id` was tested lately (and marks it tested).
    #[inline(always)]
    fn seen(&mut self, id: u32) -> bool {
        let slot = &mut self.mailbox[id as usize & (MAILBOX - 1)];
        if *slot == id {
            return true;
        }
        *slot = id;
        false
    }

    /// Tests the triangles `ids` not tested lately, four at a time; true when an occlusion
    /// query found a hit. `ISA`: the `Isa` of the copy to run (the caller's: the CPU has it);
    /// the same source and results on each.
    #[inline(always)]
    pub fn test<const ISA: u8>(&mut self, ids: &[u32]) -> bool {
        self.test_in::<ISA, u32>(0, ids)
    }

    /// [`Self::test`] on the triangles `base + d` for the entries `d` of `ids` (`u16` list
    /// entries relative to a cell's base, `cells`).
    #[inline(always)]
    pub fn test16<const ISA: u8>(&mut self, base: u32, ids: &[u16]) -> bool {
        self.test_in::<ISA, u16>(base, ids)
    }

    #[inline(always)]
    fn test_in<const ISA: u8, T: Copy + Into<u32>>(&mut self, base: u32, ids: &[T]) -> bool {
        #[cfg(target_arch = "x86_64")]
        {
            // SAFETY: the walk's copies pass their own `Isa`, chosen by `Isa::detect`.
            if ISA == Isa::X86V4 as u8 {
                return unsafe { self.test_v4(base, ids) };
            }
            if ISA == Isa::X86V3 as u8 {
                return unsafe { self.test_v3(base, ids) };
            }
        }
        self.test_baseline(base, ids)
    }

    /// [`Self::test`] for the build's baseline instruction set (the portable twin).
    #[inline(never)]
    fn test_baseline<T: Copy + Into<u32>>(&mut self, base: u32, ids: &[T]) -> bool {
        self.test_body(base, ids)
    }

    /// [`Self::test`] compiled for x86-64-v3 (AVX2, BMI1/2, LZCNT; no FMA).
    ///
    /// # Safety
    /// The CPU must have those features.
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    unsafe fn test_v3<T: Copy + Into<u32>>(&mut self, base: u32, ids: &[T]) -> bool {
        self.test_body(base, ids)
    }

    /// [`Self::test`] compiled for x86-64-v3 and AVX-512 F/VL/BW/DQ.
    ///
    /// # Safety
    /// The CPU must have those features.
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt,avx512f,avx512vl,avx512bw,avx512dq")]
    unsafe fn test_v4<T: Copy + Into<u32>>(&mut self, base: u32, ids: &[T]) -> bool {
        self.test_body(base, ids)
    }

    #[inline(always)]
    fn test_body<T: Copy + Into<u32>>(&mut self, base: u32, ids: &[T]) -> bool {
        let mut block = [0u32; 4];
        let mut n = 0;
        for &d in ids {
            let id = base + d.into();
            if self.seen(id) {
                continue;
            }
            block[n] = id;
            n += 1;
            if n == 4 {
                if self.test4(&block, 4) {
                    return true;
                }
                n = 0;
            }
        }
        n > 0 && self.test4(&block, n)
    }

    /// The slow twin of [`Self::test`]: the scalar test on each triangle in turn.
    #[cfg(test)]
    pub fn test_scalar(&mut self, ids: &[u32]) -> bool {
        for &id in ids {
            if self.seen(id) {
                continue;
            }
            self.counters.tests += 1;
            let tri = &self.tris[id as usize];
            let lim = self.best.limit(self.wt.t_max);
            if let Some(h) = self.wt.intersect_within(tri.p0, tri.p1, tri.p2, lim) {
                self.best.offer(h.t, id, h.u, h.v);
                if self.any {
                    return true;
                }
            }
        }
        false
    }

    /// Tests lanes `0..n` of `ids` (module docs).
    #[inline(always)]
    fn test4(&mut self, ids: &[u32; 4], n: usize) -> bool {
        self.counters.tests += n as u64;
        // Padding lanes repeat lane 0 (masked off below).
        let tri = |l: usize| &self.tris[ids[if l < n { l } else { 0 }] as usize];
        let t = [tri(0), tri(1), tri(2), tri(3)];
        let corners = gather(t);
        let (kx, ky, kz) = (self.wt.kx, self.wt.ky, self.wt.kz);
        let project = |p: &[Vec4; 3]| shear_vertex([p[kx], p[ky], p[kz]], self.org, self.shear);
        let (va, vb, vc) = (
            project(&corners[0]),
            project(&corners[1]),
            project(&corners[2]),
        );
        let r = watertight_lanes(va, vb, vc);
        let mask = (1u32 << n) - 1;
        let exact = r.exact & mask;
        let lim = self.best.limit(self.wt.t_max);
        if r.same_sign & mask & !exact != 0 {
            let d = r.distance(va[2], vb[2], vc[2]);
            let in_range = (d.t.cmpgt(self.t_min) & d.t.cmplt(Vec4::splat(lim))).bitmask();
            let mut hit = r.same_sign & d.nonzero & in_range & mask & !exact;
            if hit != 0 {
                let (tt, u, v) = (
                    d.t.to_array(),
                    (r.e[1] * d.inv_det).to_array(),
                    (r.e[2] * d.inv_det).to_array(),
                );
                while hit != 0 {
                    let l = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    self.best.offer(tt[l], ids[l], u[l], v[l]);
                }
                if self.any {
                    return true;
                }
            }
        }
        let mut m = exact;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let tri = t[l];
            let lim = self.best.limit(self.wt.t_max);
            if let Some(h) = self.wt.intersect_within(tri.p0, tri.p1, tri.p2, lim) {
                self.best.offer(h.t, ids[l], h.u, h.v);
                if self.any {
                    return true;
                }
            }
        }
        false
    }
}

/// The corners of four triangles as lanes, `[corner][axis]` (lane `l`: triangle `t[l]`).
#[inline(always)]
fn gather(t: [&DirtTri; 4]) -> [[Vec4; 3]; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        gather_sse(t)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        gather_scalar(t)
    }
}

/// [`gather`] one component at a time (the portable twin).
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn gather_scalar(t: [&DirtTri; 4]) -> [[Vec4; 3]; 3] {
    let soa = |corner: fn(&DirtTri) -> Vec3| {
        let p = t.map(corner);
        [
            Vec4::new(p[0].x, p[1].x, p[2].x, p[3].x),
            Vec4::new(p[0].y, p[1].y, p[2].y, p[3].y),
            Vec4::new(p[0].z, p[1].z, p[2].z, p[3].z),
        ]
    };
    [soa(|t| t.p0), soa(|t| t.p1), soa(|t| t.p2)]
}

/// [`gather`] as three 4x4 transposes of unaligned loads (SSE, part of the x86_64 baseline:
/// no run-time dispatch needed): floats 0-3 of each triangle hold `p0` (and `p1.x`), floats
/// 3-6 `p1` (and `p2.x`), floats 5-8 `p1.z` and `p2`. Moves only: bit-identical to
/// [`gather_scalar`] (tested).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn gather_sse(t: [&DirtTri; 4]) -> [[Vec4; 3]; 3] {
    use std::arch::x86_64::{
        _mm_loadu_ps, _mm_movehl_ps, _mm_movelh_ps, _mm_unpackhi_ps, _mm_unpacklo_ps,
    };
    const _: () = assert!(std::mem::size_of::<DirtTri>() == 36);
    // SAFETY: SSE is part of the x86_64 baseline; `DirtTri` is `repr(C)`, nine `f32` (three
    // `repr(C)` `Vec3`, size checked above), and the loads at floats `k <= 5` read floats
    // `k..k + 4` of the triangle.
    let rows = |k: usize| unsafe {
        let load = |tri: &DirtTri| _mm_loadu_ps((tri as *const DirtTri as *const f32).add(k));
        let (a, b, c, d) = (load(t[0]), load(t[1]), load(t[2]), load(t[3]));
        // `(a0, b0, a1, b1)`, `(c0, d0, c1, d1)`, `(a2, b2, a3, b3)`, `(c2, d2, c3, d3)`.
        let (lo01, lo23) = (_mm_unpacklo_ps(a, b), _mm_unpacklo_ps(c, d));
        let (hi01, hi23) = (_mm_unpackhi_ps(a, b), _mm_unpackhi_ps(c, d));
        [
            _mm_movelh_ps(lo01, lo23),
            _mm_movehl_ps(lo23, lo01),
            _mm_movelh_ps(hi01, hi23),
            _mm_movehl_ps(hi23, hi01),
        ]
    };
    let [x0, y0, z0, _] = rows(0);
    let [x1, y1, z1, _] = rows(3);
    let [_, x2, y2, z2] = rows(5);
    // Written out rather than by `array::map`: in some builds the nested `map` was compiled as
    // out-of-line `try_map` calls with copies of the corners through the stack.
    let v = Vec4::from;
    [
        [v(x0), v(y0), v(z0)],
        [v(x1), v(y1), v(z1)],
        [v(x2), v(y2), v(z2)],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_core::Ray;
    use parallax_core::sampling::Rng;

    /// A point uniform in the cube of side `s` around the origin.
    fn random_in_cube(rng: &mut Rng, s: f32) -> Vec3 {
        Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        ) * s
    }

    /// The SSE gather moves the very bits of the scalar one, on finite, infinite, NaN and
    /// negative-zero corners.
    #[test]
    fn gather_equals_scalar() {
        let mut rng = Rng::for_pixel(11, 4, 5, 6);
        let special = [
            0.0f32,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1e-42,
        ];
        let tris: Vec<DirtTri> = (0..64)
            .map(|i| {
                let mut c = [0.0f32; 9];
                for (k, x) in c.iter_mut().enumerate() {
                    *x = if (i + k) % 7 == 0 {
                        special[(i + k) % special.len()]
                    } else {
                        (rng.next_f32() - 0.5) * 100.0
                    };
                }
                DirtTri {
                    p0: Vec3::new(c[0], c[1], c[2]),
                    p1: Vec3::new(c[3], c[4], c[5]),
                    p2: Vec3::new(c[6], c[7], c[8]),
                }
            })
            .collect();
        let bits = |g: [[Vec4; 3]; 3]| g.map(|c| c.map(|v| v.to_array().map(f32::to_bits)));
        for w in tris.windows(4) {
            let t = [&w[0], &w[1], &w[2], &w[3]];
            assert_eq!(bits(gather(t)), bits(gather_scalar(t)));
            let r = [&w[3], &w[3], &w[0], &w[2]];
            assert_eq!(bits(gather(r)), bits(gather_scalar(r)));
        }
    }

    /// The 4-wide test and its scalar twin give the same answer (bit for bit) on random
    /// triangle lists, including shared edges and vertices (exactly-zero edge functions) and
    /// occlusion queries; and so does the x86-64-v3 copy where the CPU runs it, and each copy
    /// on `u16` entries relative to a base.
    #[test]
    fn four_wide_equals_scalar() {
        let mut rng = Rng::for_pixel(7, 1, 2, 3);
        let mut v = |s: f32| random_in_cube(&mut rng, s);
        // A fan of triangles around the z axis sharing a centre vertex and edges, plus random
        // ones: rays along z through the centre hit edges and the vertex exactly.
        let mut tris = Vec::new();
        for k in 0..8 {
            let a = k as f32 * std::f32::consts::TAU / 8.0;
            let b = (k + 1) as f32 * std::f32::consts::TAU / 8.0;
            tris.push(DirtTri {
                p0: Vec3::new(0.0, 0.0, 2.0),
                p1: Vec3::new(a.cos(), a.sin(), 2.0),
                p2: Vec3::new(b.cos(), b.sin(), 2.0),
            });
        }
        for _ in 0..200 {
            let c = v(4.0);
            tris.push(DirtTri {
                p0: c + v(1.0),
                p1: c + v(1.0),
                p2: c + v(1.0),
            });
        }
        let ids: Vec<u32> = (0..tris.len() as u32).collect();
        let mut rays = vec![
            Ray::new(Vec3::ZERO, Vec3::Z),
            Ray::new(Vec3::new(1.0, 0.0, 0.0), Vec3::Z),
            Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::Z),
        ];
        for _ in 0..500 {
            let d = v(1.0);
            if d.length() > 1e-3 {
                rays.push(Ray::new(v(3.0), d.normalize()));
            }
        }
        let mut hits = 0;
        for ray in &rays {
            for any in [false, true] {
                for len in [1, 3, 4, 5, 8, 13, ids.len()] {
                    let wt = WatertightRay::new(ray);
                    let (mut a, mut b) = (Query::new(wt, &tris, any), Query::new(wt, &tris, any));
                    let (ra, rb) = (a.test::<0>(&ids[..len]), b.test_scalar(&ids[..len]));
                    for isa in Isa::available() {
                        // Every copy the CPU runs: the same answer and counters bit for bit.
                        let mut c = Query::new(wt, &tris, any);
                        let rc = match isa {
                            Isa::Baseline => c.test::<0>(&ids[..len]),
                            Isa::X86V3 => c.test::<1>(&ids[..len]),
                            Isa::X86V4 => c.test::<2>(&ids[..len]),
                        };
                        assert_eq!(ra, rc);
                        let (x, y) = (a.best, c.best);
                        assert_eq!(
                            (x.prim, x.t.to_bits(), x.u.to_bits(), x.v.to_bits()),
                            (y.prim, y.t.to_bits(), y.u.to_bits(), y.v.to_bits()),
                        );
                        assert_eq!(a.counters, c.counters);
                        // The `u16` entries relative to a base: the same triangles.
                        let base = ids[len / 2];
                        let rel: Vec<u16> = ids[len / 2..len]
                            .iter()
                            .map(|&i| (i - base) as u16)
                            .collect();
                        let (mut d, mut e) =
                            (Query::new(wt, &tris, any), Query::new(wt, &tris, any));
                        let rd = match isa {
                            Isa::Baseline => d.test16::<0>(base, &rel),
                            Isa::X86V3 => d.test16::<1>(base, &rel),
                            Isa::X86V4 => d.test16::<2>(base, &rel),
                        };
                        assert_eq!(rd, e.test::<0>(&ids[len / 2..len]));
                        let (x, y) = (d.best, e.best);
                        assert_eq!(
                            (x.prim, x.t.to_bits(), x.u.to_bits(), x.v.to_bits()),
                            (y.prim, y.t.to_bits(), y.u.to_bits(), y.v.to_bits()),
                        );
                        assert_eq!(d.counters, e.counters);
                    }
                    if any {
                        assert_eq!(ra, rb);
                        assert_eq!(a.best.found(), b.best.found());
                    } else {
                        let (x, y) = (a.best, b.best);
                        assert_eq!(
                            (x.prim, x.t.to_bits(), x.u.to_bits(), x.v.to_bits()),
                            (y.prim, y.t.to_bits(), y.u.to_bits(), y.v.to_bits()),
                            "{ray:?} {len}"
                        );
                        hits += x.found() as u32;
                    }
                }
            }
        }
        assert!(
            hits > 100,
            "too few hits ({hits}) for the test to mean anything"
        );
    }

    /// Lists with repeated ids (within a list, across the lists of one ray, and ids sharing a
    /// mailbox slot): every copy tests the same triangles as the scalar twin (the same count
    /// of tests, so the same repeats skipped) and gives the same answer bit for bit, on `u32`
    /// and `u16` entries.
    #[test]
    fn mailbox_skips_the_scalar_twins_repeats() {
        let mut rng = Rng::for_pixel(3, 9, 2, 7);
        let mut v = |s: f32| random_in_cube(&mut rng, s);
        let tris: Vec<DirtTri> = (0..300)
            .map(|_| {
                let c = v(3.0);
                DirtTri {
                    p0: c + v(2.0),
                    p1: c + v(2.0),
                    p2: c + v(2.0),
                }
            })
            .collect();
        let rays: Vec<Ray> = (0..300)
            .filter_map(|_| {
                let d = v(1.0);
                (d.length() > 1e-3).then(|| Ray::new(v(4.0), d.normalize()))
            })
            .collect();
        let mut pick = Rng::for_pixel(5, 5, 1, 8);
        let (mut skipped, mut hits) = (0u64, 0u32);
        for ray in &rays {
            // Four lists of 1-24 entries from a few ids, some `MAILBOX` apart (one slot).
            let pool: Vec<u32> = (0..10)
                .map(|k| {
                    let id = (pick.next_f32() * 200.0) as u32;
                    if k % 3 == 0 { id % 64 + 128 } else { id }
                })
                .collect();
            let lists: Vec<Vec<u32>> = (0..4)
                .map(|_| {
                    let n = 1 + (pick.next_f32() * 24.0) as usize;
                    (0..n)
                        .map(|_| pool[(pick.next_f32() * pool.len() as f32) as usize % pool.len()])
                        .collect()
                })
                .collect();
            let total: u64 = lists.iter().map(|l| l.len() as u64).sum();
            let wt = WatertightRay::new(ray);
            for any in [false, true] {
                let mut scalar = Query::new(wt, &tris, any);
                // An occlusion query stops at its first hit (as the walk does).
                let mut rs = Vec::new();
                for l in &lists {
                    rs.push(scalar.test_scalar(l));
                    if any && rs[rs.len() - 1] {
                        break;
                    }
                }
                for isa in Isa::available() {
                    for rel in [false, true] {
                        let mut q = Query::new(wt, &tris, any);
                        let r: Vec<bool> = lists[..rs.len()]
                            .iter()
                            .map(|l| {
                                let base = if rel { *l.iter().min().unwrap() } else { 0 };
                                let d: Vec<u16> = l.iter().map(|&i| (i - base) as u16).collect();
                                match (isa, rel) {
                                    (Isa::Baseline, false) => q.test::<0>(l),
                                    (Isa::X86V3, false) => q.test::<1>(l),
                                    (Isa::X86V4, false) => q.test::<2>(l),
                                    (Isa::Baseline, true) => q.test16::<0>(base, &d),
                                    (Isa::X86V3, true) => q.test16::<1>(base, &d),
                                    (Isa::X86V4, true) => q.test16::<2>(base, &d),
                                }
                            })
                            .collect();
                        assert_eq!(r, rs);
                        if any {
                            // The four-wide test may count the rest of the hit's block.
                            assert_eq!(q.best.found(), scalar.best.found());
                            continue;
                        }
                        assert_eq!(q.counters.tests, scalar.counters.tests);
                        let (x, y) = (q.best, scalar.best);
                        assert_eq!(
                            (x.prim, x.t.to_bits(), x.u.to_bits(), x.v.to_bits()),
                            (y.prim, y.t.to_bits(), y.u.to_bits(), y.v.to_bits()),
                        );
                    }
                }
                if !any {
                    skipped += total - scalar.counters.tests;
                    hits += scalar.best.found() as u32;
                }
            }
        }
        assert!(
            skipped > 1000 && hits > 20,
            "too few repeats ({skipped}) or hits ({hits}) for the test to mean anything"
        );
    }
}
