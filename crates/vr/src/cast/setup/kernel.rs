//! What both set-up kernels ([`super::edges`], [`super::full`]) run per packet: the edge dot
//! products in the scalar order of [`super::tri::dot3`], the BVH's robust slab test of a packet
//! on a run's box ([`PacketSlab`]), and the work counters ([`SetupWork`]).

use glam::{BVec4A, Vec4};
use parallax_core::math::ROBUST_FAR_SCALE;
use parallax_core::simd::{Lanes, abs_lanes, max_or_rhs, min_or_rhs};

use super::tri::{RunBoxes16, Segment, TriSetup};
use crate::cast::lanes16::LaneReduce;

/// `n . d` per lane in the scalar order of [`super::tri::dot3`] (no FMA: plain functions, not closures,
/// so they are compiled inside the AVX2 entry point).
#[inline(always)]
pub(super) fn dot_n<L: Lanes>(n: [f32; 3], dx: L, dy: L, dz: L) -> L {
    L::splat(n[0]) * dx + L::splat(n[1]) * dy + L::splat(n[2]) * dz
}

/// The smallest of a set-up triangle's three edge values `n_i . d` per lane ([`dot_n`]).
#[inline(always)]
pub(super) fn min_edge<L: Lanes>(n: &[[f32; 3]; 3], [dx, dy, dz]: [L; 3]) -> L {
    dot_n(n[0], dx, dy, dz)
        .min_or_rhs(dot_n(n[1], dx, dy, dz))
        .min_or_rhs(dot_n(n[2], dx, dy, dz))
}

/// The edges of [`min_edge_of`] per `need` (bits 0-2), as three covector indices: the
/// needed edges in ascending order, the last one repeated (`min_or_rhs(m, e) = m` when `m` is
/// already `min_or_rhs(.., e)`, bit for bit, NaN too); `need = 0` (never asked) edge 0.
const EDGES_OF: [[u8; 3]; 8] = [
    [0, 0, 0],
    [0, 0, 0],
    [1, 1, 1],
    [0, 1, 1],
    [2, 2, 2],
    [0, 2, 2],
    [1, 2, 2],
    [0, 1, 2],
];

/// The smallest edge value `n_i . d` per lane over the edges `need` (bits `i`, not 0; the
/// others are certainly inside for every lane: [`super::affine::PacketBox::classify_edges`]),
/// in [`min_edge`]'s order. Branch-free: always three dot products, of the covectors
/// [`EDGES_OF`] picks (a repeated last edge leaves the minimum unchanged bit for bit), so the
/// edge subset, which changes from triangle to triangle, costs no jump; equal to
/// [`min_edge_of_match`] (tested).
#[inline(always)]
pub(super) fn min_edge_of<L: Lanes>(n: &[[f32; 3]; 3], [dx, dy, dz]: [L; 3], need: u32) -> L {
    let [a, b, c] = EDGES_OF[need as usize & 7];
    dot_n(n[a as usize], dx, dy, dz)
        .min_or_rhs(dot_n(n[b as usize], dx, dy, dz))
        .min_or_rhs(dot_n(n[c as usize], dx, dy, dz))
}

/// [`min_edge_of`] by a `match` on `need` (one or two dot products for one or two edges):
/// the reference of the branch-free form.
#[cfg(test)]
pub(super) fn min_edge_of_match<L: Lanes>(n: &[[f32; 3]; 3], [dx, dy, dz]: [L; 3], need: u32) -> L {
    match need {
        1 => dot_n(n[0], dx, dy, dz),
        2 => dot_n(n[1], dx, dy, dz),
        4 => dot_n(n[2], dx, dy, dz),
        3 => dot_n(n[0], dx, dy, dz).min_or_rhs(dot_n(n[1], dx, dy, dz)),
        5 => dot_n(n[0], dx, dy, dz).min_or_rhs(dot_n(n[2], dx, dy, dz)),
        6 => dot_n(n[1], dx, dy, dz).min_or_rhs(dot_n(n[2], dx, dy, dz)),
        _ => min_edge(n, [dx, dy, dz]),
    }
}

/// The edge test of the lanes `cand` (mask; `cand_bits` = its bits within the valid lanes)
/// over the edges `need` ([`min_edge_of`]; 7: all three) against `tr` (module docs of [`super`], "exact band"): the mask of lanes certainly inside
/// (every edge value above the band `bound |d|_inf`, with `dinf` the packet's `|d|_inf`) and the
/// bits of the lanes within the band, which only the watertight test decides.
#[inline(always)]
pub(super) fn edge_band<L: Lanes>(
    tr: &TriSetup,
    d: [L; 3],
    dinf: f32,
    cand: L::M,
    cand_bits: u32,
    need: u32,
) -> (L::M, u32) {
    if tr.all_in {
        return (cand, 0);
    }
    let m = min_edge_of(&tr.n, d, need);
    let b = L::splat(tr.bound * dinf);
    let inside = L::and(cand, m.gt(b));
    let rest = cand_bits & !L::bits(inside);
    let unsure = if rest != 0 {
        L::bits(m.ge(L::splat(0.0) - b)) & rest
    } else {
        0
    };
    (inside, unsure)
}

/// [`edge_band`] before the depth test (`edges_first` in `cast/setup/edges.rs`): the mask
/// of lanes above the band (`m > b`) and the bits of the valid lanes `valid` within or above it
/// (`m >= -b`), of the edges `need`. [`edge_band`]'s `(inside, unsure)` for candidates `cand`
/// (bits within `valid`, mask `ge`) are `(ge & above, reach & cand & !bits(ge & above))`:
/// the same compares of the same `m` and `b`. With `b = bound |d|_inf >= 0` (or NaN) a lane
/// above the band is within reach, so no bit of `reach` means no lane inside or unsure.
#[inline(always)]
pub(super) fn edge_reach<L: Lanes>(
    tr: &TriSetup,
    d: [L; 3],
    dinf: f32,
    valid: u32,
    need: u32,
) -> (L::M, u32) {
    debug_assert!(!tr.all_in && !(tr.bound < 0.0));
    let m = min_edge_of(&tr.n, d, need);
    let b = L::splat(tr.bound * dinf);
    (m.gt(b), L::bits(m.ge(L::splat(0.0) - b)) & valid)
}

/// Entry and exit `t` of one slab (`lo`, `hi` relative to the origin).
#[inline(always)]
pub(super) fn slab<L: Lanes>(lo: f32, hi: f32, inv: L, neg: L::M) -> (L, L) {
    let t0 = L::splat(lo) * inv;
    let t1 = L::splat(hi) * inv;
    (L::select(neg, t1, t0), L::select(neg, t0, t1))
}

/// Lanes x, y, z of a [`Vec4`].
const XYZ: BVec4A = BVec4A::from_array([true, true, true, false]);

/// Lanes holding a finite value (ordered compares: false on NaN and both infinities; a plain
/// function, not a closure, so an AVX-512 entry point inlines it).
#[inline(always)]
pub(super) fn finite<L: Lanes>(x: L) -> L::M {
    let inf = L::splat(f32::INFINITY);
    L::and(x.lt(inf), x.gt(L::splat(0.0) - inf))
}

/// `|d|_inf` per lane.
#[inline(always)]
pub(super) fn lane_dinf<L: Lanes>([dx, dy, dz]: [L; 3]) -> L {
    max_or_rhs(abs_lanes(dx), max_or_rhs(abs_lanes(dy), abs_lanes(dz)))
}

/// Per-packet constants of the set-up kernels (`cast/setup/edges.rs`, `cast/setup/full.rs`): reciprocal
/// directions and their signs for the BVH's robust slab test, and the packet's largest
/// `|d|_inf` over its lanes (the scale of the edge band; invalid lanes have `d = 0`).
pub(super) struct PacketSlab<L: Lanes> {
    inv: [L; 3],
    neg: [L::M; 3],
    pub dinf: f32,
    /// Per axis the smallest and largest reciprocal direction of the valid lanes, when every
    /// valid lane's is finite and of one sign (`None` otherwise): the packet's interval test.
    interval: Option<Interval>,
}

/// The packet's reciprocal-direction interval as SSE registers (lanes x, y, z; `w` = 0): the
/// smaller and larger end per axis and the axes where both are negative. The interval test
/// runs the three axes of [`PacketSlab::interval_reaches`] in one register each step.
#[derive(Clone, Copy)]
struct Interval {
    i0: Vec4,
    i1: Vec4,
    neg: BVec4A,
    /// Per axis `i0`, `i1` splatted and the sign: [`PacketSlab::interval_reaches4`].
    s0: [Vec4; 3],
    s1: [Vec4; 3],
    sneg: [bool; 3],
}

impl<L: Lanes> PacketSlab<L> {
    #[inline(always)]
    pub(super) fn new(d: [L; 3]) -> Self {
        let (mut s, dinf_l) = Self::lanes(d);
        for l in 0..L::N {
            s.dinf = s.dinf.max(dinf_l.get(l));
        }
        s
    }

    /// The reciprocals and their signs; `dinf` = 0 and the per-lane `|d|_inf`.
    #[inline(always)]
    fn lanes([dx, dy, dz]: [L; 3]) -> (Self, L) {
        let (zero, one) = (L::splat(0.0), L::splat(1.0));
        let inv = [one / dx, one / dy, one / dz];
        let neg = [inv[0].lt(zero), inv[1].lt(zero), inv[2].lt(zero)];
        let dinf_l = max_or_rhs(abs_lanes(dx), max_or_rhs(abs_lanes(dy), abs_lanes(dz)));
        let s = Self {
            inv,
            neg,
            dinf: 0.0,
            interval: None,
        };
        (s, dinf_l)
    }

    /// [`PacketSlab::new`] with the packet's interval test ([`PacketSlab::interval_reaches`]);
    /// invalid lanes (`d = 0`, reciprocal `+inf`) disable it.
    #[inline(always)]
    pub(super) fn with_interval(d: [L; 3]) -> Self
    where
        L: LaneReduce,
    {
        // `dinf` as `new`'s scalar loop (`0.max(x) = x`, NaN lanes ignored, the sign of a zero
        // never seen: the band `bound * dinf` is only compared), by one horizontal maximum.
        let (mut s, dinf_l) = Self::lanes(d);
        // The seven reductions in two passes of four (`hmin4` / `hmax4`: each value's own
        // reduction, bit for bit): lanes x, y, z the interval's ends, lane `w` of the maxima
        // `dinf`.
        let [x, y, z] = s.inv;
        let lo = L::hmin4([x, y, z, z]);
        let hi = L::hmax4([x, y, z, max_or_rhs(dinf_l, L::splat(0.0))]);
        s.dinf = hi.w;
        let (x0, y0, z0) = (lo.x, lo.y, lo.z);
        let (x1, y1, z1) = (hi.x, hi.y, hi.z);
        // Per axis: both ends finite and of one sign (`r0 > 0 || r1 < 0`), the three axes in
        // lanes x, y, z of one register.
        let (i0, i1) = (
            Vec4::select(XYZ, lo, Vec4::ZERO),
            Vec4::select(XYZ, hi, Vec4::ZERO),
        );
        let ok = i0.is_finite_mask()
            & i1.is_finite_mask()
            & (i0.cmpgt(Vec4::ZERO) | i1.cmplt(Vec4::ZERO));
        if ok.bitmask() & 7 == 7 {
            s.interval = Some(Interval {
                i0,
                i1,
                neg: i1.cmplt(Vec4::ZERO),
                s0: [Vec4::splat(x0), Vec4::splat(y0), Vec4::splat(z0)],
                s1: [Vec4::splat(x1), Vec4::splat(y1), Vec4::splat(z1)],
                sneg: [x1 < 0.0, y1 < 0.0, z1 < 0.0],
            });
        }
        s
    }

    /// Whether the interval test is available ([`PacketSlab::with_interval`]).
    #[inline(always)]
    pub(super) fn has_interval(&self) -> bool {
        self.interval.is_some()
    }

    /// A packet-wide conservative form of [`PacketSlab::reaches`] (same far scaling; `lim` =
    /// the largest closest-hit limit of the valid lanes): false only if no valid lane reaches
    /// the box. Float products are monotone in each factor, so per axis every lane's entry
    /// `t` is at least the smaller of the interval's two products and its exit at most the
    /// larger: a lane passing the per-lane test passes this one. True without an interval.
    #[inline(always)]
    pub(super) fn interval_reaches(&self, seg: &Segment, lim: f32) -> bool {
        let Some(iv) = &self.interval else {
            return true;
        };
        // Per axis (lanes x, y, z): the near and far planes by the interval's sign, the four
        // products, `if a < b { a } else { b }` (`minps`) for the entry and `if c > d { c }
        // else { d }` (`maxps`) for the exit. Lane `w` is 0 (`lo.w = hi.w = i.w = 0`) for the
        // entry, which also takes the `max` with 0, and `lim` for the exit. The products are
        // finite or infinite, never NaN (finite planes and interval), so the horizontal max /
        // min equal the scalar chain of the per-axis form up to the sign of a zero, which no
        // comparison sees.
        let (lo, hi) = (seg.lo, seg.hi);
        let n = Vec4::select(iv.neg, hi, lo);
        let f = Vec4::select(iv.neg, lo, hi);
        let near = (n * iv.i0).min(n * iv.i1);
        let far = (f * iv.i0).max(f * iv.i1);
        let far = Vec4::select(XYZ, far, Vec4::splat(lim));
        let t_near = near.max_element();
        let t_far = far.min_element();
        t_near <= t_far * ROBUST_FAR_SCALE
    }

    /// [`PacketSlab::interval_reaches`] of the four runs `4q..4q + 4` of `rb` at once (one
    /// lane per run): bit `r` set iff the test of run `4q + r` is true. Per lane the same products, `minps` /
    /// `maxps` over values that are never NaN (exact up to the sign of a zero, which the final
    /// compare does not see), the entry's `max` with 0 and the exit's `min` with `lim`: the
    /// same decision per run. Every bit without an interval.
    #[inline(always)]
    pub(super) fn interval_reaches4(&self, rb: &RunBoxes16, q: usize, lim: f32) -> u32 {
        let Some(iv) = &self.interval else {
            return 0xF;
        };
        let mut t_near = Vec4::ZERO;
        let mut t_far = Vec4::splat(lim);
        for a in 0..3 {
            let k = (q & 3) * 4;
            let (lo, hi) = (
                Vec4::from_slice(&rb.lo[a][k..k + 4]),
                Vec4::from_slice(&rb.hi[a][k..k + 4]),
            );
            let (n, f) = if iv.sneg[a] { (hi, lo) } else { (lo, hi) };
            t_near = t_near.max((n * iv.s0[a]).min(n * iv.s1[a]));
            t_far = t_far.min((f * iv.s0[a]).max(f * iv.s1[a]));
        }
        t_near
            .cmple(t_far * Vec4::splat(ROBUST_FAR_SCALE))
            .bitmask()
    }

    /// [`PacketSlab::interval_reaches4`] of the sixteen runs of `rb` at once in the lanes of
    /// `L` (sixteen lanes: one AVX-512 register per axis and bound with
    /// [`crate::cast::lanes512::Z16`]): bit `r` set iff the test of run `r` is true. Per lane
    /// the same products and `a < b ? a : b` / `a > b ? a : b` selects (`min_or_rhs` /
    /// `max_or_rhs`: `minps` / `maxps`, as glam's `Vec4::min` / `max` there) in the same
    /// order: the same bits, run for run (tested below). Every bit without an interval.
    #[inline(always)]
    pub(super) fn interval_reaches16(&self, rb: &RunBoxes16, lim: f32) -> u32
    where
        L: LaneReduce,
    {
        debug_assert_eq!(L::N, 16);
        let Some(iv) = &self.interval else {
            return 0xFFFF;
        };
        let mut t_near = L::splat(0.0);
        let mut t_far = L::splat(lim);
        for a in 0..3 {
            let (lo, hi) = (L::load16(&rb.lo[a]), L::load16(&rb.hi[a]));
            let (n, f) = if iv.sneg[a] { (hi, lo) } else { (lo, hi) };
            let (s0, s1) = (L::splat(iv.s0[a].x), L::splat(iv.s1[a].x));
            t_near = t_near.max_or_rhs((n * s0).min_or_rhs(n * s1));
            t_far = t_far.min_or_rhs((f * s0).max_or_rhs(f * s1));
        }
        L::bits(t_near.le(t_far * L::splat(ROBUST_FAR_SCALE)))
    }

    /// [`PacketSlab::interval_reaches16`] of the eight runs `8h..8h + 8` of `rb` (`h` = 0, 1)
    /// at once in the lanes of `M` (eight lanes: one AVX register per axis and bound with
    /// [`crate::cast::lanes256::Y8`]): the same products and selects in the same order, so
    /// bit `r` is bit `8h + r` of the sixteen-run test (tested below). Every bit without an
    /// interval.
    #[inline(always)]
    pub(super) fn interval_reaches8<M: LaneReduce>(
        &self,
        rb: &RunBoxes16,
        h: usize,
        lim: f32,
    ) -> u32 {
        debug_assert_eq!(M::N, 8);
        let Some(iv) = &self.interval else {
            return 0xFF;
        };
        let k = (h & 1) * 8;
        let mut t_near = M::splat(0.0);
        let mut t_far = M::splat(lim);
        for a in 0..3 {
            let (lo, hi) = (M::load_n(&rb.lo[a][k..]), M::load_n(&rb.hi[a][k..]));
            let (n, f) = if iv.sneg[a] { (hi, lo) } else { (lo, hi) };
            let (s0, s1) = (M::splat(iv.s0[a].x), M::splat(iv.s1[a].x));
            t_near = t_near.max_or_rhs((n * s0).min_or_rhs(n * s1));
            t_far = t_far.min_or_rhs((f * s0).max_or_rhs(f * s1));
        }
        M::bits(t_near.le(t_far * M::splat(ROBUST_FAR_SCALE)))
    }

    /// The interval test of run group `g` of `L::RUN_GROUP` runs (`runs16[g]`, half `g % 2`
    /// of `runs16[g / 2]`, or quarter `g % 4` of `runs16[g / 4]`) at `lim`: bit `r` for run
    /// `g * RUN_GROUP + r` (runs past the list's end may be set).
    #[inline(always)]
    pub(super) fn reach_group(&self, runs16: &[RunBoxes16], g: usize, lim: f32) -> u32
    where
        L: LaneReduce,
    {
        if L::RUN_GROUP == 16 {
            return self.interval_reaches16(&runs16[g], lim);
        }
        // Eight runs only for `Y16` (x86-64, inside its AVX2 entry point).
        #[cfg(target_arch = "x86_64")]
        if L::RUN_GROUP == 8 {
            return self.interval_reaches8::<crate::cast::lanes256::Y8>(&runs16[g / 2], g % 2, lim);
        }
        self.interval_reaches4(&runs16[g / 4], g % 4, lim)
    }

    /// The BVH's robust slab test (Ize 2013 far scaling) of the packet on a run's box: true
    /// when a lane of `valid` reaches the box before `box_lim` (its closest hit so far).
    #[inline(always)]
    pub(super) fn reaches(&self, seg: &Segment, box_lim: L, valid: u32) -> bool {
        let (inv, neg) = (&self.inv, &self.neg);
        let (tnx, tfx) = slab(seg.lo.x, seg.hi.x, inv[0], neg[0]);
        let (tny, tfy) = slab(seg.lo.y, seg.hi.y, inv[1], neg[1]);
        let (tnz, tfz) = slab(seg.lo.z, seg.hi.z, inv[2], neg[2]);
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, L::splat(0.0))));
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, box_lim)));
        L::bits(t_near.le(t_far * L::splat(ROBUST_FAR_SCALE))) & valid != 0
    }
}

/// Work counters of the set-up kernel.
#[derive(Clone, Copy, Debug, Default)]
pub struct SetupWork {
    pub rays: u64,
    /// Packet-triangle tests (one per packet of `lanes` rays and set-up triangle).
    pub tri_tests: u64,
    /// Ray-triangle tests (valid lanes of the packet-triangle tests).
    pub pair_tests: u64,
    /// Watertight tests run in the band (edge or depth uncertain), per ray and triangle.
    pub exact_tests: u64,
    /// Watertight tests of winners for their bit-exact `t`.
    pub final_tests: u64,
    /// Of `exact_tests`: edge value within the band (the rest: depth band).
    pub edge_band: u64,
    /// Rays re-decided by the exact scan (a certain decision contradicted; expected 0).
    pub rescues: u64,
    /// Packet-triangle tests the affine packet test decided: all rays out / all rays in.
    pub packet_out: u64,
    pub packet_in: u64,
    /// Tiles swept (`cast/setup/sweep.rs`) instead of walked.
    pub swept: u64,
}

impl SetupWork {
    /// Adds `o`'s counters to these.
    pub fn add(&mut self, o: &Self) {
        self.rays += o.rays;
        self.tri_tests += o.tri_tests;
        self.pair_tests += o.pair_tests;
        self.exact_tests += o.exact_tests;
        self.final_tests += o.final_tests;
        self.edge_band += o.edge_band;
        self.rescues += o.rescues;
        self.packet_out += o.packet_out;
        self.packet_in += o.packet_in;
        self.swept += o.swept;
    }
}

#[cfg(test)]
mod tests;
