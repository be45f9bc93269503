//! Single-ray traversal of the 4-wide BVH: closest hit, any hit, all hits.
//!
//! One kernel ([`Bvh::traverse`]) serves all three queries; the leaf action is a closure and the
//! work counter a generic ([`Counter`]), so each query compiles to its own specialised loop
//! without runtime switches. The loop is the explicit-stack wide traversal of Wald et al. 2008 /
//! Embree (Wald et al. 2014, "Embree: a kernel framework for efficient CPU ray tracing", §4):
//! test the four child boxes of a node with one SIMD slab test, continue with the nearest hit
//! child, push the others far-to-near with their entry distance, and on pop skip entries that
//! start beyond the closest hit found so far.
//!
//! The stack is a fixed array of [`STACK_SIZE`] entries: a node pushes at most 3 entries, and
//! the build bounds the depth (`build.rs`), so `3 * depth < STACK_SIZE` (checked at build).

use glam::Vec4;
use parallax_core::Ray;
use parallax_core::math::ROBUST_FAR_SCALE;
use parallax_core::math::WatertightRay;

use crate::node::{Node4, is_leaf, leaf_count, leaf_first};
use crate::simd::{max_or_rhs, min_or_rhs};
use crate::stats::{Counter, NoStats, TraversalStats};
use crate::{Bvh, Hit};

/// Traversal stack entries.
pub(crate) const STACK_SIZE: usize = 256;

#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    t: f32,
}

/// A ray prepared for the 4-wide slab test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayBoxes {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    /// Index into `Node4::bounds` of the near / far plane per axis (`2 * axis + sign`).
    near: [usize; 3],
    far: [usize; 3],
    t_min: Vec4,
}

impl RayBoxes {
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        // 1 / ±0 = ±inf; see `intersect` for how the resulting 0 * inf = NaN is handled.
        let inv = ray.dir.recip();
        let o = ray.origin;
        let neg = |x: f32| x.is_sign_negative() as usize;
        let (sx, sy, sz) = (neg(inv.x), neg(inv.y), neg(inv.z));
        Self {
            org: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [sx, 2 + sy, 4 + sz],
            far: [1 - sx, 3 - sy, 5 - sz],
            t_min: Vec4::splat(ray.t_min),
        }
    }

    /// Slab test of the four children (Kay & Kajiya 1986), ordered form: per axis the ray's sign
    /// picks the near and far plane, so
    ///
    /// ```text
    /// t_near = max(t_min, (near_x - o_x) / d_x, (near_y - o_y) / d_y, (near_z - o_z) / d_z)
    /// t_far  = min((far_x - o_x) / d_x, ...) * (1 + 2 gamma(3))          (Ize 2013, robust)
    /// hit    = t_near <= min(t_far, t_max)
    /// ```
    ///
    /// Empty lanes (`min = +inf, max = -inf`) give `t_near = +inf`, `t_far = -inf`: never hit.
    /// A zero direction component with the origin exactly on a plane gives `0 * inf = NaN`; the
    /// ray then lies in the closed slab, and `max_or_rhs` / `min_or_rhs` ignore the NaN (the
    /// accumulators on the right stay NaN-free). Returns the hit mask (bit i = lane i) and the
    /// entry distances.
    #[inline(always)]
    pub fn intersect(&self, node: &Node4, t_max: f32) -> (u32, Vec4) {
        let b = &node.bounds;
        let tnx = (b[self.near[0]] - self.org[0]) * self.inv[0];
        let tny = (b[self.near[1]] - self.org[1]) * self.inv[1];
        let tnz = (b[self.near[2]] - self.org[2]) * self.inv[2];
        let tfx = (b[self.far[0]] - self.org[0]) * self.inv[0];
        let tfy = (b[self.far[1]] - self.org[1]) * self.inv[1];
        let tfz = (b[self.far[2]] - self.org[2]) * self.inv[2];
        let t_near = max_or_rhs(tnz, max_or_rhs(tny, max_or_rhs(tnx, self.t_min)));
        let t_far = min_or_rhs(tfz, min_or_rhs(tfy, min_or_rhs(tfx, Vec4::INFINITY)));
        let t_far = min_or_rhs(t_far * ROBUST_FAR_SCALE, Vec4::splat(t_max));
        (t_near.cmple(t_far).bitmask(), t_near)
    }
}

/// Whether a ray can hit anything: finite origin and direction, non-zero direction, and a
/// non-empty, non-NaN interval.
#[inline(always)]
fn ray_ok(ray: &Ray) -> bool {
    ray.is_valid() && ray.t_min <= ray.t_max
}

impl Bvh {
    /// The traversal kernel. `leaf(first, count, t_max, stats)` tests a leaf's triangles, may
    /// shrink `t_max` (closest hit), and returns `true` to stop (any hit). With `ORDERED`,
    /// children are visited near-to-far; otherwise in lane order.
    #[inline(always)]
    fn traverse<C: Counter, const ORDERED: bool>(
        &self,
        rb: &RayBoxes,
        mut t_max: f32,
        stats: &mut C,
        mut leaf: impl FnMut(u32, u32, &mut f32, &mut C) -> bool,
    ) {
        let mut stack = [Entry { child: 0, t: 0.0 }; STACK_SIZE];
        let mut sp = 0usize;
        let mut cur = 0u32; // the root
        loop {
            if !is_leaf(cur) {
                let node = &self.nodes[cur as usize];
                stats.node(node.num_children);
                let (mask, t_near) = rb.intersect(node, t_max);
                if mask != 0 {
                    let tn = t_near.to_array();
                    let c0 = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    if rest == 0 {
                        cur = node.child[c0];
                        continue;
                    }
                    if !ORDERED {
                        let mut m = rest;
                        while m != 0 {
                            let c = m.trailing_zeros() as usize;
                            m &= m - 1;
                            stack[sp] = Entry {
                                child: node.child[c],
                                t: tn[c],
                            };
                            sp += 1;
                        }
                        cur = node.child[c0];
                        continue;
                    }
                    let c1 = rest.trailing_zeros() as usize;
                    let rest = rest & (rest - 1);
                    if rest == 0 {
                        let (near, far) = if tn[c0] <= tn[c1] { (c0, c1) } else { (c1, c0) };
                        stack[sp] = Entry {
                            child: node.child[far],
                            t: tn[far],
                        };
                        sp += 1;
                        cur = node.child[near];
                        continue;
                    }
                    // Three or four children: insertion sort far-to-near, push all but the
                    // nearest, continue with the nearest.
                    let mut e = [Entry { child: 0, t: 0.0 }; 4];
                    let mut n = 0;
                    let mut m = mask;
                    while m != 0 {
                        let c = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let x = Entry {
                            child: node.child[c],
                            t: tn[c],
                        };
                        let mut j = n;
                        while j > 0 && e[j - 1].t < x.t {
                            e[j] = e[j - 1];
                            j -= 1;
                        }
                        e[j] = x;
                        n += 1;
                    }
                    for x in &e[..n - 1] {
                        stack[sp] = *x;
                        sp += 1;
                    }
                    cur = e[n - 1].child;
                    continue;
                }
            } else {
                stats.leaf();
                if leaf(leaf_first(cur), leaf_count(cur), &mut t_max, stats) {
                    return;
                }
            }
            // Pop the next entry that can still hold a closer hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let e = stack[sp];
                if e.t <= t_max {
                    cur = e.child;
                    break;
                }
            }
        }
    }

    #[inline(always)]
    fn closest_impl<C: Counter>(&self, ray: &Ray, stats: &mut C) -> Option<Hit> {
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return None;
        }
        let rb = RayBoxes::new(ray);
        let wt = WatertightRay::new(ray);
        let mut best = None;
        self.traverse::<C, true>(&rb, ray.t_max, stats, |first, count, t_max, stats| {
            for i in first..first + count {
                let tri = &self.tris[i as usize];
                let h = wt.intersect_within(tri.p0, tri.p1, tri.p2, *t_max);
                stats.triangle(h.is_some());
                if let Some(h) = h {
                    *t_max = h.t;
                    best = Some((i, h));
                }
            }
            false
        });
        best.map(|(i, h)| Hit {
            prim: self.prim_ids[i as usize],
            t: h.t,
            u: h.u,
            v: h.v,
        })
    }

    #[inline(always)]
    fn any_impl<C: Counter>(&self, ray: &Ray, stats: &mut C) -> bool {
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return false;
        }
        let rb = RayBoxes::new(ray);
        let wt = WatertightRay::new(ray);
        let mut found = false;
        self.traverse::<C, false>(&rb, ray.t_max, stats, |first, count, t_max, stats| {
            for tri in &self.tris[first as usize..(first + count) as usize] {
                let h = wt.intersect_within(tri.p0, tri.p1, tri.p2, *t_max);
                stats.triangle(h.is_some());
                if h.is_some() {
                    found = true;
                    return true;
                }
            }
            false
        });
        found
    }

    #[inline(always)]
    fn all_impl<C: Counter>(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut C) {
        out.clear();
        stats.ray();
        if self.nodes.is_empty() || !ray_ok(ray) {
            return;
        }
        let rb = RayBoxes::new(ray);
        let wt = WatertightRay::new(ray);
        self.traverse::<C, false>(&rb, ray.t_max, stats, |first, count, _, stats| {
            for i in first..first + count {
                let tri = &self.tris[i as usize];
                let h = wt.intersect(tri.p0, tri.p1, tri.p2);
                stats.triangle(h.is_some());
                if let Some(h) = h {
                    out.push(Hit {
                        prim: self.prim_ids[i as usize],
                        t: h.t,
                        u: h.u,
                        v: h.v,
                    });
                }
            }
            false
        });
        sort_hits(out);
    }

    /// The closest intersection with `ray` in `(t_min, t_max)`, or `None`. Both faces of a
    /// triangle are hit. Invalid rays (non-finite, zero direction) hit nothing.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        self.closest_impl(ray, &mut NoStats)
    }

    /// [`Self::closest_hit`], adding the work done to `stats`.
    pub fn closest_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> Option<Hit> {
        self.closest_impl(ray, stats)
    }

    /// Whether anything intersects `ray` in `(t_min, t_max)` (occlusion / shadow rays). Stops
    /// at the first hit found, in no particular order.
    pub fn any_hit(&self, ray: &Ray) -> bool {
        self.any_impl(ray, &mut NoStats)
    }

    /// [`Self::any_hit`], adding the work done to `stats`.
    pub fn any_hit_with_stats(&self, ray: &Ray, stats: &mut TraversalStats) -> bool {
        self.any_impl(ray, stats)
    }

    /// Every intersection with `ray` in `(t_min, t_max)`, sorted by `t` (ties by primitive).
    /// `out` is cleared first; it only allocates when it must grow. With the watertight test's
    /// tie-break, a ray through a shared edge or vertex of a closed mesh is reported once.
    pub fn all_hits(&self, ray: &Ray, out: &mut Vec<Hit>) {
        self.all_impl(ray, out, &mut NoStats)
    }

    /// [`Self::all_hits`], adding the work done to `stats`.
    pub fn all_hits_with_stats(&self, ray: &Ray, out: &mut Vec<Hit>, stats: &mut TraversalStats) {
        self.all_impl(ray, out, stats)
    }
}

/// Sorts hits by `t`, then by primitive (allocation-free).
pub(crate) fn sort_hits(hits: &mut [Hit]) {
    hits.sort_unstable_by(|a, b| a.t.total_cmp(&b.t).then(a.prim.cmp(&b.prim)));
}
