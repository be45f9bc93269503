//! Sample testing (Hunt et al. 2018, §5.5): the subsample rays of a tile against the tile's
//! triangle list, closest hit with depth test, written to the [`VisibilityBuffer`](crate::visibility::VisibilityBuffer).
//!
//! - Rays are generated just in time per subsample ([`SampleSet::fast_subsample_ray`], the
//!   same rays bit for bit as [`SampleSet::subsample_ray`]), never stored.
//! - The triangle list is the tile cull's leaves in near-depth order; a leaf is one (or more)
//!   SoA block of four triangles of the BVH ([`Tri4`]), tested four at a time with the
//!   watertight test of Woop et al. 2013 in exactly the f32 operations of the BVH's own leaf
//!   test (`parallax_bvh::Tri4Ray`, shared; lanes with an exactly-zero edge function fall back to the
//!   scalar [`WatertightRay::intersect_within`]), and the same tie-break (lower index in
//!   `Bvh::triangles` on equal `t`): so every hit equals the per-ray BVH traversal's
//!   ([`crate::trace_per_ray`]) whenever the tile list holds the ray's closest triangle.
//! - **Beyond the paper: front-to-back early exit per ray.** The leaves are sorted by the near
//!   depth `min s p_a` of their boxes along the tile beam's dominant axis; once a ray's closest
//!   hit lies at dominant-axis depth `s (o_a + t d_a)` below the next leaf's near depth (with a
//!   relative slack), no later leaf can hold a hit at `t' <= t`, and the ray stops. HVVR's
//!   future-work section proposes interleaving exactly this with tile culling.
//!
//! This is the exact kernel ([`crate::SampleTest::Watertight`]): for tiles without a shared
//! ray origin (thin lens) and on request. The default for tiles whose rays share an origin is
//! HVVR's per-tile triangle set-up with tile-corner all-in / partial / all-out classification
//! ([`crate::cast::setup`]).
//!
//! Simplifications: no back-face culling (our meshes are two-sided), no near-plane culling
//! (rays start at `t = 0` like the per-ray baseline).

use glam::{Vec3, Vec4};
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_bvh::{Tri4, Tri4Hits, Tri4Ray};
use parallax_core::math::{ROBUST_FAR_SCALE, WatertightRay};
use parallax_core::simd::{max_or_rhs, min_or_rhs};
use parallax_core::{NO_ID, Ray};

use crate::SampleSet;
use crate::beam::PreparedBeam;
use crate::cast::leaves::{LeafBox, LeafGroup};
use crate::cast::packet_kernel::run_packets;

/// Keeps `(t, tri)` if it is closer than the best so far, or as close with a lower triangle
/// index (the BVH's tie-break).
#[inline(always)]
fn offer(best_t: &mut f32, best_tri: &mut u32, t: f32, tri: u32) {
    if *best_tri == u32::MAX || t < *best_t || (t == *best_t && tri < *best_tri) {
        *best_t = t;
        *best_tri = tri;
    }
}

/// The robust slab test of the BVH traversal (Ize 2013 far scaling) on four leaf boxes: the
/// lanes a ray with closest hit `t_max` so far may still hit something in.
#[inline(always)]
fn slab4(
    g: &LeafGroup,
    org: &[Vec4; 3],
    inv: &[Vec4; 3],
    near: &[usize; 3],
    t_min: Vec4,
    t_max: f32,
) -> u32 {
    let b = &g.bounds;
    let tnx = (b[near[0]] - org[0]) * inv[0];
    let tny = (b[near[1]] - org[1]) * inv[1];
    let tnz = (b[near[2]] - org[2]) * inv[2];
    let tfx = (b[near[0] ^ 1] - org[0]) * inv[0];
    let tfy = (b[near[1] ^ 1] - org[1]) * inv[1];
    let tfz = (b[near[2] ^ 1] - org[2]) * inv[2];
    let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, t_min)));
    let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, Vec4::splat(t_max))));
    t_near.cmple(t_far * ROBUST_FAR_SCALE).bitmask()
}

/// Work counters of a tile.
#[derive(Clone, Copy, Debug, Default)]
pub struct TileWork {
    pub rays: u64,
    /// Four-box slab tests against leaf groups.
    pub group_tests: u64,
    pub leaf_tests: u64,
}

/// Tests every subsample ray of the tile `samples` against `leaves` (near-depth order) and
/// writes the closest hits. `prim` / `t` point at the visibility buffer's arrays, indexed
/// `sample * spp + k`; `beam` is the tile's prepared beam (its dominant axis orders the leaves)
/// and `scale` the magnitude bound used for the early-exit slack.
///
/// # Safety
/// `prim` and `t` must be valid for `set.ray_count()` elements, and no other thread may write
/// the entries of these samples (each sample belongs to one tile).
/// The closest hit `(t, index in Bvh::triangles)` of one ray (`u32::MAX` = none) against the
/// tile's leaf groups.
#[inline(never)]
pub fn closest_one(
    ray: &Ray,
    blocks: &[Tri4],
    groups: &[LeafGroup],
    beam: &PreparedBeam,
    slack: f32,
    work: &mut TileWork,
) -> (f32, u32) {
    let (mut best_t, mut best_tri) = (f32::INFINITY, u32::MAX);
    if !(ray.is_valid() && ray.t_min <= ray.t_max) {
        return (best_t, best_tri);
    }
    let a = beam.axis;
    let s = beam.sign;
    let ordered = !beam.everything;
    let r4 = Tri4Ray::new(WatertightRay::new(ray));
    let (oa, da) = (ray.origin[a], ray.dir[a]);
    let inv = ray.dir.recip();
    let org = [
        Vec4::splat(ray.origin.x),
        Vec4::splat(ray.origin.y),
        Vec4::splat(ray.origin.z),
    ];
    let invv = [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)];
    let neg = |x: f32| x.is_sign_negative() as usize;
    let near = [neg(inv.x), 2 + neg(inv.y), 4 + neg(inv.z)];
    let t_min4 = Vec4::splat(ray.t_min);
    for g in groups {
        if ordered && best_tri != u32::MAX && g.near > s * (oa + best_t * da) + slack {
            break;
        }
        let lim = if best_tri == u32::MAX {
            ray.t_max
        } else {
            best_t
        };
        work.group_tests += 1;
        let mut lanes = slab4(g, &org, &invv, &near, t_min4, lim);
        while lanes != 0 {
            let l = g.leaf[lanes.trailing_zeros() as usize];
            lanes &= lanes - 1;
            work.leaf_tests += 1;
            let (first, count) = (leaf_first(l), leaf_count(l));
            for kb in 0..count.div_ceil(4) {
                let b = &blocks[(first + kb) as usize];
                let left = count - 4 * kb;
                let mask = if left >= 4 { 0xF } else { (1 << left) - 1 };
                let limit = if best_tri == u32::MAX {
                    ray.t_max
                } else {
                    best_t.next_up()
                };
                let Tri4Hits {
                    hit, exact, t: tv, ..
                } = r4.intersect(b, mask, limit);
                if hit != 0 {
                    let ta = tv.to_array();
                    let mut m = hit;
                    while m != 0 {
                        let ln = m.trailing_zeros() as usize;
                        m &= m - 1;
                        offer(&mut best_t, &mut best_tri, ta[ln], b.tri[ln]);
                    }
                }
                let mut m = exact;
                while m != 0 {
                    let ln = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let v = |j: usize| Vec3::new(b.p[j][0][ln], b.p[j][1][ln], b.p[j][2][ln]);
                    let limit = if best_tri == u32::MAX {
                        ray.t_max
                    } else {
                        best_t.next_up()
                    };
                    if let Some(h) = r4.wt.intersect_within(v(0), v(1), v(2), limit) {
                        offer(&mut best_t, &mut best_tri, h.t, b.tri[ln]);
                    }
                }
            }
        }
    }
    (best_t, best_tri)
}

/// Tests every subsample ray of the tile `samples` against the tile's leaves and writes the
/// closest hits: packets of `lanes` = 8 (AVX2, if the CPU has it) or 4 rays ([`crate::cast::packet`])
/// where they share one watertight permutation, one ray at a time ([`closest_one`]) otherwise
/// (or always, with `lanes = 1`). `prim` / `t` point at the visibility buffer's arrays, indexed `sample * spp + k`;
/// `beam` is the tile's prepared beam (its dominant axis orders the leaves) and `scale` the
/// magnitude bound used for the early-exit slack.
///
/// # Safety
/// `prim` and `t` must be valid for `set.ray_count()` elements, and no other thread may write
/// the entries of these samples (each sample belongs to one tile).
#[allow(clippy::too_many_arguments)]
pub unsafe fn test_tile(
    set: &SampleSet,
    blocks: &[Tri4],
    samples: &[u32],
    groups: &[LeafGroup],
    boxes: &[LeafBox],
    beam: &PreparedBeam,
    scale: f32,
    lanes: usize,
    prim: *mut u32,
    t: *mut f32,
) -> TileWork {
    let spp = set.spp as usize;
    let mut work = TileWork::default();
    let slack = 1e-5 * (scale.abs() + 1.0);
    let write = |o: usize, bt: f32, tri: u32| {
        // SAFETY: the caller guarantees exclusive access to this sample's entries.
        unsafe {
            if tri == u32::MAX {
                *prim.add(o) = NO_ID;
                *t.add(o) = f32::INFINITY;
            } else {
                *prim.add(o) = tri;
                *t.add(o) = bt;
            }
        }
    };
    let total = samples.len() * spp;
    let pair = |j: usize| (samples[j / spp], (j % spp) as u32);
    let write =
        |(i, k): (u32, u32), bt: f32, tri: u32| write(i as usize * spp + k as usize, bt, tri);
    if lanes <= 1 {
        for j in 0..total {
            let (i, k) = pair(j);
            let (bt, tri) = match set.fast_subsample_ray(i as usize, k as usize) {
                Some(ray) => {
                    work.rays += 1;
                    closest_one(&ray, blocks, groups, beam, slack, &mut work)
                }
                None => (f32::INFINITY, u32::MAX),
            };
            write((i, k), bt, tri);
        }
        return work;
    }
    let mut single = TileWork::default();
    let fallback = |r: &Ray| closest_one(r, blocks, groups, beam, slack, &mut single);
    #[cfg(target_arch = "x86_64")]
    let (pw, rays) = if lanes == 8 && crate::cast::isa::avx2_detected() {
        // SAFETY: the AVX2 tier was detected.
        unsafe {
            crate::cast::packet_kernel::run_packets_avx2(
                set, blocks, boxes, beam, slack, total, pair, write, fallback,
            )
        }
    } else {
        run_packets::<Vec4>(
            set, blocks, boxes, beam, slack, total, pair, write, fallback,
        )
    };
    #[cfg(not(target_arch = "x86_64"))]
    let (pw, rays) = run_packets::<Vec4>(
        set, blocks, boxes, beam, slack, total, pair, write, fallback,
    );
    work.rays += rays;
    work.group_tests += single.group_tests;
    work.leaf_tests += single.leaf_tests;
    work.group_tests += pw.box_tests;
    work.leaf_tests += pw.tri_tests;
    work
}
