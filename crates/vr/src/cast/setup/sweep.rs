//! The sweep: the set-up sample test with the tile's triangles outside and its packets
//! inside (Hunt et al. 2018, §5.5: HVVR's GPU kernel loops over a tile's triangles per
//! thread). For the 16-subsample packets of pinhole and stereo tiles
//! ([`crate::SetupExactness::Edges`]), instead of walking the tile's runs once per packet
//! (`edges.rs`), every packet of the tile is generated once ([`TilePackets`]) and each
//! set-up triangle is swept over all of them:
//!
//! - **The affine test across packets.** A triangle's affine packet test
//!   (`affine.rs`) runs on sixteen packets at once, one lane per packet
//!   ([`BoxLanes::classify`]: the same float operations as `PacketBox::classify_bits`, so the
//!   same class per packet); only the packets not certainly outside take the per-lane test
//!   (`edges::test_tri`, the walk's own), as in the walk.
//! - **The run-box test across packets.** Before a run's triangles, the walk's interval
//!   test of a packet on the run's box (`PacketSlab::interval_reaches`: the packet's
//!   reciprocal-direction interval, its largest closest-hit limit, the robust far scaling)
//!   runs on sixteen packets at once, one lane per packet, the run's box splatted
//!   ([`run_reaches`]); only the packets it passes meet the run's triangles. It is
//!   conservative as the walk's is (every lane's reciprocal lies in its packet's interval,
//!   float products are monotone), so it drops no hit. A packet's interval comes from bounds
//!   of its lanes' directions: for packets inside the film frame's region, bounds from the
//!   packet's affine box, sixteen packets at a time (`FilmFrame::dir_rows`: one pass instead
//!   of two horizontal reductions per packet, a slightly wider interval); for the others the
//!   lanes' own range.
//! - **The early exit per run.** Before each run (the tile's leaves in near-depth order) the
//!   packets whose every lane has a hit nearer than the run's near depth (plus the slack)
//!   leave the sweep, sixteen compares at once; the sweep ends when none is left. A packet's
//!   exit depth is brought up to date after each run that changed its best, as the walk does.
//! - **The same buffer.** The result of every lane is the maximum over the covering
//!   triangles of `(1/t, -index)` (`edges.rs`, "the result does not depend on the triangle
//!   order"), and a packet leaves only where no later triangle can exceed its best: the sweep
//!   writes what the walk writes, bit for bit (tests: `tests/sweep.rs`, and the
//!   casts of `tests/cast.rs`).
//!
//! What the walk pays per packet and the sweep does not: the packet's slab set-up (three
//! lane divisions), the run groups' interval tests and the loop over runs; the affine test
//! costs a lane per packet instead of a register. What the sweep pays instead: one row of
//! sixteen packets is the unit of work, so a row of which any packet reaches a run takes the
//! run-box test and each of the run's triangles' affine tests for all sixteen.
//! Measurements: `docs/notes/vr.md`.
//!
//! **Parameters:** none of its own; it runs for [`crate::CastOptions::sweep`] on tiles whose
//! packets are each one sample's chunk of sixteen subsamples with an affine box (otherwise the
//! walk runs).

use glam::Vec2;
use parallax_bvh::Tri4;
use parallax_core::math::ROBUST_FAR_SCALE;

use super::affine::{BoxLanes, CLASS_IN, CLASS_OUT, PacketBox, PacketClass};
use super::bands::refine_run;
use super::edges::test_tri;
use super::kernel::{SetupWork, finite, lane_dinf};
use super::out::Out;
use super::tile_packets::{Packet, TilePackets};
use super::tri::{Segment, TileTris};
use crate::SampleSet;
use crate::cast::lanes16::LaneReduce;
use crate::cast::packet::{ClosestN, MAX_LANES, RaysN, sample_chunk};
use parallax_core::simd::max_or_rhs;

/// Every lane of a packet.
const FULL: u32 = (1 << MAX_LANES) - 1;

/// The sweep of the tile `samples` (each `spp = chunks.len() * 16` subsamples: chunk `c` with
/// the offset lanes `chunks[c]` and offset range `ranges[c]`) over the set-up list `tt`, the
/// results to `out`. Returns `false`, having written nothing, when a packet has no chunk rays
/// or no affine box (the caller then runs the walk); `L::N` must be 16 and `tt.frame` set.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn sweep_edges<L: LaneReduce>(
    set: &SampleSet,
    blocks: &[Tri4],
    tt: &mut TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    samples: &[u32],
    chunks: &[(L, L)],
    ranges: &[(Vec2, Vec2)],
    out: Out,
    work: &mut SetupWork,
) -> bool {
    debug_assert_eq!(L::N, MAX_LANES);
    let Some(fr) = tt.frame else {
        return false;
    };
    if samples.len() * chunks.len() > ROWS_MAX * 16 {
        return false;
    }
    let mut pk = std::mem::take(&mut tt.packets);
    let ok = gen_packets(set, &fr, &mut pk, samples, chunks, ranges);
    if ok {
        sweep::<L>(blocks, tt, &mut pk, axis, sign, slack, work);
        write_packets::<L>(&pk, samples, chunks.len(), out);
        work.rays += (pk.packets.len() * MAX_LANES) as u64;
        work.swept += 1;
    }
    tt.packets = pk;
    ok
}

/// Every packet of the tile into `pk`: its chunk rays (`sample_chunk`), affine box and
/// reciprocal-direction interval (module docs, "the run-box test").
#[inline(always)]
fn gen_packets<L: LaneReduce>(
    set: &SampleSet,
    fr: &super::affine::FilmFrame,
    pk: &mut TilePackets,
    samples: &[u32],
    chunks: &[(L, L)],
    ranges: &[(Vec2, Vec2)],
) -> bool {
    let cps = chunks.len();
    pk.reset(samples.len() * cps);
    let mut p = 0;
    // The lanes' largest `|d|_inf` over the packets (`packet_dinf` of them all at once).
    let mut dinf = L::splat(0.0);
    for &i in samples {
        let s = &set.samples[i as usize];
        for (&(ox, oy), &(a, b)) in chunks.iter().zip(ranges) {
            let Some(rays) = sample_chunk::<L>(set, i, ox, oy, a.x, b.x) else {
                return false;
            };
            if rays.valid != FULL {
                return false;
            }
            // The film box of `packet_box` (`mod.rs`) from the chunk's offset range (the
            // footprint is finite and `>= 0`: `sample_chunk` gave rays).
            let (lo, hi) = (s.film + a * s.footprint, s.film + b * s.footprint);
            let region = fr.in_region(lo.x, hi.x, lo.y, hi.y);
            let Some(pb) = PacketBox::new_in(fr, region, lo.x, hi.x, lo.y, hi.y) else {
                return false;
            };
            let mut d = [[0.0; MAX_LANES]; 3];
            for (lanes, row) in rays.d.iter().zip(&mut d) {
                lanes.write(row);
            }
            pk.packets[p] = Packet::fresh(d);
            dinf = max_or_rhs(dinf, lane_dinf(rays.d));
            let row = &mut pk.boxes[p / 16];
            for (f, v) in pb.scalars().into_iter().enumerate() {
                row[f][p % 16] = v;
            }
            // The direction's range, turned into the interval row by row below: for packets
            // inside the frame's region bounded from their boxes sixteen at a time
            // (`FilmFrame::dir_rows`), for the others the lanes' own range.
            if !region {
                let [x, y, z] = rays.d;
                let (lo, hi) = (L::hmin4([x, y, z, z]), L::hmax4([x, y, z, z]));
                pk.own_range.push((p as u32, lo, hi));
            }
            p += 1;
        }
    }
    for (r, row) in pk.intervals[..p.div_ceil(16)].iter_mut().enumerate() {
        let b = &pk.boxes[r];
        // (No closure for the loads: it would call the lane loads out of line.)
        let (lo, hi) = fr.dir_rows([
            L::load16(&b[0]),
            L::load16(&b[1]),
            L::load16(&b[2]),
            L::load16(&b[3]),
        ]);
        for a in 0..3 {
            hi[a].write(&mut row[a]);
            lo[a].write(&mut row[3 + a]);
        }
    }
    for &(q, lo, hi) in &pk.own_range {
        let (row, k) = (&mut pk.intervals[q as usize / 16], q as usize % 16);
        for a in 0..3 {
            row[a][k] = hi[a];
            row[3 + a][k] = lo[a];
        }
    }
    for row in &mut pk.intervals[..p.div_ceil(16)] {
        intervals_of_row::<L>(row);
    }
    pk.dinf = dinf.hmax();
    true
}

/// Sixteen packets' reciprocal-direction intervals from their direction ranges, in place: row
/// `a` holds the largest `d` of axis `a` per packet and row `3 + a` the smallest on entry, and
/// `[1 / max d, 1 / min d]` on return, which is `[min 1/d, max 1/d]` over the lanes bit for
/// bit where every lane's `d` has one sign (an IEEE division is monotone in its divisor), as
/// `PacketSlab::with_interval` takes it; `(0, 0)` on every axis of a packet where on one axis
/// a lane's reciprocal is not finite or the signs differ (as the walk then has no interval
/// test). One division per axis and end for sixteen packets.
#[inline(always)]
fn intervals_of_row<L: LaneReduce>(row: &mut [[f32; 16]; 6]) {
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let mut ok = zero.eq(zero);
    let mut iv = [zero; 6];
    for a in 0..3 {
        let (hi, lo) = (L::load16(&row[a]), L::load16(&row[3 + a]));
        let (i0, i1) = (one / hi, one / lo);
        let one_sign = L::or(lo.gt(zero), hi.lt(zero));
        ok = L::and(ok, L::and(one_sign, L::and(finite(i0), finite(i1))));
        (iv[a], iv[3 + a]) = (i0, i1);
    }
    for (r, v) in row.iter_mut().zip(iv) {
        L::select(ok, v, zero).write(r);
    }
}

/// The walk's interval test (`PacketSlab::interval_reaches16`'s products and selects, one
/// lane per packet instead of per run) of the run box `seg` against the sixteen packets of
/// one row: their intervals `iv` ([`TilePackets::intervals`]) and limits `lim`. Bit `k` set
/// iff packet `k` may reach the box before its limit; set on every packet without an
/// interval (`(0, 0)` on every axis: entry 0, exit `min(lim, 0) = 0`).
#[inline(always)]
fn run_reaches<L: LaneReduce>(seg: &Segment, iv: &[[f32; 16]; 6], lim: &[f32; 16]) -> u32 {
    let zero = L::splat(0.0);
    let mut t_near = zero;
    let mut t_far = L::load16(lim);
    for a in 0..3 {
        let (i0, i1) = (L::load16(&iv[a]), L::load16(&iv[3 + a]));
        let neg = i1.lt(zero);
        let (lo, hi) = (L::splat(seg.lo[a]), L::splat(seg.hi[a]));
        let (n, f) = (L::select(neg, hi, lo), L::select(neg, lo, hi));
        t_near = t_near.max_or_rhs((n * i0).min_or_rhs(n * i1));
        t_far = t_far.min_or_rhs((f * i0).max_or_rhs(f * i1));
    }
    L::bits(t_near.le(t_far * L::splat(ROBUST_FAR_SCALE)))
}

/// The run-by-run sweep of `tt`'s set-up triangles over the packets `pk` (module docs).
#[inline(always)]
fn sweep<L: LaneReduce>(
    blocks: &[Tri4],
    tt: &mut TileTris,
    pk: &mut TilePackets,
    axis: usize,
    sign: f32,
    slack: f32,
    work: &mut SetupWork,
) {
    let np = pk.packets.len();
    let rows = np.div_ceil(16);
    let (origin, perm) = (tt.origin, tt.perm);
    let o = [L::splat(origin.x), L::splat(origin.y), L::splat(origin.z)];
    let zero = L::splat(0.0);
    let all = zero.eq(zero);
    let (sign_v, oa_v, one) = (L::splat(sign), L::splat(origin[axis]), L::splat(1.0));
    // The packets of each row still in the sweep, and those whose best changed in this run.
    let mut live = [0u32; ROWS_MAX];
    let mut dirty = [0u32; ROWS_MAX];
    debug_assert!(rows <= ROWS_MAX);
    let mut first = 0usize;
    for si in 0..tt.segs.len() {
        let (near, end) = (tt.segs[si].near, tt.segs[si].end as usize);
        let run = first..end;
        first = end;
        // The early exit: packets with every lane's hit nearer than the run's near depth.
        let near_v = L::splat(near);
        let mut any = 0u32;
        for (r, live_r) in live.iter_mut().enumerate().take(rows) {
            let exit = L::load16(pk.exit[16 * r..16 * r + 16].try_into().unwrap());
            // (The packets of row `r`: all sixteen but in the last row.)
            let present = FULL >> (16 - (np - 16 * r).min(16));
            *live_r = present & !L::bits(near_v.gt(exit + L::splat(slack)));
            any |= *live_r;
        }
        if any == 0 {
            break;
        }
        if run.is_empty() {
            continue;
        }
        // The run-box test of the live packets (module docs).
        let seg = &tt.segs[si];
        let mut reach = [0u32; ROWS_MAX];
        let mut reach_any = 0u32;
        for (r, (&live_r, reach_r)) in live.iter().zip(&mut reach).enumerate().take(rows) {
            if live_r != 0 {
                let lim = pk.lim[16 * r..16 * r + 16].try_into().unwrap();
                *reach_r = live_r & run_reaches::<L>(seg, &pk.intervals[r], lim);
                reach_any |= *reach_r;
            }
        }
        if reach_any == 0 {
            continue;
        }
        if tt.tris[run.start].rho.is_nan() {
            refine_run(tt, run.start, run.end, blocks);
        }
        let (tris, affs) = (&tt.tris[run.clone()], &tt.aff[run]);
        for (tr, aff) in tris.iter().zip(affs) {
            let small = aff.small();
            let rows_of = reach.iter().zip(dirty.iter_mut()).zip(&pk.boxes);
            for (r, ((&live_r, dirty_r), b)) in rows_of.enumerate() {
                if live_r == 0 {
                    continue;
                }
                // (All-in triangles: partial, no edge skipped, as in the walk.)
                let (mut test, cls) = if tr.all_in {
                    (live_r, None)
                } else {
                    let bl = BoxLanes {
                        xc: L::load16(&b[0]),
                        yc: L::load16(&b[1]),
                        rx: L::load16(&b[2]),
                        ry: L::load16(&b[3]),
                        ka: L::load16(&b[4]),
                        kb: L::load16(&b[5]),
                    };
                    let c = bl.classify(aff, tr.bound);
                    (live_r & !c.out, Some(c))
                };
                let n = live_r.count_ones();
                work.tri_tests += n as u64;
                work.pair_tests += n as u64 * MAX_LANES as u64;
                work.packet_out += (n - test.count_ones()) as u64;
                // (The row's packets: `rows` rows of sixteen but the last.)
                let row = &mut pk.packets[16 * r..(16 * r + 16).min(np)];
                while test != 0 {
                    let k = test.trailing_zeros();
                    test &= test - 1;
                    let code = match &cls {
                        Some(c) => c.code(k, small),
                        None => 0,
                    };
                    debug_assert_ne!(code, CLASS_OUT);
                    let class = if code == CLASS_IN {
                        PacketClass::In
                    } else {
                        PacketClass::Partial
                    };
                    let pkt = &mut row[k as usize];
                    let rays = RaysN {
                        o,
                        d: [
                            L::load16(&pkt.d[0]),
                            L::load16(&pkt.d[1]),
                            L::load16(&pkt.d[2]),
                        ],
                        valid: FULL,
                    };
                    let mut best = L::load16(&pkt.best);
                    if test_tri(
                        &rays,
                        blocks,
                        tr,
                        perm,
                        class,
                        code & 7,
                        false,
                        all,
                        pk.dinf,
                        &mut best,
                        &mut pkt.tri,
                        work,
                    ) {
                        best.write(&mut pkt.best);
                        *dirty_r |= 1 << k;
                    }
                }
            }
        }
        // The exit depths of the packets this run changed (the walk's `exit_depth`).
        for (r, dirty_r) in dirty.iter_mut().enumerate().take(rows) {
            while *dirty_r != 0 {
                let k = dirty_r.trailing_zeros() as usize;
                *dirty_r &= *dirty_r - 1;
                let p = 16 * r + k;
                let pkt = &pk.packets[p];
                let best = L::load16(&pkt.best);
                let hit = L::bits(best.gt(zero)) == FULL;
                // (`1 / best` is `+inf` on a lane without a hit: the walk's `lim_max`.)
                let lim = one / best;
                pk.lim[p] = lim.hmax();
                pk.exit[p] = if hit {
                    let d = L::load16(&pkt.d[axis]);
                    (sign_v * (oa_v + lim * d)).hmax()
                } else {
                    f32::INFINITY
                };
            }
        }
    }
}

/// Rows of sixteen packets a swept tile may hold: the pinhole and stereo tiles' rays from 16
/// spp ([`crate::hierarchy::tile_samples_of`]) in 16-lane packets.
const ROWS_MAX: usize = crate::hierarchy::SWEEP_TILE_RAYS / MAX_LANES / 16;

/// Every packet's closest hits to `out`: `t = 1 / best` where a lane has a hit, the walk's
/// `box_lim`.
#[inline(always)]
fn write_packets<L: LaneReduce>(pk: &TilePackets, samples: &[u32], cps: usize, out: Out) {
    let (zero, one) = (L::splat(0.0), L::splat(1.0));
    let inf = L::splat(f32::INFINITY);
    for (p, pkt) in pk.packets.iter().enumerate() {
        let b = L::load16(&pkt.best);
        let mut c = ClosestN {
            t: [0.0; MAX_LANES],
            tri: pkt.tri,
        };
        L::select(b.gt(zero), one / b, inf).write(&mut c.t);
        let (q, k) = (p / cps, p % cps);
        // SAFETY: the caller of `test_tile_setup` guarantees exclusive access to these
        // samples' entries; chunk `k` of sample `samples[q]` is entries `16 k..16 k + 16`.
        unsafe { out.run_streamed((samples[q], (k * MAX_LANES) as u32), &c) };
    }
    out.fence();
}

#[cfg(test)]
mod tests;
