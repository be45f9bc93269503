//! The watertight sample test four or eight subsample rays at a time
//! ([`crate::cast::SampleTest::Watertight`]; Hunt et al. 2018, §5.5): a packet is four (SSE,
//! glam `Vec4`) or eight (AVX2, behind runtime detection) consecutive subsample rays of a tile
//! (`packet.rs` generates them); the kernel is written once over the [`Lanes`] trait. If the
//! rays share the permutation of the watertight test (dominant axis and its sign, Woop et al.
//! 2013 §3) — all but a few packets on the diagonals of the image — each triangle is tested
//! against them with the exact f32 operations of `WatertightRay::intersect_within` per lane
//! (vertex coordinates splatted, ray constants per lane; exactly-zero edge functions fall back
//! to the scalar test), so every hit equals the per-ray BVH answer. Otherwise the packet's
//! rays take the one-ray path ([`crate::cast::intersect`]).
//!
//! Per leaf (near-depth order), the rays first run the robust slab test of the BVH on the
//! leaf's box (Ize 2013 far scaling; lanes already holding a closer hit skip it), and the packet
//! stops once every ray has a hit nearer than the next leaf's near depth along the beam axis.

use parallax_bvh::Tri4;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::Ray;
use parallax_core::math::{
    ROBUST_FAR_SCALE, WatertightRay, shear_vertex, watertight_lanes, watertight_permutation,
};
use parallax_core::simd::{F8, Lanes, max_or_rhs, min_or_rhs};

use crate::SampleSet;
use crate::beam::PreparedBeam;
use crate::cast::leaves::LeafBox;
use crate::cast::packet::{ClosestN, MAX_LANES, RaysN, gen_n};
use crate::cast::stored::RayBuffer;

/// Work counters of the packet kernel.
#[derive(Clone, Copy, Debug, Default)]
pub struct PacketWork {
    pub box_tests: u64,
    pub tri_tests: u64,
}

/// Tests the packet against the near-sorted `leaves`; `None` when the rays do not share one
/// watertight permutation (the caller then takes the one-ray path).
#[inline(always)]
fn closest_n<L: Lanes>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    leaves: &[LeafBox],
    beam: &PreparedBeam,
    slack: f32,
    work: &mut PacketWork,
) -> Option<ClosestN> {
    // Per-lane watertight set-up (Woop et al. 2013, §3, as `WatertightRay::new`); all lanes
    // must share (kx, ky, kz). The shear constants are divided lane-wise (the same IEEE
    // divisions); a scalar `WatertightRay` is only built for the exact-fallback lanes.
    let valid = rays.valid;
    let mut out = ClosestN {
        t: [f32::INFINITY; MAX_LANES],
        tri: [u32::MAX; MAX_LANES],
    };
    let mut perm = None;
    for l in 0..L::N {
        if valid >> l & 1 == 0 {
            continue;
        }
        let ray = rays.lane(l);
        // The packet kernel assumes `Ray::new`'s interval (0, inf); anything else takes the
        // one-ray path.
        if !(ray.is_valid() && ray.t_min == 0.0 && ray.t_max == f32::INFINITY) {
            return None;
        }
        let p = watertight_permutation(ray.dir);
        if *perm.get_or_insert(p) != p {
            return None;
        }
    }
    let Some([kx, ky, kz]) = perm else {
        return Some(out);
    };
    let one = L::splat(1.0);
    let zero = L::splat(0.0);
    let dkz = rays.d[kz];
    let sx = rays.d[kx] / dkz;
    let sy = rays.d[ky] / dkz;
    let sz = one / dkz;
    let t_min = zero;
    let (okx, oky, okz) = (rays.o[kx], rays.o[ky], rays.o[kz]);
    let inv = [one / rays.d[0], one / rays.d[1], one / rays.d[2]];
    let neg = [inv[0].lt(zero), inv[1].lt(zero), inv[2].lt(zero)];
    let a = beam.axis;
    let (oa, da) = (rays.o[a], rays.d[a]);
    let s = L::splat(beam.sign);
    let ordered = !beam.everything;
    // Per lane: the slab limit (closest t so far) and the triangle limit (next float above it).
    let mut box_lim = L::splat(f32::INFINITY);
    let mut tri_lim = L::splat(f32::INFINITY);
    let mut exit_depth = f32::INFINITY;
    let mut hit_lanes = 0u32;
    for lb in leaves {
        if ordered && hit_lanes == valid && lb.near > exit_depth + slack {
            break;
        }
        work.box_tests += 1;
        let b = &lb.bounds;
        let slab = |lo: f32, hi: f32, ax: usize| {
            let t0 = (L::splat(lo) - rays.o[ax]) * inv[ax];
            let t1 = (L::splat(hi) - rays.o[ax]) * inv[ax];
            (L::select(neg[ax], t1, t0), L::select(neg[ax], t0, t1))
        };
        let (tnx, tfx) = slab(b.min.x, b.max.x, 0);
        let (tny, tfy) = slab(b.min.y, b.max.y, 1);
        let (tnz, tfz) = slab(b.min.z, b.max.z, 2);
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, t_min)));
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, box_lim)));
        let m = L::bits(t_near.le(t_far * L::splat(ROBUST_FAR_SCALE))) & valid;
        if m == 0 {
            continue;
        }
        let (first, count) = (leaf_first(lb.leaf), leaf_count(lb.leaf));
        let mut changed = false;
        for j in 0..count {
            let blk = &blocks[(first + j / 4) as usize];
            let ln = (j % 4) as usize;
            let tri = blk.tri[ln];
            work.tri_tests += 1;
            // (A macro, not a closure: a closure here is compiled without the AVX2 entry
            // point's features and called out of line, three times per triangle.)
            macro_rules! proj {
                ($v:expr) => {{
                    let p = &blk.p[$v];
                    shear_vertex(
                        [
                            L::splat(p[kx][ln]),
                            L::splat(p[ky][ln]),
                            L::splat(p[kz][ln]),
                        ],
                        [okx, oky, okz],
                        [sx, sy, sz],
                    )
                }};
            }
            let (va, vb, vc) = (proj!(0), proj!(1), proj!(2));
            let r = watertight_lanes(va, vb, vc);
            let d = r.distance(va[2], vb[2], vc[2]);
            let exact = r.exact & m;
            let t = d.t;
            let in_range = L::bits(t.gt(t_min)) & L::bits(t.lt(tri_lim));
            let hit = r.same_sign & d.nonzero & in_range & m & !exact;
            let mut offer = |l: usize, tl: f32| {
                if out.tri[l] == u32::MAX || tl < out.t[l] || (tl == out.t[l] && tri < out.tri[l]) {
                    out.t[l] = tl;
                    out.tri[l] = tri;
                    changed = true;
                }
            };
            let mut hm = hit;
            while hm != 0 {
                let l = hm.trailing_zeros() as usize;
                hm &= hm - 1;
                offer(l, t.get(l));
            }
            let mut em = exact;
            while em != 0 {
                let l = em.trailing_zeros() as usize;
                em &= em - 1;
                let wt = WatertightRay::new(&rays.lane(l));
                let vtx = |q: usize| blk.vertex(ln, q);
                if let Some(hh) = wt.intersect_within(vtx(0), vtx(1), vtx(2), tri_lim.get(l)) {
                    offer(l, hh.t);
                }
            }
            if changed {
                tri_lim = L::from_fn(|l| {
                    if out.tri[l] != u32::MAX {
                        out.t[l].next_up()
                    } else {
                        f32::INFINITY
                    }
                });
                box_lim = L::from_fn(|l| out.t[l]);
            }
        }
        if changed {
            hit_lanes = 0;
            let bt = L::from_fn(|l| out.t[l]);
            let depth = s * (oa + bt * da);
            exit_depth = f32::NEG_INFINITY;
            for l in 0..L::N {
                if valid >> l & 1 != 0 {
                    if out.tri[l] != u32::MAX {
                        hit_lanes |= 1 << l;
                    }
                    exit_depth = exit_depth.max(depth.get(l));
                }
            }
        }
    }
    Some(out)
}

/// The body of [`run_packets`] and [`run_packets_avx2`], written into each: the per-packet
/// closure it hands to [`for_each_packet`] holds the whole packet kernel, and a closure is
/// compiled with the target features of the function it is written in — inside a shared
/// generic helper it stayed a baseline-compiled function called once per packet from the
/// AVX2 entry point, which made the 8-lane tier slower than the 4-lane one
/// (`docs/notes/vr.md`, 2026-12-06).
macro_rules! run_packets_body {
    ($l:ty, $set:expr, $blocks:expr, $leaves:expr, $beam:expr, $slack:expr, $total:expr,
     $pair:expr, $write:expr, $fallback:expr) => {{
        let (blocks, leaves, beam, slack) = ($blocks, $leaves, $beam, $slack);
        let (mut write, mut fallback) = ($write, $fallback);
        let mut pw = PacketWork::default();
        let rays_n =
            for_each_packet::<$l>($set, None, $total, $pair, |batch, rays| {
                match closest_n(rays, blocks, leaves, beam, slack, &mut pw) {
                    Some(c) => {
                        for (l, &p) in batch.iter().enumerate() {
                            write(p, c.t[l], c.tri[l]);
                        }
                    }
                    None => {
                        for (l, &p) in batch.iter().enumerate() {
                            let (bt, tri) = if rays.valid >> l & 1 != 0 {
                                fallback(&rays.lane(l))
                            } else {
                                (f32::INFINITY, u32::MAX)
                            };
                            write(p, bt, tri);
                        }
                    }
                }
            });
        (pw, rays_n)
    }};
}

/// Runs every subsample ray `0..total` of a tile (`pair(j)` = its `(sample, k)`) through the
/// packet kernel with `L::N` lanes; `write(j, t, tri)` stores a result and `fallback(ray)`
/// answers rays of packets the kernel declines.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_packets<L: Lanes>(
    set: &SampleSet,
    blocks: &[Tri4],
    leaves: &[LeafBox],
    beam: &PreparedBeam,
    slack: f32,
    total: usize,
    pair: impl Fn(usize) -> (u32, u32),
    write: impl FnMut((u32, u32), f32, u32),
    fallback: impl FnMut(&Ray) -> (f32, u32),
) -> (PacketWork, u64) {
    run_packets_body!(
        L, set, blocks, leaves, beam, slack, total, pair, write, fallback
    )
}

/// Cuts subsample rays `0..total` of a tile (`pair(j)` = its `(sample, k)`) into packets of
/// `L::N` lanes (the last one partial), generates each packet's rays (or reads them from
/// `stored`) and hands both to `f`.
/// Returns the number of valid rays.
#[inline(always)]
pub(crate) fn for_each_packet<L: Lanes>(
    set: &SampleSet,
    stored: Option<&RayBuffer>,
    total: usize,
    pair: impl Fn(usize) -> (u32, u32),
    mut f: impl FnMut(&[(u32, u32)], &RaysN<L>),
) -> u64 {
    let mut rays_n = 0u64;
    let mut pairs = [(0u32, 0u32); MAX_LANES];
    let mut j = 0;
    while j < total {
        let n = (total - j).min(L::N);
        for (l, p) in pairs.iter_mut().enumerate().take(n) {
            *p = pair(j + l);
        }
        j += n;
        let batch = &pairs[..n];
        let rays = gen_n::<L>(set, stored, batch);
        rays_n += rays.valid.count_ones() as u64;
        f(batch, &rays);
    }
    rays_n
}

/// [`run_packets`] with eight AVX lanes (and the AVX2 tier's bit instructions: the lane
/// counts by `popcnt`).
///
/// # Safety
/// The CPU must support the AVX2 tier ([`crate::cast::isa::avx2_detected`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn run_packets_avx2(
    set: &SampleSet,
    blocks: &[Tri4],
    leaves: &[LeafBox],
    beam: &PreparedBeam,
    slack: f32,
    total: usize,
    pair: impl Fn(usize) -> (u32, u32),
    write: impl FnMut((u32, u32), f32, u32),
    fallback: impl FnMut(&Ray) -> (f32, u32),
) -> (PacketWork, u64) {
    run_packets_body!(
        F8, set, blocks, leaves, beam, slack, total, pair, write, fallback
    )
}
