//! The set-up sample test with exact coverage only ([`crate::SetupExactness::Edges`], the
//! default): HVVR's per-tile set-up test (Hunt et al. 2018, §5.5, `cast/setup/mod.rs`) with the
//! edge uncertainty band of `cast/setup/mod.rs` ("exact band") and HVVR's own depth rule.
//!
//! - **Coverage exact.** A (ray, triangle) pair whose smallest edge value lies within the
//!   band `TriSetup::bound |d|_inf` is decided by the BVH's watertight test (Woop et al.
//!   2013); outside the band the float sign is certain. So coverage equals per-ray
//!   traversal's: no vertex hole, every shared edge given to the triangle(s) the watertight
//!   test gives it. The common path adds one compare (`m > bound`) to HVVR's sign test; the
//!   second compare (`m >= -bound`) runs only for packets with a candidate lane not certainly
//!   inside.
//! - **Depth by `1/t = g . d`** as HVVR (§5.5) and the kernel before the band: the largest
//!   `g . d` wins, equal values go to the lower triangle index; the winner's `t` is
//!   `1 / (g . d)`. Candidates whose `1/t` differ by less than the float error of `g . d`
//!   (relative `rho`, ~1e-6 for well-conditioned triangles) can be ordered differently from
//!   the watertight `t`: these *depth ties* (overlapping coplanar faces, triangles meeting at
//!   the hit point) are the only differences from per-ray traversal (tests/cast.rs:
//!   >= 99.99% agreement, every difference within 1e-5 relative in `t`, never hit vs miss).
//! - **Affine packet test first** (`cast/setup/affine.rs`, pinhole and stereo tiles): before
//!   `g . d`, the edge functions' affine form over the packet's film box decides the whole
//!   packet — every lane certainly outside (skipped) or certainly inside (no per-lane edge
//!   test) — with a rigorous error bound; partial packets take the per-lane test below. The
//!   decisions equal the watertight test's, so the buffer is unchanged (`tests/affine.rs`).
//!   The walk classifies an entered run's triangles (16 at a time) in one pass without
//!   branches (`PacketBox::classify_bits`: the class changes from triangle to triangle, so a
//!   branch per triangle would often be mispredicted), then visits only those not out, by
//!   their bits, in list order.
//! - **Edges first at 1 spp** (`edges_first`, the full 1-spp packets of `run_setup`): a 1-spp
//!   packet is a block of 4 x 4 pixels, and most triangles that reach it cover none of its
//!   lanes, while few fail the depth test (`g . d >= best`) on every lane. So there the edge
//!   values come before `g . d`, and a triangle with no valid lane within or above the band
//!   is skipped without its depth test (`kernel.rs` `edge_reach`); per lane the same compares
//!   of the same values decide, in another order. At 16 spp (one pixel per packet, most later
//!   triangles behind the best) the depth test stays first.
//! - **Lazy band.** The tile's triangles are set up with a crude conservative band (enough
//!   for the corner classification); a triangle's full band (and its depth condition `rho`)
//!   is computed when a packet first enters its run, for the whole run four triangles at a
//!   time (`refine_run` in `cast/setup/tile.rs`, bit-identical to `TileTris::refine`), so
//!   triangles dropped all-out or in runs never entered skip the band analysis.
//! - Ill-conditioned triangles (`rho > RHO_MAX`: seen nearly edge-on, or their plane nearly
//!   through the origin, where `g . d` may even have the wrong sign) take the watertight
//!   test for coverage and depth (their `1/t` is the watertight `t`'s), so they cannot turn
//!   a hit into a miss.
//!
//! - **The result does not depend on the triangle order.** Per lane the kernel returns the
//!   maximum, over the triangles that cover the lane (coverage decided exactly, above), of
//!   the pair `(1/t, -triangle index)` in lexicographic order, with `1/t` the lane's `g . d`
//!   (the watertight `1/t` for ill-conditioned triangles) and only positive `1/t` counted: a
//!   triangle replaces the best iff its value is larger, or equal with a lower index. Each
//!   pair is a fixed function of the float ray and the set-up triangle, and a maximum is
//!   order-independent, so visiting the triangles in any order, or skipping any whose pair
//!   cannot exceed the best (the early exit by near depth, the run boxes' slab and interval
//!   tests at the best's `t`), gives the same buffer bit for bit. This is why the packet
//!   widths (4, 8, 16 lanes) and the run walk below agree, and what a walk with the tile's
//!   triangles outside and its packets inside would rely on.
//! - **Run walk.** The runs (one per leaf, near-depth order) are tested `RUN_GROUP` at a
//!   time by the packet's interval test (`kernel.rs`: 4 runs per SSE register, 8 per AVX
//!   register, 16 per AVX-512 register), and only the runs it passes are visited, by their bits; a run is
//!   tested again alone (16-run groups: the rest of the group in one pass) after the best
//!   so far moved its limit. The early exit is checked at each group's first run and at
//!   every visited run: the runs' near depths ascend, so the walk stops before the same
//!   first entered run as a check at every run (the same work counters).
//!
//! [`crate::SetupExactness::Full`] (`cast/setup/mod.rs`) adds the depth band and the watertight
//! `t` of every winner: bit-identical to per-ray traversal, at ~1.5x the cost of this kernel
//! (measurements in `docs/notes/vr.md`).

use parallax_bvh::Tri4;
use parallax_core::math::WatertightRay;
use parallax_core::simd::Lanes;

use super::affine::{CLASS_IN, CLASS_OUT, PacketBox, PacketClass};
use super::bands::refine_run;
use super::kernel::{PacketSlab, SetupWork, dot_n, edge_band, edge_reach, min_edge};
use super::tri::{RHO_MAX, TileTris, TriSetup, exact_t, exact_t_lanes, splat_vertices};
use crate::cast::lanes16::LaneReduce;
use crate::cast::packet::{ClosestN, MAX_LANES, RaysN};

/// The closest hit of every lane of `rays` against the set-up list (module docs); `axis` /
/// `sign` are the tile beam's dominant axis (the near-depth order), `slack` the early-exit
/// slack.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn closest_edges<L: LaneReduce>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    tt: &mut TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    pbox: Option<&PacketBox>,
    edges_first: bool,
    work: &mut SetupWork,
) -> ClosestN {
    let valid = rays.valid;
    let zero = L::splat(0.0);
    let perm = tt.perm;
    let mut best = zero;
    let mut out = ClosestN {
        t: [f32::INFINITY; MAX_LANES],
        tri: [u32::MAX; MAX_LANES],
    };
    let mut hit_lanes = 0u32;
    let mut exit_depth = f32::INFINITY;
    let oa = tt.origin[axis];
    let mut box_lim = L::splat(f32::INFINITY);
    let one = L::splat(1.0);
    let packet = PacketSlab::with_interval(rays.d);
    let valid_m = if valid == (1 << L::N) - 1 {
        zero.eq(zero)
    } else {
        L::from_fn(|l| (valid >> l & 1) as f32).gt(zero)
    };
    let (sign_v, oa_v) = (L::splat(sign), L::splat(oa));
    let mut lim_max = f32::INFINITY;
    let dinf = packet.dinf;
    // (A full packet without a population count: the baseline x86-64 target has no
    // `popcnt`, its bit-trick expansion is ~15 instructions.)
    let lanes = if valid == (1 << L::N) - 1 {
        L::N as u64
    } else {
        valid.count_ones() as u64
    };
    // The run walk (module docs): the interval test of the group's runs at `run_lim` (one
    // pass, `reach_group`), then only the runs it passes, bit by bit. `lim_max` only
    // decreases and the test is monotone in it, so a run failing at `run_lim` fails at
    // `lim_max`; a run passing is tested again if `lim_max` changed since.
    let nseg = tt.segs.len();
    let group = L::RUN_GROUP;
    let interval = packet.has_interval();
    let mut base = 0usize;
    'walk: while base < nseg {
        if hit_lanes == valid && tt.segs[base].near > exit_depth + slack {
            break;
        }
        let g = base / group;
        let count = (nseg - base).min(group);
        let mut run_lim = lim_max;
        let mut bits = if interval {
            packet.reach_group(&tt.runs16, g, lim_max)
        } else {
            u32::MAX
        };
        bits &= (1u32 << count) - 1;
        let gbase = base;
        base += group;
        while bits != 0 {
            if group == 16 && run_lim != lim_max {
                run_lim = lim_max;
                bits &= packet.reach_group(&tt.runs16, g, lim_max);
                if bits == 0 {
                    break;
                }
            }
            let si = gbase + bits.trailing_zeros() as usize;
            bits &= bits - 1;
            // (The run's box is read only when tested: a copy of the segment costs more.)
            let (near, end) = (tt.segs[si].near, tt.segs[si].end as usize);
            if hit_lanes == valid && near > exit_depth + slack {
                break 'walk;
            }
            // The BVH's robust slab test (Ize 2013 far scaling) of the packet on the run's
            // box: the packet's interval test first (above); 16-lane packets skip the per-lane
            // test behind it (fewer instructions, measured: docs/notes/vr.md).
            let reach = if interval {
                (run_lim == lim_max || packet.interval_reaches(&tt.segs[si], lim_max))
                    && (L::N >= 16 || packet.reaches(&tt.segs[si], box_lim, valid))
            } else {
                packet.reaches(&tt.segs[si], box_lim, valid)
            };
            if !reach {
                continue;
            }
            let first = if si == 0 {
                0
            } else {
                tt.segs[si - 1].end as usize
            };
            work.tri_tests += (end - first) as u64;
            work.pair_tests += (end - first) as u64 * lanes;
            let mut changed = false;
            // The full bands of the run's lazy triangles, four at a time (every triangle of an
            // entered run is reached: the loop below never stops early).
            if tt.tris[first].rho.is_nan() {
                refine_run(tt, first, end, blocks);
            }
            // The run's triangles and affine forms as slices of one length: no bounds check
            // per triangle.
            let tris = &tt.tris[first..end];
            let affs = match pbox {
                Some(_) => &tt.aff[first..end],
                None => &[],
            };
            match pbox {
                // The affine packet test (`affine.rs`) of up to 32 triangles of the run in one
                // pass without branches (every lane certainly out or in; a partial packet's
                // edges certainly inside for every lane, `skip`, take no per-lane test), then
                // the triangles not out, by their bits.
                Some(pb) => {
                    let mut c0 = 0;
                    loop {
                        let n = (tris.len() - c0).min(16);
                        let (ts, fs) = (&tris[c0..c0 + n], &affs[c0..c0 + n]);
                        // Per triangle `k` of the chunk: 4 bits of class word at `4 k`
                        // (`CLASS_IN` or the skip bits), bit `k` of `live` if not out.
                        let mut codes = 0u64;
                        let mut live = 0u32;
                        for k in 0..n {
                            let (tr, a) = (&ts[k], &fs[k]);
                            let code = pb.classify_bits(a, tr.bound);
                            // (All-in triangles: partial, no edge skipped.)
                            let code = if tr.all_in { 0 } else { code };
                            codes |= ((code & 15) as u64) << (4 * k);
                            live |= ((code != CLASS_OUT) as u32) << k;
                        }
                        work.packet_out += (n as u32 - live.count_ones()) as u64;
                        while live != 0 {
                            let k = live.trailing_zeros() as usize;
                            live &= live - 1;
                            let code = (codes >> (4 * k)) as u32 & 15;
                            let class = if code == CLASS_IN {
                                PacketClass::In
                            } else {
                                PacketClass::Partial
                            };
                            changed |= test_tri(
                                rays,
                                blocks,
                                &ts[k],
                                perm,
                                class,
                                code & 7,
                                edges_first,
                                valid_m,
                                dinf,
                                &mut best,
                                &mut out.tri,
                                work,
                            );
                        }
                        c0 += 16;
                        if c0 >= tris.len() {
                            break;
                        }
                    }
                }
                None => {
                    for tr in tris {
                        changed |= test_tri(
                            rays,
                            blocks,
                            tr,
                            perm,
                            PacketClass::Partial,
                            0,
                            edges_first,
                            valid_m,
                            dinf,
                            &mut best,
                            &mut out.tri,
                            work,
                        );
                    }
                }
            }
            if changed {
                // `1 / best` once per packet (the same IEEE division as per lane); a lane has a
                // hit iff its best `1/t` is positive (every win raises `best` above 0).
                box_lim = one / best;
                hit_lanes = L::bits(best.gt(zero)) & valid;
                let depth = sign_v * (oa_v + box_lim * rays.d[axis]);
                exit_depth = L::select(valid_m, depth, L::splat(f32::NEG_INFINITY)).hmax();
                lim_max = L::select(valid_m, box_lim, L::splat(f32::NEG_INFINITY)).hmax();
            }
        }
    }
    // Hit lanes: `t = 1 / best` (= `box_lim`); the others keep `inf`.
    if hit_lanes != 0 {
        let hit_m = L::and(best.gt(zero), valid_m);
        L::select(hit_m, box_lim, L::splat(f32::INFINITY)).write(&mut out.t);
    }
    out
}

/// One packet (`rays`, lanes `valid` as a mask `valid_m`, `|d|_inf` `dinf`) against the set-up
/// triangle `tr` with the affine class `class` and skipped edges `skip`
/// (`PacketClass::Partial` and 0 without the affine test; `PacketClass::In`: every lane
/// certainly inside): raises `best` (`1/t` per lane) and `tri` where it wins (module docs,
/// "the result does not depend on the triangle order"). Returns whether a lane changed.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn test_tri<L: LaneReduce>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    tr: &TriSetup,
    perm: Option<[usize; 3]>,
    class: PacketClass,
    skip: u32,
    edges_first: bool,
    valid_m: L::M,
    dinf: f32,
    best: &mut L,
    tri: &mut [u32; MAX_LANES],
    work: &mut SetupWork,
) -> bool {
    let valid = rays.valid;
    let [dx, dy, dz] = rays.d;
    if tr.rho > RHO_MAX {
        // Ill-conditioned: the watertight test decides coverage and depth.
        return ill_conditioned(rays, blocks, tr, perm, valid, dinf, best, tri, work);
    }
    // Edges first (module docs): the triangle is skipped when no valid lane is
    // within or above the band, before its `g . d`.
    let edges = if edges_first && class != PacketClass::In && !tr.all_in {
        let e = edge_reach(tr, rays.d, dinf, valid, 7 & !skip);
        if e.1 == 0 {
            return false;
        }
        Some(e)
    } else {
        None
    };
    let gd = dot_n(tr.g, dx, dy, dz);
    let ge = gd.ge(*best);
    let cand = L::bits(ge) & valid;
    if cand == 0 {
        return false;
    }
    // Certainly inside (a mask), plus the band's lanes the watertight test accepts.
    let (inn_m, mut unsure) = if class == PacketClass::In {
        work.packet_in += 1;
        (ge, 0)
    } else if let Some((inside, maybe)) = edges {
        let inn_m = L::and(ge, inside);
        (inn_m, maybe & cand & !L::bits(inn_m))
    } else {
        edge_band(tr, rays.d, dinf, ge, cand, 7 & !skip)
    };
    let mut extra = 0u32;
    // Within the edge band: the watertight test decides coverage (~0.2% of pairs).
    if unsure != 0 {
        work.edge_band += unsure.count_ones() as u64;
        work.exact_tests += unsure.count_ones() as u64;
    }
    while unsure != 0 {
        let l = unsure.trailing_zeros() as usize;
        unsure &= unsure - 1;
        let wt = &WatertightRay::new(&rays.lane(l));
        if exact_t(wt, blocks, tr.src).is_some() {
            extra |= 1 << l;
        }
    }
    let ib = (L::bits(inn_m) & valid) | extra;
    if ib == 0 {
        return false;
    }
    let gt_m = L::and(inn_m, gd.gt(*best));
    let gt = L::bits(gt_m) & valid;
    // (The second mask only for band lanes the watertight test accepted: rare.)
    let mut win = if extra == 0 {
        gt
    } else {
        gt | (extra & L::bits(gd.gt(*best)))
    };
    // Ties (equal `1/t`, a hit so far): the lower triangle index wins.
    let mut tie = ib & !win;
    while tie != 0 {
        let l = tie.trailing_zeros() as usize;
        tie &= tie - 1;
        if tri[l] != u32::MAX && tr.tri < tri[l] {
            win |= 1 << l;
        }
    }
    if win == 0 {
        return false;
    }
    if win == gt {
        // The winners are the mask's valid lanes: one blend each.
        *best = L::select(gt_m, gd, *best);
        L::set_u32(L::and(gt_m, valid_m), tr.tri, tri);
    } else {
        *best = L::from_fn(|l| {
            if win >> l & 1 != 0 {
                gd.get(l)
            } else {
                best.get(l)
            }
        });
        let mut w = win;
        while w != 0 {
            let l = w.trailing_zeros() as usize;
            w &= w - 1;
            tri[l] = tr.tri;
        }
    }
    true
}

/// An ill-conditioned triangle (`rho > RHO_MAX`) against every lane: certainly-out lanes
/// (edge value below minus the band) skip it, the others take the watertight test, whose
/// `t` is compared as `1/t` with the lane's best. Returns whether a lane's best changed.
/// Where the tile's rays share one permutation (`perm`, `TileTris::perm`) the test runs in
/// lanes ([`exact_t_lanes`], the scalar test's operations); lanes with an exactly-zero edge
/// function, and every lane without `perm`, take the scalar test.
/// Inlined into its callers: a separate copy is compiled without the entry point's target
/// features, and every lane operation in it becomes an out-of-line intrinsic call
/// (`tools/hot_calls.py` checks).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn ill_conditioned<L: Lanes>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    tr: &crate::cast::setup::TriSetup,
    perm: Option<[usize; 3]>,
    valid: u32,
    dinf: f32,
    best: &mut L,
    tri: &mut [u32; MAX_LANES],
    work: &mut SetupWork,
) -> bool {
    let mut maybe = valid;
    if !tr.all_in {
        let m = min_edge(&tr.n, rays.d);
        maybe &= L::bits(m.ge(L::splat(-tr.bound * dinf)));
    }
    if maybe == 0 {
        return false;
    }
    work.exact_tests += maybe.count_ones() as u64;
    // The lanes' watertight `t` where the test accepts the ray (`hits`).
    let (mut hits, mut scalar, mut tv) = (0u32, maybe, L::splat(f32::NAN));
    if let Some(perm) = perm {
        let (zero, hit, t) = exact_t_lanes(rays, perm, &splat_vertices(blocks, tr.src));
        (hits, scalar, tv) = (hit & maybe, maybe & zero, t);
    }
    let (mut scalar_t, mut scalar_hits) = ([0.0f32; MAX_LANES], 0u32);
    while scalar != 0 {
        let l = scalar.trailing_zeros() as usize;
        scalar &= scalar - 1;
        if let Some(tc) = exact_t(&WatertightRay::new(&rays.lane(l)), blocks, tr.src) {
            scalar_t[l] = tc;
            scalar_hits |= 1 << l;
        }
    }
    hits |= scalar_hits;
    let mut changed = false;
    while hits != 0 {
        let l = hits.trailing_zeros() as usize;
        hits &= hits - 1;
        let tc = if scalar_hits >> l & 1 != 0 {
            scalar_t[l]
        } else {
            tv.get(l)
        };
        let g = 1.0 / tc;
        let b = best.get(l);
        if g > b || (g == b && tri[l] != u32::MAX && tr.tri < tri[l]) {
            *best = L::from_fn(|i| if i == l { g } else { best.get(i) });
            tri[l] = tr.tri;
            changed = true;
        }
    }
    changed
}
