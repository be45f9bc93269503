//! The set-up sample test made bit-identical to per-ray traversal
//! ([`crate::SetupExactness::Full`], `--visibility beam-exact`): HVVR's per-tile set-up test
//! (Hunt et al. 2018, §5.5, `cast/setup/mod.rs`) with the edge uncertainty band of `cast/setup/mod.rs`
//! ("exact band", as [`crate::SetupExactness::Edges`] in `cast/setup/edges.rs`), plus a *depth*
//! band — candidates whose `1/t` lies within the float error of the best are ordered by their
//! watertight `t` and the BVH's tie-break — and the watertight `t` of every winner, so the
//! same triangle gives the same `t` bit for bit. Ours, beyond HVVR; ~1.5x the cost of the
//! default `Edges` kernel (measurements in `docs/notes/vr.md`).

use glam::Vec3;
use parallax_bvh::Tri4;
use parallax_core::math::{WatertightRay, watertight_permutation};
use parallax_core::simd::Lanes;

use super::kernel::{PacketSlab, SetupWork, dot_n, edge_band};
use super::tri::{
    RHO_EXACT, RHO_MAX, TileTris, U, exact_closest, exact_t, exact_t_lanes, splat_vertices,
};
use crate::cast::packet::{ClosestN, MAX_LANES, RaysN};

/// Per-lane state of the best hit so far: `1/t` (lanes), its band, and the triangle.
struct BestN<L> {
    gd: L,
    rho: L,
    tri: [u32; MAX_LANES],
    /// Index in the tile's set-up list.
    idx: [u32; MAX_LANES],
    /// The exact watertight `t`, when known (NaN otherwise).
    t: [f32; MAX_LANES],
}

/// `x` with lane `l` replaced by `v`.
#[inline(always)]
fn set_lane<L: Lanes>(x: L, l: usize, v: f32) -> L {
    L::from_fn(|i| if i == l { v } else { x.get(i) })
}

/// The closest hit of every lane of `rays` against the set-up list (module docs); `axis` /
/// `sign` are the tile beam's dominant axis (the near-depth order), `slack` the early-exit
/// slack. Returns per lane the closest triangle and its watertight `t`.
#[inline(always)]
pub(super) fn closest_full<L: Lanes>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    tt: &TileTris,
    axis: usize,
    sign: f32,
    slack: f32,
    work: &mut SetupWork,
) -> ClosestN {
    let valid = rays.valid;
    let zero = L::splat(0.0);
    let [dx, dy, dz] = rays.d;
    let mut best = BestN {
        gd: zero,
        rho: zero,
        tri: [u32::MAX; MAX_LANES],
        idx: [u32::MAX; MAX_LANES],
        t: [f32::NAN; MAX_LANES],
    };
    // Lanes whose best so far was contradicted by the watertight test (a bound violation,
    // expected never): re-decided by the exact scan at the end.
    let mut suspect = 0u32;
    let mut hit_lanes = 0u32;
    let mut exit_depth = f32::INFINITY;
    let mut start = 0usize;
    let oa = tt.origin[axis];
    let mut box_lim = L::splat(f32::INFINITY);
    let one = L::splat(1.0);
    let packet = PacketSlab::new(rays.d);
    let dinf = packet.dinf;
    let k = L::splat(1.5);
    // Band of the best so far: gk = 1.5 g.d, lo_b / hi_b = g.d -+ gk rho_b (per triangle the
    // band widens by gk rho_c).
    let (mut gk, mut lo_b, mut hi_b, mut lo_t) = (zero, zero, zero, zero);
    let rho_t = L::splat(tt.rho_max);
    let lanes = valid.count_ones() as u64;
    for seg in &tt.segs {
        if hit_lanes == valid && seg.near > exit_depth + slack {
            break;
        }
        let end = seg.end as usize;
        let first = start;
        let tris = &tt.tris[start..end];
        start = end;
        // The BVH's robust slab test (Ize 2013 far scaling) of the packet on the run's box:
        // runs no ray of the packet can reach (before its closest hit so far) are skipped.
        if !packet.reaches(seg, box_lim, valid) {
            continue;
        }
        work.tri_tests += tris.len() as u64;
        work.pair_tests += tris.len() as u64 * lanes;
        let mut changed = false;
        for (j, tr) in tris.iter().enumerate() {
            let gd = dot_n(tr.g, dx, dy, dz);
            // The depth band around the best 1/t: below `lo` certainly farther, above `hi`
            // certainly nearer (rho of both triangles; 1.5 covers the first-order quotient).
            let well = tr.rho <= RHO_MAX;
            // Reject test against the tile-wide band (rho_c <= the tile's largest rho): one
            // compare, as without the band.
            let lo = if well {
                lo_t
            } else {
                L::splat(f32::NEG_INFINITY)
            };
            let cand = gd.ge(lo);
            let cand_bits = L::bits(cand) & valid;
            if cand_bits == 0 {
                continue;
            }
            let (inside, unsure) = edge_band(tr, rays.d, dinf, cand, cand_bits, 7);
            let mut in_bits = L::bits(inside) & valid;
            let mut unsure = unsure;
            if in_bits | unsure == 0 {
                continue;
            }
            // This triangle's own band: certainly farther below `lo`, nearer above `hi`.
            let (lo, hi) = if well {
                let c = gk * L::splat(tr.rho);
                (lo_b - c, hi_b + c)
            } else {
                (L::splat(f32::NEG_INFINITY), L::splat(f32::INFINITY))
            };
            let near = L::bits(gd.ge(lo));
            in_bits &= near;
            unsure &= near;
            if in_bits | unsure == 0 {
                continue;
            }
            let win_m = L::and(inside, gd.gt(hi));
            let win = L::bits(win_m) & in_bits;
            let slow = (in_bits & !win) | unsure;
            work.edge_band += unsure.count_ones() as u64;
            changed = true;
            if win != 0 {
                best.gd = L::select(win_m, gd, best.gd);
                best.rho = L::select(win_m, L::splat(tr.rho), best.rho);
                let mut w = win;
                while w != 0 {
                    let l = w.trailing_zeros() as usize;
                    w &= w - 1;
                    best.tri[l] = tr.tri;
                    best.idx[l] = (first + j) as u32;
                    best.t[l] = f32::NAN;
                }
            }
            let mut s = slow;
            while s != 0 {
                let l = s.trailing_zeros() as usize;
                s &= s - 1;
                let wt = &WatertightRay::new(&rays.lane(l));
                work.exact_tests += 1;
                let Some(tc) = exact_t(wt, blocks, tr.src) else {
                    continue;
                };
                let better = if best.tri[l] == u32::MAX {
                    true
                } else {
                    if best.t[l].is_nan() {
                        work.exact_tests += 1;
                        let bsrc = tt.tris[best.idx[l] as usize].src;
                        // A certain inside decision the watertight test rejects would be a
                        // bound violation: the candidate replaces it and the ray is suspect.
                        best.t[l] = exact_t(wt, blocks, bsrc).unwrap_or(f32::NAN);
                        if best.t[l].is_nan() {
                            suspect |= 1 << l;
                        }
                    }
                    let bt = best.t[l];
                    bt.is_nan() || tc < bt || (tc == bt && tr.tri < best.tri[l])
                };
                if better {
                    best.gd = set_lane(best.gd, l, 1.0 / tc);
                    best.rho = set_lane(best.rho, l, RHO_EXACT);
                    best.tri[l] = tr.tri;
                    best.idx[l] = (first + j) as u32;
                    best.t[l] = tc;
                }
            }
            gk = best.gd * k;
            lo_b = best.gd - gk * best.rho;
            hi_b = best.gd + gk * best.rho;
            lo_t = lo_b - gk * rho_t;
        }
        if changed {
            hit_lanes = 0;
            exit_depth = f32::NEG_INFINITY;
            // Upper bound of the exact t of every lane's best: 1/t >= g.d (1 - rho), so
            // t <= 1 / (g.d (1 - rho - 8U)) (8U: the roundings of this bound).
            let lim = best.gd - best.gd * (best.rho + L::splat(8.0 * U));
            let t_up = L::select(lim.gt(zero), one / lim, L::splat(f32::INFINITY));
            for l in 0..L::N {
                if valid >> l & 1 != 0 {
                    if best.tri[l] != u32::MAX {
                        hit_lanes |= 1 << l;
                    }
                    let t = t_up.get(l);
                    exit_depth = exit_depth.max(sign * (oa + t * rays.d[axis].get(l)));
                }
            }
            box_lim = t_up;
        }
    }
    let mut out = ClosestN {
        t: [f32::INFINITY; MAX_LANES],
        tri: [u32::MAX; MAX_LANES],
    };
    // The winners' watertight t, lane-wise in one pass when the lanes share a permutation.
    let mut need = 0u32;
    for l in 0..L::N {
        if valid >> l & 1 != 0 && best.tri[l] != u32::MAX && best.t[l].is_nan() {
            need |= 1 << l;
        }
    }
    if need != 0 {
        work.final_tests += need.count_ones() as u64;
        let done = final_t_lanes(rays, blocks, tt, &best.idx, need, &mut best.t);
        // Lanes left (another permutation, an exactly-zero edge function): scalar.
        let mut m = need & !done;
        while m != 0 {
            let l = m.trailing_zeros() as usize;
            m &= m - 1;
            let wt = &WatertightRay::new(&rays.lane(l));
            best.t[l] =
                exact_t(wt, blocks, tt.tris[best.idx[l] as usize].src).unwrap_or(f32::INFINITY);
        }
    }
    for l in 0..L::N {
        if valid >> l & 1 == 0 || best.tri[l] == u32::MAX {
            continue;
        }
        let mut t = best.t[l];
        // (+inf: the watertight test rejected the winner.)
        if t == f32::INFINITY {
            t = f32::NAN;
        }
        if t.is_nan() {
            let wt = &WatertightRay::new(&rays.lane(l));
            work.final_tests += 1;
            t = exact_t(wt, blocks, tt.tris[best.idx[l] as usize].src).unwrap_or(f32::NAN);
        }
        if t.is_nan() || suspect >> l & 1 != 0 {
            work.rescues += 1;
            let (et, ei) = exact_closest(&rays.lane(l), blocks, &tt.tris);
            if ei != u32::MAX {
                out.t[l] = et;
                out.tri[l] = tt.tris[ei as usize].tri;
            }
            continue;
        }
        out.t[l] = t;
        out.tri[l] = best.tri[l];
    }
    out
}

/// The watertight test of each lane of `need` against its own winner (`idx` into the set-up
/// list), lane-wise in exactly the f32 operations of `WatertightRay::intersect_within` (as
/// the packet kernel of `packet.rs`: the same rays, shear constants divided lane-wise).
/// Writes `t[l]` (+inf for a rejected winner) and returns the lanes done; lanes with an
/// exactly-zero edge function, or all when the lanes do not share one permutation, are left
/// to the scalar test.
#[inline(always)]
#[allow(clippy::needless_range_loop)]
fn final_t_lanes<L: Lanes>(
    rays: &RaysN<L>,
    blocks: &[Tri4],
    tt: &TileTris,
    idx: &[u32; MAX_LANES],
    need: u32,
    t: &mut [f32; MAX_LANES],
) -> u32 {
    let first = need.trailing_zeros() as usize;
    let lane_dir = |l: usize| Vec3::new(rays.d[0].get(l), rays.d[1].get(l), rays.d[2].get(l));
    let perm = match tt.perm {
        Some(p) => p,
        None => {
            let perm = watertight_permutation(lane_dir(first));
            let mut m = need;
            while m != 0 {
                let l = m.trailing_zeros() as usize;
                m &= m - 1;
                if watertight_permutation(lane_dir(l)) != perm {
                    return 0;
                }
            }
            perm
        }
    };
    // Lanes outside `need` repeat the first lane's triangle (results ignored).
    let mut srcs = [0u32; MAX_LANES];
    let mut same = true;
    let s0 = tt.tris[idx[first] as usize].src;
    for (l, s) in srcs.iter_mut().enumerate().take(L::N) {
        *s = if need >> l & 1 != 0 {
            tt.tris[idx[l] as usize].src
        } else {
            s0
        };
        same &= *s == s0;
    }
    // Usually every lane (subsamples of one pixel) has the same winner: splat its vertices.
    let mut p = [[L::splat(0.0); 3]; 3];
    if same {
        p = splat_vertices(blocks, s0);
    } else {
        let mut raw = [[[0.0f32; MAX_LANES]; 3]; 3];
        for (l, &s) in srcs.iter().enumerate().take(L::N) {
            let b = &blocks[(s >> 2) as usize];
            let ln = (s & 3) as usize;
            for v in 0..3 {
                for k in 0..3 {
                    raw[v][k][l] = b.p[v][k][ln];
                }
            }
        }
        for v in 0..3 {
            for k in 0..3 {
                p[v][k] = L::from_fn(|l| raw[v][k][l]);
            }
        }
    }
    let (exact, ok, tv) = exact_t_lanes(rays, perm, &p);
    let done = need & !exact;
    let mut m = done;
    while m != 0 {
        let l = m.trailing_zeros() as usize;
        m &= m - 1;
        t[l] = if ok >> l & 1 != 0 {
            tv.get(l)
        } else {
            f32::INFINITY
        };
    }
    done
}
