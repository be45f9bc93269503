//! Bounding beams of ray bundles (Hunt et al. 2018, §5, "4-sided bounding beams" built with the
//! dominant-axis technique of Overbeck et al. 2008) and the beam/box separating-axis test with
//! outcomes Miss / Contained / Partial (§5.3).
//!
//! ## The beam
//!
//! A beam has a dominant axis `a` with a sign `s` (every ray of the bundle has `s d[a] > 0`), the
//! two other axes `b, c`, direction *slopes* `u = d[b] / |d[a]|` in `[u0, u1]` and
//! `v = d[c] / |d[a]|` in `[v0, v1]`, and an origin box `O` (a point for a pinhole, the lens
//! disc's box for a thin lens, the film rectangle for an orthographic camera). Its point set is
//!
//! ```text
//! B = { o + λ (s e_a + u e_b + v e_c) : o ∈ O, λ >= 0, u ∈ [u0, u1], v ∈ [v0, v1] }
//! ```
//!
//! which contains every ray `o + t d, t >= 0` of the bundle (`λ = t |d[a]|`).
//!
//! ## The test (separating planes)
//!
//! `B` lies in the five half-spaces `f_i(p) >= k_i`:
//!
//! ```text
//! depth: f = s p_a                      k = min_O s o_a
//! u0:    f = p_b - u0 s p_a             k = min_O (o_b - u0 s o_a)     (= o_b - u0 s o_a + λ (u - u0))
//! u1:    f = u1 s p_a - p_b             k = min_O (u1 s o_a - o_b)
//! v0, v1 likewise with c
//! ```
//!
//! A box whose maximum of some `f_i` is below `k_i` is separated from the beam: **Miss** (this is
//! the only outcome correctness depends on, and it is conservative: the planes are supporting
//! planes of `B`). A box whose eight corners satisfy all five inequalities is **Contained** in
//! their intersection (exactly the beam for a point origin; a superset for an origin box, which
//! only means a subtree is handed on whole — never that something is culled). Otherwise
//! **Partial**. Simplification against a full separating-axis test: the edge-cross-edge axes
//! are not tested, so some boxes near the beam's corners are Partial instead of Miss.
//!
//! Rounding: the thresholds are lowered by `1e-5 * (|coefficients|) * scale` ([`PreparedBeam`]),
//! with `scale` the largest coordinate magnitude of the scene and the origins, far above the few
//! ulps the float evaluation of `f_i` can err by; so a box holding a point of a bundle ray is
//! never reported Miss.
//!
//! A bundle that no axis bounds (directions spanning more than a hemisphere, or a dominant
//! component below [`MIN_DOMINANT`]) gets [`Beam::EVERYTHING`]: every test says Partial.

use glam::Vec3;

use parallax_core::simd::Lanes;
use parallax_core::{Aabb, Ray};

/// Smallest `|d[a]| / |d|` a ray may have for axis `a` to bound it (about 84 degrees off the
/// axis); steeper bundles are split or get [`Beam::EVERYTHING`].
pub const MIN_DOMINANT: f32 = 0.1;

/// Relative tolerance of the plane tests (module docs).
pub const BEAM_TOLERANCE: f32 = 1e-5;

/// Outcome of a beam/box test (Hunt et al. 2018, §5.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamTest {
    Miss,
    Partial,
    Contained,
}

/// A 4-sided bounding beam (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Dominant axis `a` (0, 1, 2).
    pub axis: u8,
    /// `+1` or `-1`: the sign of `d[a]` of every ray.
    pub sign: f32,
    /// Slopes `d[b] / |d[a]|`, `b = (a + 1) % 3`: `[min, max]`.
    pub u: [f32; 2],
    /// Slopes `d[c] / |d[a]|`, `c = (a + 2) % 3`: `[min, max]`.
    pub v: [f32; 2],
    /// Box of the ray origins.
    pub origin: Aabb,
    /// The unbounded beam: every test is Partial.
    pub everything: bool,
}

impl Beam {
    /// The beam that contains everything (the safe fallback).
    pub const EVERYTHING: Beam = Beam {
        axis: 2,
        sign: -1.0,
        u: [f32::NEG_INFINITY, f32::INFINITY],
        v: [f32::NEG_INFINITY, f32::INFINITY],
        origin: Aabb::EMPTY,
        everything: true,
    };

    /// The other two axes `(b, c)`.
    #[inline]
    pub fn side_axes(&self) -> (usize, usize) {
        let a = self.axis as usize;
        ((a + 1) % 3, (a + 2) % 3)
    }

    /// Whether the ray (origin, and direction for `t >= 0`) lies in the beam, up to a relative
    /// tolerance `tol` on the slopes and origin box.
    pub fn contains_ray(&self, ray: &Ray, tol: f32) -> bool {
        if self.everything {
            return true;
        }
        let (a, b, c) = (self.axis as usize, self.side_axes().0, self.side_axes().1);
        let d = ray.dir;
        // Negated so that a NaN component is outside.
        #[allow(clippy::neg_cmp_op_on_partial_ord)]
        let outside = !(d[a] * self.sign > 0.0);
        if outside {
            return false;
        }
        let (u, v) = (d[b] / d[a].abs(), d[c] / d[a].abs());
        let within = |x: f32, r: [f32; 2]| {
            x >= r[0] - tol * (1.0 + r[0].abs()) && x <= r[1] + tol * (1.0 + r[1].abs())
        };
        let o = ray.origin;
        let pad = Vec3::splat(tol) * (Vec3::ONE + self.origin.min.abs().max(self.origin.max.abs()));
        within(u, self.u)
            && within(v, self.v)
            && o.cmpge(self.origin.min - pad).all()
            && o.cmple(self.origin.max + pad).all()
    }

    /// The five planes `f_i(p) = ca p_a + cx p_x >= k_i` (module docs) as
    /// `(ca, x, cx, k)`, with `x` the second axis (`a` itself and `cx = 0` for the depth plane).
    pub fn planes(&self) -> [(f32, usize, f32, f32); 5] {
        let (a, b, c) = (self.axis as usize, self.side_axes().0, self.side_axes().1);
        let s = self.sign;
        let o = &self.origin;
        // min over the origin box of ca o_a + cx o_x.
        let kmin = |ca: f32, x: usize, cx: f32| {
            let ta = (ca * o.min[a]).min(ca * o.max[a]);
            let tx = if cx == 0.0 {
                0.0
            } else {
                (cx * o.min[x]).min(cx * o.max[x])
            };
            ta + tx
        };
        let plane = |ca: f32, x: usize, cx: f32| (ca, x, cx, kmin(ca, x, cx));
        [
            plane(s, a, 0.0),
            plane(-self.u[0] * s, b, 1.0),
            plane(self.u[1] * s, b, -1.0),
            plane(-self.v[0] * s, c, 1.0),
            plane(self.v[1] * s, c, -1.0),
        ]
    }

    /// The plain scalar beam/box test (module docs) with the rounding slack for coordinates up
    /// to `scale` in magnitude.
    pub fn test_box(&self, b: &Aabb, scale: f32) -> BeamTest {
        PreparedBeam::new(self, scale).test_box(b)
    }
}

/// A beam's five planes with the rounding slack applied, ready for box tests.
#[derive(Clone, Copy, Debug)]
pub struct PreparedBeam {
    pub everything: bool,
    pub axis: usize,
    pub sign: f32,
    /// Per plane: coefficient of `p_a`.
    pub ca: [f32; 5],
    /// Per plane: second axis and its coefficient (0 for the depth plane).
    pub x: [usize; 5],
    pub cx: [f32; 5],
    /// Miss when `max_box f_i < k_miss[i]`.
    pub k_miss: [f32; 5],
    /// Contained when `min_box f_i >= k_in[i]` for all `i`.
    pub k_in: [f32; 5],
}

impl PreparedBeam {
    /// Prepares `beam` for boxes with coordinates up to `scale` in magnitude (the slack is
    /// relative to `scale` and the origin box's magnitude; module docs).
    pub fn new(beam: &Beam, scale: f32) -> Self {
        let a = beam.axis as usize;
        let mut p = PreparedBeam {
            everything: beam.everything,
            axis: a,
            sign: beam.sign,
            ca: [0.0; 5],
            x: [a; 5],
            cx: [0.0; 5],
            k_miss: [f32::NEG_INFINITY; 5],
            k_in: [f32::INFINITY; 5],
        };
        if beam.everything {
            return p;
        }
        let o = beam
            .origin
            .min
            .abs()
            .max(beam.origin.max.abs())
            .max_element();
        let m = scale.abs().max(o) + 1.0;
        for (i, (ca, x, cx, k)) in beam.planes().into_iter().enumerate() {
            let tol = BEAM_TOLERANCE * (ca.abs() + cx.abs()) * m;
            p.ca[i] = ca;
            p.x[i] = x;
            p.cx[i] = cx;
            if k.is_finite() {
                p.k_miss[i] = k - tol;
                p.k_in[i] = k + tol;
            }
        }
        p
    }

    /// The scalar test of one box: the arithmetic the 4-wide test performs per lane.
    #[inline]
    pub fn test_box(&self, b: &Aabb) -> BeamTest {
        if self.everything {
            return BeamTest::Partial;
        }
        let (lo, hi) = (b.min.to_array(), b.max.to_array());
        let a = self.axis;
        let mut inside = true;
        for i in 0..5 {
            let (ca, x, cx) = (self.ca[i], self.x[i], self.cx[i]);
            let (fmax, fmin) = if i == 0 {
                plane_range1(ca, lo[a], hi[a])
            } else {
                plane_range2(ca, lo[a], hi[a], cx, lo[x], hi[x])
            };
            // `!(fmax >= k)` so that a NaN (0 * inf on an empty box) is never a miss by itself;
            // empty boxes miss on the depth plane, which has no zero coefficient.
            if fmax < self.k_miss[i] {
                return BeamTest::Miss;
            }
            inside &= fmin >= self.k_in[i];
        }
        if inside {
            BeamTest::Contained
        } else {
            BeamTest::Partial
        }
    }

    /// The near depth of a box along the dominant axis, `min_box s p_a`: the sort key of entry
    /// points and triangle lists (§5.3, "the near plane along the dominant axis").
    #[inline]
    pub fn near(&self, b: &Aabb) -> f32 {
        if self.sign > 0.0 {
            b.min[self.axis]
        } else {
            -b.max[self.axis]
        }
    }
}

/// `(max, min)` of `ca p_a` over `[lo, hi]`.
#[inline(always)]
pub fn plane_range1(ca: f32, lo: f32, hi: f32) -> (f32, f32) {
    if ca >= 0.0 {
        (ca * hi, ca * lo)
    } else {
        (ca * lo, ca * hi)
    }
}

/// `(max, min)` of `ca p_a + cx p_x` over the box.
#[inline(always)]
pub fn plane_range2(ca: f32, lo_a: f32, hi_a: f32, cx: f32, lo_x: f32, hi_x: f32) -> (f32, f32) {
    let (ma, na) = plane_range1(ca, lo_a, hi_a);
    let (mx, nx) = plane_range1(cx, lo_x, hi_x);
    (ma + mx, na + nx)
}

/// Accumulates the rays of a bundle and picks its bounding beam (dominant-axis technique,
/// Overbeck et al. 2008, as HVVR §5 uses it). Mergeable, so a block's beam is the merge of its
/// tiles' accumulators.
#[derive(Clone, Copy, Debug)]
pub struct BeamBuilder {
    count: u32,
    origin: Aabb,
    sum: Vec3,
    /// Per axis: min and max of the normalised component `d[a] / |d|`.
    dmin: [f32; 3],
    dmax: [f32; 3],
    /// Per axis `a`: min / max of `d[(a+1)%3] / |d[a]|` and `d[(a+2)%3] / |d[a]|`.
    umin: [f32; 3],
    umax: [f32; 3],
    vmin: [f32; 3],
    vmax: [f32; 3],
}

impl Default for BeamBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl BeamBuilder {
    pub fn new() -> Self {
        Self {
            count: 0,
            origin: Aabb::EMPTY,
            sum: Vec3::ZERO,
            dmin: [f32::INFINITY; 3],
            dmax: [f32::NEG_INFINITY; 3],
            umin: [f32::INFINITY; 3],
            umax: [f32::NEG_INFINITY; 3],
            vmin: [f32::INFINITY; 3],
            vmax: [f32::NEG_INFINITY; 3],
        }
    }

    /// Number of rays added.
    pub fn count(&self) -> u32 {
        self.count
    }

    /// Adds a ray (invalid rays are ignored: they are never cast).
    #[inline]
    pub fn add(&mut self, ray: &Ray) {
        if !ray.is_valid() {
            return;
        }
        let d = ray.dir;
        let n = d / d.length();
        self.count += 1;
        self.origin = self.origin.grow(ray.origin);
        self.sum += n;
        for a in 0..3 {
            self.dmin[a] = self.dmin[a].min(n[a]);
            self.dmax[a] = self.dmax[a].max(n[a]);
            let da = d[a].abs();
            // Division (not a reciprocal) so [`Beam::contains_ray`] reproduces the slopes.
            let (u, v) = (d[(a + 1) % 3] / da, d[(a + 2) % 3] / da);
            if da > 0.0 {
                self.umin[a] = self.umin[a].min(u);
                self.umax[a] = self.umax[a].max(u);
                self.vmin[a] = self.vmin[a].min(v);
                self.vmax[a] = self.vmax[a].max(v);
            }
        }
    }

    /// The union of two bundles.
    pub fn merge(&mut self, o: &BeamBuilder) {
        self.count += o.count;
        self.origin = self.origin.union(o.origin);
        self.sum += o.sum;
        for a in 0..3 {
            self.dmin[a] = self.dmin[a].min(o.dmin[a]);
            self.dmax[a] = self.dmax[a].max(o.dmax[a]);
            self.umin[a] = self.umin[a].min(o.umin[a]);
            self.umax[a] = self.umax[a].max(o.umax[a]);
            self.vmin[a] = self.vmin[a].min(o.vmin[a]);
            self.vmax[a] = self.vmax[a].max(o.vmax[a]);
        }
    }

    /// The bounding beam: the dominant axis of the mean direction if every ray has a component
    /// of at least [`MIN_DOMINANT`] along it with the mean's sign (otherwise the next axes are
    /// tried). `None` when no axis bounds the bundle (split it, or use [`Beam::EVERYTHING`]).
    /// An empty bundle gives a beam that misses every box... of positive depth only; callers
    /// skip empty bundles.
    pub fn finish(&self) -> Option<Beam> {
        if self.count == 0 {
            return None;
        }
        let mut axes = [0usize, 1, 2];
        let m = self.sum.abs();
        axes.sort_by(|&i, &j| m[j].total_cmp(&m[i]));
        for a in axes {
            let sign = if self.sum[a] >= 0.0 { 1.0 } else { -1.0 };
            let ok = if sign > 0.0 {
                self.dmin[a] >= MIN_DOMINANT
            } else {
                self.dmax[a] <= -MIN_DOMINANT
            };
            if !ok {
                continue;
            }
            return Some(Beam {
                axis: a as u8,
                sign,
                u: [self.umin[a].next_down(), self.umax[a].next_up()],
                v: [self.vmin[a].next_down(), self.vmax[a].next_up()],
                origin: self.origin,
                everything: false,
            });
        }
        None
    }
}

/// [`BeamBuilder`] over packets of rays in SIMD lanes (the caster's packets, `cast/packet.rs`):
/// lane-wise running extrema of the same per-ray values as [`BeamBuilder::add`] (the
/// normalised direction by `Vec3::length`'s operations, the slopes by division), folded into a
/// [`BeamBuilder`] once by [`Self::fold`]. The extrema, the origin box and the count equal
/// those of adding the rays one by one; the sum of the normalised directions (which only picks
/// the dominant axis) is summed in another order.
#[derive(Clone, Copy)]
pub struct LaneBeamBuilder<L> {
    count: u32,
    omin: [L; 3],
    omax: [L; 3],
    sum: [L; 3],
    dmin: [L; 3],
    dmax: [L; 3],
    umin: [L; 3],
    umax: [L; 3],
    vmin: [L; 3],
    vmax: [L; 3],
}

impl<L: Lanes> Default for LaneBeamBuilder<L> {
    fn default() -> Self {
        let (inf, ninf) = (L::splat(f32::INFINITY), L::splat(f32::NEG_INFINITY));
        Self {
            count: 0,
            omin: [inf; 3],
            omax: [ninf; 3],
            sum: [L::splat(0.0); 3],
            dmin: [inf; 3],
            dmax: [ninf; 3],
            umin: [inf; 3],
            umax: [ninf; 3],
            vmin: [inf; 3],
            vmax: [ninf; 3],
        }
    }
}

impl<L: Lanes> LaneBeamBuilder<L> {
    /// Adds the rays `(o, d)` of the lanes set in `valid` that [`Ray::is_valid`] accepts.
    /// (No closures in here or in [`Self::fold`]: the hierarchy runs them inside an AVX-512
    /// entry point, where a closure would call the lane intrinsics out of line.)
    #[inline(always)]
    pub fn add(&mut self, o: [L; 3], d: [L; 3], valid: u32) {
        let zero = L::splat(0.0);
        let mut ok = L::from_fn(|l| (valid >> l & 1) as f32).gt(zero);
        for a in 0..3 {
            ok = L::and(ok, L::and(finite(o[a]), finite(d[a])));
        }
        let [x, y, z] = d;
        let len2 = x * x + y * y + z * z;
        ok = L::and(ok, len2.gt(zero));
        let bits = L::bits(ok);
        if bits == 0 {
            return;
        }
        self.count += bits.count_ones();
        let len = len2.sqrt();
        let n = [x / len, y / len, z / len];
        for a in 0..3 {
            self.omin[a] = lower(self.omin[a], o[a], ok);
            self.omax[a] = higher(self.omax[a], o[a], ok);
            self.sum[a] = self.sum[a] + L::select(ok, n[a], zero);
            self.dmin[a] = lower(self.dmin[a], n[a], ok);
            self.dmax[a] = higher(self.dmax[a], n[a], ok);
            // `|d[a]|` (`0 - d` is `-d` exactly for `d != 0`; zeros are masked out).
            let da = L::select(d[a].lt(zero), zero - d[a], d[a]);
            let m = L::and(ok, da.gt(zero));
            let (u, v) = (d[(a + 1) % 3] / da, d[(a + 2) % 3] / da);
            self.umin[a] = lower(self.umin[a], u, m);
            self.umax[a] = higher(self.umax[a], u, m);
            self.vmin[a] = lower(self.vmin[a], v, m);
            self.vmax[a] = higher(self.vmax[a], v, m);
        }
    }

    /// The rays added so far as a [`BeamBuilder`].
    #[inline(always)]
    pub fn fold(&self) -> BeamBuilder {
        let mut b = BeamBuilder::new();
        if self.count == 0 {
            return b;
        }
        b.count = self.count;
        let (mut omin, mut omax, mut sum) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
        for a in 0..3 {
            omin[a] = lane_min(self.omin[a]);
            omax[a] = lane_max(self.omax[a]);
            sum[a] = lane_sum(self.sum[a]);
            b.dmin[a] = lane_min(self.dmin[a]);
            b.dmax[a] = lane_max(self.dmax[a]);
            b.umin[a] = lane_min(self.umin[a]);
            b.umax[a] = lane_max(self.umax[a]);
            b.vmin[a] = lane_min(self.vmin[a]);
            b.vmax[a] = lane_max(self.vmax[a]);
        }
        b.origin = Aabb::new(Vec3::from(omin), Vec3::from(omax));
        b.sum = Vec3::from(sum);
        b
    }
}

/// The lanes of `x` that are finite (`-inf < x < inf`).
#[inline(always)]
fn finite<L: Lanes>(x: L) -> L::M {
    L::and(
        x.gt(L::splat(f32::NEG_INFINITY)),
        x.lt(L::splat(f32::INFINITY)),
    )
}

/// `acc` with the lanes of `m` where `v < acc` taken from `v`.
#[inline(always)]
fn lower<L: Lanes>(acc: L, v: L, m: L::M) -> L {
    L::select(L::and(m, v.lt(acc)), v, acc)
}

/// `acc` with the lanes of `m` where `v > acc` taken from `v`.
#[inline(always)]
fn higher<L: Lanes>(acc: L, v: L, m: L::M) -> L {
    L::select(L::and(m, v.gt(acc)), v, acc)
}

/// The smallest lane of `v` (`f32::min`: NaN lanes ignored).
#[inline(always)]
fn lane_min<L: Lanes>(v: L) -> f32 {
    let mut m = f32::INFINITY;
    for l in 0..L::N {
        m = m.min(v.get(l));
    }
    m
}

/// The largest lane of `v` (`f32::max`: NaN lanes ignored).
#[inline(always)]
fn lane_max<L: Lanes>(v: L) -> f32 {
    let mut m = f32::NEG_INFINITY;
    for l in 0..L::N {
        m = m.max(v.get(l));
    }
    m
}

/// The sum of the lanes of `v`, lane 0 first.
#[inline(always)]
fn lane_sum<L: Lanes>(v: L) -> f32 {
    let mut s = 0.0;
    for l in 0..L::N {
        s += v.get(l);
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn beam_of(rays: &[Ray]) -> Beam {
        let mut b = BeamBuilder::new();
        for r in rays {
            b.add(r);
        }
        b.finish().unwrap()
    }

    #[test]
    fn frustum_of_four_rays_classifies_boxes() {
        let o = Vec3::ZERO;
        let rays: Vec<Ray> = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|&(x, y)| Ray::new(o, Vec3::new(x * 0.2, y * 0.2, -1.0).normalize()))
            .collect();
        let beam = beam_of(&rays);
        assert_eq!(beam.axis, 2);
        assert_eq!(beam.sign, -1.0);
        let inside = Aabb::new(Vec3::new(-0.1, -0.1, -2.0), Vec3::new(0.1, 0.1, -1.0));
        let straddle = Aabb::new(Vec3::new(0.1, -0.1, -2.0), Vec3::new(1.0, 0.1, -1.0));
        let outside = Aabb::new(Vec3::new(0.5, -0.1, -2.0), Vec3::new(1.0, 0.1, -1.0));
        let behind = Aabb::new(Vec3::new(-0.1, -0.1, 1.0), Vec3::new(0.1, 0.1, 2.0));
        assert_eq!(beam.test_box(&inside, 10.0), BeamTest::Contained);
        assert_eq!(beam.test_box(&straddle, 10.0), BeamTest::Partial);
        assert_eq!(beam.test_box(&outside, 10.0), BeamTest::Miss);
        assert_eq!(beam.test_box(&behind, 10.0), BeamTest::Miss);
        assert_eq!(beam.test_box(&Aabb::EMPTY, 10.0), BeamTest::Miss);
        assert_eq!(Beam::EVERYTHING.test_box(&outside, 10.0), BeamTest::Partial);
        for r in &rays {
            assert!(beam.contains_ray(r, 0.0));
        }
    }

    /// `LaneBeamBuilder` folds to `BeamBuilder::add` of the same rays one by one: the same
    /// extrema, origin box and count bit for bit (the direction sum within rounding), with
    /// invalid lanes, NaN, infinite and zero directions among random rays.
    #[test]
    fn lane_builder_equals_adding_rays_one_by_one() {
        fn check<L: Lanes>(seed: u64) {
            let mut s = seed;
            let mut next = || {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
            };
            let (mut one, mut lanes) = (BeamBuilder::new(), LaneBeamBuilder::<L>::default());
            for p in 0..300 {
                let mut rays = Vec::new();
                for l in 0..L::N {
                    let o = Vec3::new(next(), next(), next()) * 3.0;
                    let mut d = Vec3::new(next(), next() * 0.3, -1.0 - next().abs());
                    match (p * 7 + l) % 23 {
                        0 => d = Vec3::ZERO,
                        1 => d.x = f32::NAN,
                        2 => d.y = f32::INFINITY,
                        3 => d.z = 0.0,
                        _ => {}
                    }
                    rays.push(Ray::new(o, d));
                }
                let valid = (next().to_bits() | 1) & ((1u32 << L::N) - 1).max(1);
                for (l, r) in rays.iter().enumerate() {
                    if valid >> l & 1 == 1 {
                        one.add(r);
                    }
                }
                let comp = |f: fn(&Ray) -> Vec3, a: usize| L::from_fn(|l| f(&rays[l])[a]);
                let o = [0, 1, 2].map(|a| comp(|r| r.origin, a));
                let d = [0, 1, 2].map(|a| comp(|r| r.dir, a));
                lanes.add(o, d, valid);
            }
            let got = lanes.fold();
            assert!(one.count > 100);
            assert_eq!(got.count, one.count);
            assert_eq!(got.origin, one.origin);
            let bits = |v: [f32; 3]| v.map(f32::to_bits);
            assert_eq!(bits(got.dmin), bits(one.dmin));
            assert_eq!(bits(got.dmax), bits(one.dmax));
            assert_eq!(bits(got.umin), bits(one.umin));
            assert_eq!(bits(got.umax), bits(one.umax));
            assert_eq!(bits(got.vmin), bits(one.vmin));
            assert_eq!(bits(got.vmax), bits(one.vmax));
            assert!((got.sum - one.sum).length() <= 1e-4 * one.sum.length());
            assert_eq!(got.finish(), one.finish());
        }
        check::<glam::Vec4>(3);
        check::<crate::cast::lanes16::V16>(4);
    }

    #[test]
    fn opposite_rays_have_no_beam() {
        let mut b = BeamBuilder::new();
        for d in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            b.add(&Ray::new(Vec3::ZERO, d));
        }
        assert!(b.finish().is_none());
    }
}
