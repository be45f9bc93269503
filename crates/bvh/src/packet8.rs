//! Packet traversal of the 8-wide tree: up to [`PACKET_SIZE`] = 16 coherent rays walk the tree
//! together, one SIMD lane per ray (AVX-512: one register per 16 rays; AVX2: two; the portable
//! twin on four `Vec4`s; `lanes16.rs`, chosen at run time in `packet_lanes.rs`). Wald, Slusallek, Benthin & Wagner 2001 (packets), Reshetov,
//! Soupikov & Hurley 2005 and Wald et al. 2007 (interval / frustum culling of whole packets),
//! in the wide-node form of Embree's `rtcIntersect16` (Wald et al. 2014, §4.2).
//!
//! - **Interval culling** (packets whose rays share the direction signs and have finite
//!   `1 / dir`, e.g. a pixel tile's or one pixel's camera rays): per axis the packet's origins
//!   span `[o_lo, o_hi]` and its `1 / dir` `[inv_lo, inv_hi]`; a lower bound of every ray's
//!   near-plane distance `fl(fl(p - o) * inv)` is the same expression at one corner of that
//!   box (the exact product is bilinear, so its extremes are at corners, and rounding is
//!   monotone), and likewise an upper bound of the far-plane distances. One 8-lane test of
//!   those bounds culls the children that no ray of the packet can enter, before any per-ray
//!   work; its near bound also orders the children (`u64` keys and sorting networks, as in the
//!   single-ray loop: `sorted_keys`).
//! - **Per-ray node test** for the remaining children of packets without interval bounds
//!   (mixed direction signs, e.g. bounce rays): the single-ray slab test of `traverse8.rs`,
//!   lane for lane (the same IEEE operations, near / far plane selected by the sign of each
//!   ray's `1 / dir`), so each ray's box test is exactly as conservative as its single-ray
//!   test. With interval bounds the children keep the packet's mask (`PURE_INTERVAL`); either
//!   way a ray is only ever dropped where its own test (or a pop against its closest hit)
//!   culls it.
//! - **Hybrid**: a subtree entered by at most `SINGLE_RAYS_BELOW` rays is finished ray by ray
//!   with the single-ray loop (Benthin, Wald, Woop, Ernst & Mark 2012, "Combining single and
//!   packet-ray tracing for arbitrary ray distributions on the Intel MIC architecture").
//! - **Leaves** (`packet_leaf.rs`): when all rays share the axis permutation of the watertight
//!   test (Woop, Benthin & Wald 2013, §3), each triangle is tested against the 16 rays at once
//!   with the operations of the scalar test lane for lane, on vertices laid out once per leaf
//!   block for the packet (lanes with an exactly-zero edge function fall back to the scalar
//!   double-precision test); otherwise each active ray runs its 4-triangle test.
//!
//! **Invariant:** every ray's answer equals [`Bvh::closest_hit`] exactly (prim, t, u, v): the
//! node tests only cull conservatively, and each ray keeps the lexicographic minimum of
//! `(t, primitive id)` over the hits it finds (ties at `t` kept by inclusive culling), which
//! is what the single-ray traversal returns whatever the order. `tests/packets.rs` checks it.

use std::mem::MaybeUninit;

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::{ROBUST_FAR_SCALE, WatertightRay};

use crate::bvh::Bvh;
use crate::hit::Hit;
use crate::lanes16::{F16, Lanes16, U16};
use crate::node::{is_leaf, leaf_count, leaf_first};
use crate::node8::Node8;
use crate::packet_interval::Interval;
use crate::stats::NoStats;
use crate::traverse::Best;
use crate::traverse8::{RayBoxes8, STACK8_SIZE};
use crate::tri4::Tri4Ray;

/// Rays per packet ([`Bvh::closest_hit_packet`] splits longer slices).
pub const PACKET_SIZE: usize = 16;

/// A subtree entered by at most this many rays of a packet is traversed ray by ray.
pub(crate) const SINGLE_RAYS_BELOW: u32 = 2;
/// With interval bounds, children passing the interval test keep the packet's whole mask (no
/// per-ray child test): a ray that misses the child costs only lanes of the SIMD triangle test,
/// which runs all 16 lanes anyway, and rays with a closer hit drop out at the pops
/// (`not_beyond`). Faster on Sponza, neutral on the classroom (notes).
const PURE_INTERVAL: bool = true;

#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    mask: u32,
    t: f32,
}

/// A packet's rays in SoA form, with each ray's closest hit so far.
pub(crate) struct Packet {
    pub valid: u32,
    pub(crate) org: [F16; 3],
    inv: [F16; 3],
    /// Lanes whose `1 / dir` is negative, per axis.
    neg: [u32; 3],
    pub(crate) t_min: F16,
    /// The closest hit so far (or the ray's `t_max`).
    pub(crate) t_max: F16,
    pub(crate) best_tri: U16,
    pub(crate) best_u: F16,
    pub(crate) best_v: F16,
    /// The shear of the watertight test, per ray, and the common axis permutation if any.
    pub(crate) sx: F16,
    pub(crate) sy: F16,
    pub(crate) sz: F16,
    pub(crate) perm: Option<[usize; 3]>,
    /// The origin all valid rays share, bit for bit (a pinhole camera's tile), if they do: the
    /// triangle test then subtracts it once per vertex instead of once per lane.
    pub(crate) org0: Option<[f32; 3]>,
    pub interval: Option<Interval>,
    /// With `interval`: per axis the valid rays' origin range (axes 0..3) and `1 / dir` range
    /// (axes 3..6), and their `t_min` / `t_max` ranges (`packet64.rs` unites them).
    pub lo: [f32; 6],
    pub hi: [f32; 6],
    pub t_range: (f32, f32),
}

impl Packet {
    /// The packet's SoA form. The per-ray values are the single ray's, bit for bit: `1 / dir`
    /// as `Vec3::recip`, and the shear `d[kx] / d[kz]`, `d[ky] / d[kz]`, `1 / d[kz]` of
    /// `WatertightRay::new` (computed here in SIMD when all rays share the axis permutation;
    /// otherwise rays build their `WatertightRay` where they need it).
    /// `valid`: the rays that are valid with `t_min <= t_max` (computed here, in lanes for a
    /// full packet: the same comparisons as `Ray::is_valid`).
    /// Built in `slot` (a packet is ~1.4 kB: returning it by value cost a copy per packet).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
    pub fn init<'a, L: Lanes16>(
        slot: &'a mut MaybeUninit<Self>,
        l: L,
        rays: &[Ray],
    ) -> &'a mut Self {
        let z = F16([0.0; 16]);
        let p = slot.write(Packet {
            valid: 0,
            org: [z; 3],
            inv: [F16([1.0; 16]); 3],
            neg: [0; 3],
            t_min: z,
            t_max: F16([f32::NEG_INFINITY; 16]),
            best_tri: U16([u32::MAX; 16]),
            best_u: z,
            best_v: z,
            sx: z,
            sy: z,
            sz: z,
            perm: None,
            org0: None,
            interval: None,
            lo: [0.0; 6],
            hi: [0.0; 6],
            t_range: (0.0, 0.0),
        });
        let mut dir = [F16([1.0; 16]); 3];
        let (valid, code, o0, same_org) = match <&[Ray; PACKET_SIZE]>::try_from(rays) {
            Ok(r16) => p.load_lanes(l, r16, &mut dir),
            Err(_) => p.load_scalar(rays, &mut dir),
        };
        p.valid = valid;
        let one = l.splat(1.0);
        let mut finite = valid;
        let d = [l.load(&dir[0]), l.load(&dir[1]), l.load(&dir[2])];
        for a in 0..3 {
            let inv = l.div(one, d[a]);
            l.store(inv, &mut p.inv[a]);
            p.neg[a] = l.lt(inv, l.splat(0.0)) & valid;
            finite &= l.lt(inv, l.splat(f32::INFINITY)) & l.gt(inv, l.splat(f32::NEG_INFINITY));
        }
        if let Some(code) = code {
            let [kx, ky, kz] = axes_of_code(code);
            let (dx, dy, dz) = (d[kx], d[ky], d[kz]);
            l.store(l.div(dx, dz), &mut p.sx);
            l.store(l.div(dy, dz), &mut p.sy);
            l.store(l.div(one, dz), &mut p.sz);
            p.perm = Some([kx, ky, kz]);
        }
        if same_org && valid != 0 {
            p.org0 = Some(o0);
        }
        let uniform = (0..3).all(|a| p.neg[a] == 0 || p.neg[a] == valid);
        if uniform && finite == valid && valid != 0 {
            let mut lo = [0.0; 6];
            let mut hi = [0.0; 6];
            for a in 0..3 {
                let (o, inv) = (l.load(&p.org[a]), l.load(&p.inv[a]));
                lo[a] = l.hmin(valid, o);
                hi[a] = l.hmax(valid, o);
                lo[3 + a] = l.hmin(valid, inv);
                hi[3 + a] = l.hmax(valid, inv);
            }
            let t_lo = l.hmin(valid, l.load(&p.t_min));
            let t_hi = l.hmax(valid, l.load(&p.t_max));
            p.interval = Some(p.interval(lo, hi, t_lo, t_hi));
            (p.lo, p.hi, p.t_range) = (lo, hi, (t_lo, t_hi));
        }
        p
    }

    /// Loads up to 16 rays one by one into the SoA rows (invalid rays keep the defaults):
    /// returns the valid rays, their common axis-permutation code (if any), the first valid
    /// ray's origin and whether every valid ray has that origin bit for bit.
    #[inline(always)]
    fn load_scalar(
        &mut self,
        rays: &[Ray],
        dir: &mut [F16; 3],
    ) -> (u32, Option<u32>, [f32; 3], bool) {
        let p = self;
        let mut valid = 0u32;
        for (i, r) in rays.iter().enumerate() {
            if r.is_valid() && r.t_min <= r.t_max {
                valid |= 1 << i;
            }
        }
        let mut same_org = true;
        let o0 = rays
            .get(valid.trailing_zeros() as usize)
            .map_or(glam::Vec3::ZERO, |r| r.origin);
        // The permutation as a code `2 kz + swapped` (one byte compare per ray).
        let (mut code_and, mut code_or) = (u32::MAX, 0u32);
        for (i, r) in rays.iter().enumerate() {
            if valid >> i & 1 == 0 {
                continue;
            }
            for a in 0..3 {
                p.org[a].0[i] = r.origin[a];
                dir[a].0[i] = r.dir[a];
                same_org &= r.origin[a].to_bits() == o0[a].to_bits();
            }
            p.t_min.0[i] = r.t_min;
            p.t_max.0[i] = r.t_max;
            let c = watertight_code(r.dir);
            code_and &= c;
            code_or |= c;
        }
        let code = (code_and == code_or).then_some(code_or);
        (valid, code, o0.to_array(), same_org)
    }

    /// [`Self::load_scalar`] for a full packet, in lanes (`packet_setup.rs`).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // the loop index addresses several arrays in step
    fn load_lanes<L: Lanes16>(
        &mut self,
        l: L,
        rays: &[Ray; PACKET_SIZE],
        dir: &mut [F16; 3],
    ) -> (u32, Option<u32>, [f32; 3], bool) {
        let s = crate::packet_setup::rays16(l, rays);
        let v = s.valid;
        let (zero, one) = (l.splat(0.0), l.splat(1.0));
        for a in 0..3 {
            l.store(l.select(v, s.f[a], zero), &mut self.org[a]);
            l.store(l.select(v, s.f[3 + a], one), &mut dir[a]);
        }
        l.store(l.select(v, s.f[6], zero), &mut self.t_min);
        l.store(
            l.select(v, s.f[7], l.splat(f32::NEG_INFINITY)),
            &mut self.t_max,
        );
        (v, s.code, s.o0, s.same_org)
    }

    /// The interval bounds from the per-axis ranges `lo` / `hi` of the valid rays' origins
    /// (axes 0..3) and `1 / dir` (axes 3..6), and their `t_min` / `t_max` ranges.
    #[inline(always)]
    pub fn interval(&self, lo: [f32; 6], hi: [f32; 6], t_min: f32, t_max: f32) -> Interval {
        let mut iv = Interval {
            o_near: [Vec4::ZERO; 3],
            o_far: [Vec4::ZERO; 3],
            inv_near: [(Vec4::ZERO, Vec4::ZERO); 3],
            inv_far: [(Vec4::ZERO, Vec4::ZERO); 3],
            near: [0; 3],
            far: [0; 3],
            t_min: Vec4::splat(t_min),
            t_max,
        };
        for a in 0..3 {
            let (i_lo, i_hi) = (Vec4::splat(lo[3 + a]), Vec4::splat(hi[3 + a]));
            let negative = self.neg[a] != 0;
            // Near row: the min of `d * inv` over the box; far row: the max (module docs).
            let (on, of) = if negative {
                (lo[a], hi[a])
            } else {
                (hi[a], lo[a])
            };
            iv.o_near[a] = Vec4::splat(on);
            iv.o_far[a] = Vec4::splat(of);
            iv.inv_near[a] = (i_lo, i_hi);
            iv.inv_far[a] = (i_hi, i_lo);
            let s = negative as usize;
            iv.near[a] = 32 * (2 * a + s);
            iv.far[a] = 32 * (2 * a + 1 - s);
        }
        iv
    }

    /// Per-ray slab test of child `c` of `node` for the rays of `mask`: the rays that enter it,
    /// and (with `entry`) the smallest entry distance among them (+inf without).
    #[inline(always)]
    fn test_child<L: Lanes16>(
        &self,
        l: L,
        node: &Node8,
        c: usize,
        mask: u32,
        entry: bool,
    ) -> (u32, f32) {
        let b = &node.bounds;
        let mut t_near = l.load(&self.t_min);
        let mut t_far = l.load(&self.t_max);
        let mut tn = [t_near; 3];
        let mut tf = [t_far; 3];
        for a in 0..3 {
            let (o, inv) = (l.load(&self.org[a]), l.load(&self.inv[a]));
            let t0 = l.mul(l.sub(l.splat(b[2 * a][c]), o), inv);
            let t1 = l.mul(l.sub(l.splat(b[2 * a + 1][c]), o), inv);
            tn[a] = l.select(self.neg[a], t1, t0);
            tf[a] = l.select(self.neg[a], t0, t1);
        }
        // The single-ray order: max(tnz, max(tny, max(tnx, t_min))), likewise for t_far.
        for a in 0..3 {
            t_near = l.max(tn[a], t_near);
            t_far = l.min(tf[a], t_far);
        }
        let t_far = l.mul(t_far, l.splat(ROBUST_FAR_SCALE));
        let hit = l.le(t_near, t_far) & mask;
        let t = if entry && hit != 0 {
            l.hmin(hit, t_near)
        } else {
            f32::INFINITY
        };
        (hit, t)
    }

    /// The direction signs of the valid rays as bits (axis `a` negative: bit `a`), meaningful
    /// when they agree (`interval` is some).
    #[inline(always)]
    pub fn sign_code(&self) -> u32 {
        (0..3).map(|a| ((self.neg[a] != 0) as u32) << a).sum()
    }

    /// Sets the interval's `t_max` to the largest current `t_max` of the valid rays.
    #[inline(always)]
    pub fn refresh_interval<L: Lanes16>(&mut self, l: L) {
        if let Some(iv) = &mut self.interval {
            iv.t_max = l.hmax(self.valid, l.load(&self.t_max));
        }
    }

    /// Rays of `mask` that have not yet found a hit nearer than `t`.
    #[inline(always)]
    pub fn not_beyond<L: Lanes16>(&self, l: L, mask: u32, t: f32) -> u32 {
        let bound = l.mul(l.load(&self.t_max), l.splat(ROBUST_FAR_SCALE));
        l.le(l.splat(t), bound) & mask
    }

    /// Ray `i` finishes the subtree `root` alone (its closest hit so far carried over).
    #[inline(always)]
    pub fn single_ray<L: Lanes16>(&mut self, bvh: &Bvh, l: L, rays: &[Ray], i: usize, root: u32) {
        let mut best = self.best(i);
        let mut t_max = self.t_max.0[i];
        // SAFETY: rays of a mask are valid, and valid rays were initialised.
        let r4 = Tri4Ray::new(WatertightRay::new(&rays[i]));
        let nt = l.single(RayBoxes8::new(&rays[i]));
        bvh.closest8_from(&nt, &r4, root, &mut t_max, &mut best, &mut NoStats);
        self.set_best(i, best, t_max);
    }

    #[inline(always)]
    pub fn best(&self, i: usize) -> Best {
        Best {
            t: if self.best_tri.0[i] == u32::MAX {
                f32::INFINITY
            } else {
                self.t_max.0[i]
            },
            tri: self.best_tri.0[i],
            u: self.best_u.0[i],
            v: self.best_v.0[i],
        }
    }

    #[inline(always)]
    pub(crate) fn set_best(&mut self, i: usize, b: Best, t_max: f32) {
        self.t_max.0[i] = t_max;
        self.best_tri.0[i] = b.tri;
        self.best_u.0[i] = b.u;
        self.best_v.0[i] = b.v;
    }
}

impl Bvh {
    /// The 16-ray traversal of up to [`PACKET_SIZE`] rays on lanes `l` (module docs; the
    /// entry points and the choice of lanes are in `packet_lanes.rs`).
    #[inline(always)]
    pub(crate) fn packet8<L: Lanes16>(&self, l: L, rays: &[Ray], out: &mut [Option<Hit>]) {
        for o in out.iter_mut().take(rays.len()) {
            *o = None;
        }
        if self.nodes8.is_empty() {
            return;
        }
        let mut slot = MaybeUninit::uninit();
        let p = Packet::init(&mut slot, l, rays);
        let valid = p.valid;
        if valid == 0 {
            return;
        }
        let mut stack = [MaybeUninit::<Entry>::uninit(); STACK8_SIZE];
        let mut sp = 0usize;
        let mut cur = 0u32;
        let mut mask = valid;
        loop {
            if mask.count_ones() <= SINGLE_RAYS_BELOW {
                // Few rays left in this subtree: each finishes it alone (the single-ray loop is
                // cheaper than a mostly empty packet; module docs, "Hybrid").
                let mut m = mask;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    p.single_ray(self, l, rays, i, cur);
                }
                if let Some(iv) = &mut p.interval {
                    iv.t_max = l.hmax(p.valid, l.load(&p.t_max));
                }
            } else if !is_leaf(cur) {
                let node = &self.nodes8[cur as usize];
                // With interval bounds, their entry bound orders the children and culls pops
                // (it is below every ray's entry distance); else the rays' smallest entry.
                let (cand, t_ia) = match &p.interval {
                    #[cfg(target_arch = "x86_64")]
                    // SAFETY: `L::AVX2` holds only for lanes made after detecting AVX2.
                    Some(iv) if L::AVX2 => unsafe { iv.test_avx2(node) },
                    Some(iv) => iv.test(node),
                    None => ((1u32 << node.num_children) - 1, [0.0; 8]),
                };
                let ia = p.interval.is_some();
                if ia && PURE_INTERVAL {
                    // Every candidate keeps the packet's mask: order by the entry bound alone,
                    // with the single-ray loop's keys and sorting network (`traverse8.rs`).
                    if cand != 0 {
                        if cand & (cand - 1) == 0 {
                            cur = node.child[cand.trailing_zeros() as usize];
                            continue;
                        }
                        let ks = sorted_keys(cand, &t_ia);
                        let n = cand.count_ones() as usize;
                        for &k in ks[1..n].iter().rev() {
                            let c = (k & 7) as usize;
                            let (child, t) = (node.child[c], t_ia[c]);
                            stack[sp] = MaybeUninit::new(Entry { child, mask, t });
                            sp += 1;
                        }
                        cur = node.child[(ks[0] & 7) as usize];
                        continue;
                    }
                }
                let mut kid = [Entry {
                    child: 0,
                    mask: 0,
                    t: 0.0,
                }; 8];
                let mut n = 0;
                let mut m = cand;
                while m != 0 {
                    let c = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let (hits, t) = if ia && PURE_INTERVAL {
                        (mask, t_ia[c])
                    } else {
                        p.test_child(l, node, c, mask, !ia)
                    };
                    if hits != 0 {
                        let t = if ia { t_ia[c] } else { t };
                        let e = Entry {
                            child: node.child[c],
                            mask: hits,
                            t,
                        };
                        // Insertion, far to near.
                        let mut j = n;
                        while j > 0 && kid[j - 1].t < e.t {
                            kid[j] = kid[j - 1];
                            j -= 1;
                        }
                        kid[j] = e;
                        n += 1;
                    }
                }
                if n != 0 {
                    for e in &kid[..n - 1] {
                        stack[sp] = MaybeUninit::new(*e);
                        sp += 1;
                    }
                    cur = kid[n - 1].child;
                    mask = kid[n - 1].mask;
                    continue;
                }
            } else {
                self.packet_leaf(l, p, rays, leaf_first(cur), leaf_count(cur), mask);
                if let Some(iv) = &mut p.interval {
                    iv.t_max = l.hmax(p.valid, l.load(&p.t_max));
                }
            }
            loop {
                if sp == 0 {
                    for (i, o) in out.iter_mut().enumerate().take(rays.len()) {
                        *o = p.best(i).hit();
                    }
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were written by the pushes above.
                let e = unsafe { stack[sp].assume_init() };
                let m = p.not_beyond(l, e.mask, e.t);
                if m != 0 {
                    cur = e.child;
                    mask = m;
                    break;
                }
            }
        }
    }
}

/// The candidates `cand` (at least two) of a node as keys `ordered(t[c]) << 32 | c`, nearest
/// first; slots from `cand.count_ones()` on hold `u64::MAX`. `ordered` maps f32 to u32 in the
/// order of `<` (negative values reversed), so any order of equal or NaN bounds may result:
/// the order only affects speed (module docs, invariant).
#[inline(always)]
pub(crate) fn sorted_keys(cand: u32, t: &[f32; 8]) -> [u64; 8] {
    let mut ks = [u64::MAX; 8];
    let mut n = 0;
    let mut m = cand;
    while m != 0 {
        let c = m.trailing_zeros() as usize;
        m &= m - 1;
        let b = t[c].to_bits();
        let o = if (b as i32) < 0 { !b } else { b | 1 << 31 };
        ks[n] = (o as u64) << 32 | c as u64;
        n += 1;
    }
    let sort2 = |ks: &mut [u64; 8], i: usize, j: usize| {
        let (x, y) = (ks[i], ks[j]);
        ks[i] = x.min(y);
        ks[j] = x.max(y);
    };
    if n == 2 {
        sort2(&mut ks, 0, 1);
    } else if n <= 4 {
        for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            sort2(&mut ks, i, j);
        }
    } else {
        // Batcher's odd-even merge sort of eight (19 comparators; padding sorts last).
        for (i, j) in [
            (0, 1),
            (2, 3),
            (4, 5),
            (6, 7),
            (0, 2),
            (1, 3),
            (4, 6),
            (5, 7),
            (1, 2),
            (5, 6),
            (0, 4),
            (1, 5),
            (2, 6),
            (3, 7),
            (2, 4),
            (3, 5),
            (1, 2),
            (3, 4),
            (5, 6),
        ] {
            sort2(&mut ks, i, j);
        }
    }
    ks
}

/// The axis permutation of `WatertightRay::new` for direction `d` as a code `2 kz + swapped`
/// (the same comparisons: `kz` the dominant axis, `kx, ky` swapped when `d[kz] < 0`).
#[inline(always)]
pub(crate) fn watertight_code(d: glam::Vec3) -> u32 {
    let a = d.abs();
    let kz = if a.x > a.y {
        if a.x > a.z { 0 } else { 2 }
    } else if a.y > a.z {
        1
    } else {
        2
    };
    2 * kz + (d[kz as usize] < 0.0) as u32
}

/// `[kx, ky, kz]` of a [`watertight_code`].
#[inline(always)]
fn axes_of_code(code: u32) -> [usize; 3] {
    let kz = (code / 2) as usize;
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    if code & 1 != 0 {
        [ky, kx, kz]
    } else {
        [kx, ky, kz]
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use parallax_core::Ray;
    use parallax_core::math::WatertightRay;

    #[test]
    fn sorted_keys_order_every_candidate_set() {
        let mut s = 7u32;
        for round in 0..40 {
            let t: [f32; 8] = std::array::from_fn(|_| {
                s = s.wrapping_mul(747796405).wrapping_add(2891336453);
                // Some rounds with many equal values and negative bounds.
                let r = (s >> 8) as f32 / (1 << 24) as f32;
                if round % 4 == 0 {
                    (r * 3.0).floor() - 1.0
                } else {
                    r * 10.0 - 2.0
                }
            });
            for cand in 0u32..256 {
                if cand.count_ones() < 2 {
                    continue;
                }
                let ks = super::sorted_keys(cand, &t);
                let n = cand.count_ones() as usize;
                let lanes: Vec<usize> = ks[..n].iter().map(|&k| (k & 7) as usize).collect();
                let mut seen = 0u32;
                for &c in &lanes {
                    seen |= 1 << c;
                }
                assert_eq!(seen, cand, "{cand:#x}: {lanes:?}");
                assert!(ks[n..].iter().all(|&k| k == u64::MAX));
                for w in lanes.windows(2) {
                    assert!(t[w[0]] <= t[w[1]], "{cand:#x} {t:?} {lanes:?}");
                }
            }
        }
    }

    #[test]
    fn axes_match_the_watertight_ray() {
        let mut s = 1u32;
        let mut r = || {
            s = s.wrapping_mul(747796405).wrapping_add(2891336453);
            (s >> 8) as f32 / (1 << 23) as f32 - 1.0
        };
        let mut dirs: Vec<Vec3> = (0..2000).map(|_| Vec3::new(r(), r(), r())).collect();
        // Ties between components and zeros.
        dirs.extend([
            Vec3::ONE,
            -Vec3::ONE,
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 0.0, -2.0),
        ]);
        for d in dirs {
            let wt = WatertightRay::new(&Ray::new(Vec3::ZERO, d));
            let axes = super::axes_of_code(super::watertight_code(d));
            assert_eq!(axes, [wt.kx, wt.ky, wt.kz], "{d:?}");
        }
    }
}
