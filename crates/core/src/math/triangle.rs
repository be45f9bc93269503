//! Ray-triangle intersection.
//!
//! The default is the watertight test of Woop, Benthin and Wald 2013 ("Watertight Ray/Triangle
//! Intersection", JCGT 2(1)): the ray is sheared so that it becomes the +z axis through the
//! origin, the triangle's vertices are projected into that frame once per vertex with the same
//! arithmetic, and the three 2-D edge functions decide coverage. Edge functions that are exactly
//! zero are recomputed in double precision (where products of floats are exact), so the sign of
//! every edge function is correct and the edge shared by two triangles gets exactly opposite
//! values in both.
//!
//! **Beyond the paper — tie-breaking.** The paper counts a ray through a shared edge as a hit of
//! *both* triangles (it only promises "no ray slips through"). parallax also wants "no ray hits
//! twice", so that all-hits queries on closed meshes return even counts and depth peeling sees
//! every surface once. An exactly-zero edge function is therefore accepted only when the edge's
//! 2-D direction (taken in the orientation that makes the triangle's determinant positive)
//! lies in a fixed half-open half-plane: `d.y < 0 || (d.y == 0 && d.x > 0)`. Exactly one of `d`
//! and `-d` passes, so of two front-facing triangles sharing an edge exactly one accepts the
//! ray; at a shared vertex the same rule (a rotated top-left fill rule) gives the vertex to
//! exactly one triangle of the fan.
//!
//! **One definition, every width.** The arithmetic of the test — the axis permutation
//! ([`watertight_permutation`]), the shear of a vertex ([`shear_vertex`]), the edge functions
//! ([`edge_functions`]) and the scaled distance ([`scaled_distance`]) — is written once, generic
//! over [`Lanes`]: the scalar [`WatertightRay::intersect_within`] runs it on `f32`, and the SIMD
//! kernels (the BVH's four triangles per ray, HVVR's four or eight rays per triangle) run it on
//! `Vec4` / `F8` through [`watertight_lanes`] and [`WatertightLanes::distance`]. Lanes round exactly like scalar f32, so every lane
//! computes bit-identical `u, v, w, t`; lanes with an exactly-zero edge function are reported for
//! the scalar test, which alone holds the double-precision recompute and the tie-break.
//!
//! [`intersect_triangle_moller`] (Möller & Trumbore 1997) is kept as the simple, non-watertight
//! twin used by tests and benchmarks.
//!
//! [`F8`]: crate::simd::F8

use glam::{DVec2, Vec3};

use super::Ray;
use crate::simd::Lanes;

/// Woop et al. 2013, §3: the axis `kz < 3` of the largest `|d[kz]|` (the first of equal
/// ones in the order of [`watertight_permutation`]'s compares).
#[inline(always)]
pub fn dominant_axis(d: Vec3) -> usize {
    let a = d.abs();
    // `a.x > a.y ? (a.x > a.z ? 0 : 2) : (a.y > a.z ? 1 : 2)` as selects of the three
    // compares: no branch to mispredict per ray.
    let (xy, xz, yz) = (a.x > a.y, a.x > a.z, a.y > a.z);
    if xy {
        2 * !xz as usize
    } else {
        2 - yz as usize
    }
}

/// Woop et al. 2013, §3: the dominant axis `kz` of `d`, and `kx, ky` the next two, swapped when
/// `d[kz] < 0` so that the winding is kept. Returns `[kx, ky, kz]`.
#[inline(always)]
pub fn watertight_permutation(d: Vec3) -> [usize; 3] {
    let kz = dominant_axis(d);
    let kx = (kz + 1) % 3;
    let ky = (kx + 1) % 3;
    let swap = d.to_array()[kz] < 0.0;
    [if swap { ky } else { kx }, if swap { kx } else { ky }, kz]
}

/// Woop et al. 2013, §3: a vertex in the ray's sheared frame, where the ray is the +z axis.
/// `p` and `o` are the vertex and the ray origin in permuted order (`[p[kx], p[ky], p[kz]]`),
/// `shear = [sx, sy, sz]`:
///
/// ```text
/// a = p - o;  (a[kx] - sx a[kz], a[ky] - sy a[kz], sz a[kz])
/// ```
///
/// Every triangle sharing a vertex gets bit-identical coordinates.
#[inline(always)]
pub fn shear_vertex<L: Lanes>(p: [L; 3], o: [L; 3], shear: [L; 3]) -> [L; 3] {
    let az = p[2] - o[2];
    let x = (p[0] - o[0]) - shear[0] * az;
    let y = (p[1] - o[1]) - shear[1] * az;
    [x, y, shear[2] * az]
}

/// The 2-D edge functions (cross products) of edges C->B, A->C and B->A of the sheared vertices
/// at the origin: `[u, v, w]`, `u = Cx By - Cy Bx`, `v = Ax Cy - Ay Cx`, `w = Bx Ay - By Ax`.
/// The ray is inside iff all three are `>= 0` or all `<= 0`.
#[inline(always)]
pub fn edge_functions<L: Lanes>(a: [L; 3], b: [L; 3], c: [L; 3]) -> [L; 3] {
    [
        c[0] * b[1] - c[1] * b[0],
        a[0] * c[1] - a[1] * c[0],
        b[0] * a[1] - b[1] * a[0],
    ]
}

/// `(det, t det)` of edge functions `e` and the sheared vertices' `z`:
/// `det = (u + v) + w`, `t det = (u Az + v Bz) + w Cz`.
#[inline(always)]
pub fn scaled_distance<L: Lanes>(e: [L; 3], az: L, bz: L, cz: L) -> (L, L) {
    let det = e[0] + e[1] + e[2];
    (det, e[0] * az + e[1] * bz + e[2] * cz)
}

/// Lane-wise edge functions of the watertight test and their decisions ([`watertight_lanes`]).
#[derive(Clone, Copy, Debug)]
pub struct WatertightLanes<L> {
    /// The edge functions `[u, v, w]`.
    pub e: [L; 3],
    /// Lanes with an edge function exactly `0.0`: only the scalar test decides them.
    pub exact: u32,
    /// Lanes where the three edge functions have the same sign bit: for nonzero, non-NaN
    /// values exactly "no two of opposite signs" of the scalar test (the ray is inside if also
    /// `det != 0`). Meaningless for `exact` lanes (a zero's sign bit says nothing). A lane with
    /// a NaN edge function may be classified either way, but its `det` and `t` are NaN, so
    /// every caller's `t > t_min` (or `t > 0`) rejects it, as the scalar test does: only the
    /// work differs, never a result.
    pub same_sign: u32,
}

/// The distance part of the lane test ([`WatertightLanes::distance`]).
#[derive(Clone, Copy, Debug)]
pub struct LaneDistance<L> {
    /// `t = (t det) * (1 / det)`.
    pub t: L,
    /// `1 / det` (barycentrics of vertices 1 and 2: `v / det`, `w / det`).
    pub inv_det: L,
    /// Lanes with `det != 0`.
    pub nonzero: u32,
}

/// The watertight test's edge functions of three sheared vertices ([`shear_vertex`]) with their
/// sign decisions as bit masks, per lane the same f32 operations as
/// [`WatertightRay::intersect_within`]. The distance follows with
/// [`WatertightLanes::distance`] (a caller may skip it when no lane can hit).
#[inline(always)]
pub fn watertight_lanes<L: Lanes>(a: [L; 3], b: [L; 3], c: [L; 3]) -> WatertightLanes<L> {
    let e = edge_functions(a, b, c);
    let zero = L::splat(0.0);
    let [u, v, w] = e;
    let exact = L::bits(L::or(L::or(u.eq(zero), v.eq(zero)), w.eq(zero)));
    // Same sign bit in all three (module docs of `WatertightLanes::same_sign`).
    let (su, sv, sw) = (u.sign_bits(), v.sign_bits(), w.sign_bits());
    let all = (1u32 << L::N) - 1;
    WatertightLanes {
        e,
        exact,
        same_sign: !((su ^ sv) | (su ^ sw)) & all,
    }
}

impl<L: Lanes> WatertightLanes<L> {
    /// [`scaled_distance`] of the sheared vertices' `z`, then `t` with one division per lane.
    #[inline(always)]
    pub fn distance(&self, az: L, bz: L, cz: L) -> LaneDistance<L> {
        let (det, t_scaled) = scaled_distance(self.e, az, bz, cz);
        let inv_det = L::splat(1.0) / det;
        LaneDistance {
            t: t_scaled * inv_det,
            inv_det,
            nonzero: L::bits(det.ne(L::splat(0.0))),
        }
    }
}

/// A ray prepared for the watertight test: the permutation and shear of Woop et al. 2013, §3.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    pub origin: Vec3,
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
    pub t_min: f32,
    pub t_max: f32,
}

/// A ray-triangle hit: distance and barycentrics of vertices 1 and 2
/// (`P = (1 - u - v) * v0 + u * v1 + v * v2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl WatertightRay {
    /// Woop et al. 2013, §3: choose the dominant axis `kz`, keep winding by swapping `kx, ky`
    /// when `dir[kz] < 0`, and precompute the shear constants.
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let [kx, ky, kz] = watertight_permutation(ray.dir);
        // Components by array index (a load), not `Vec3`'s `Index` (a branch chain per use).
        let d = ray.dir.to_array();
        Self {
            origin: ray.origin,
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
            t_min: ray.t_min,
            t_max: ray.t_max,
        }
    }

    /// Projects a vertex into the ray's sheared frame ([`shear_vertex`]).
    #[inline(always)]
    fn project(&self, p: Vec3) -> Vec3 {
        let (o, k) = (self.origin, [self.kx, self.ky, self.kz]);
        let [x, y, z] = shear_vertex(
            k.map(|i| p[i]),
            k.map(|i| o[i]),
            [self.sx, self.sy, self.sz],
        );
        Vec3::new(x, y, z)
    }

    /// The watertight test against triangle `(p0, p1, p2)`, for `t` in `(t_min, t_max)`.
    /// Both faces are hit (no culling).
    #[inline]
    pub fn intersect(&self, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<TriangleHit> {
        self.intersect_within(p0, p1, p2, self.t_max)
    }

    /// As [`Self::intersect`] with a tighter upper bound (the closest hit so far).
    #[inline]
    pub fn intersect_within(
        &self,
        p0: Vec3,
        p1: Vec3,
        p2: Vec3,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let a = self.project(p0);
        let b = self.project(p1);
        let c = self.project(p2);
        // Edge functions (2-D cross products) of edges C->B, A->C and B->A at the origin.
        let [mut u, mut v, mut w] = edge_functions(a.to_array(), b.to_array(), c.to_array());
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Woop et al. 2013, §4.1: products of floats are exact in f64, so the signs are too.
            let (ad, bd, cd) = (
                a.truncate().as_dvec2(),
                b.truncate().as_dvec2(),
                c.truncate().as_dvec2(),
            );
            let ud = cd.x * bd.y - cd.y * bd.x;
            let vd = ad.x * cd.y - ad.y * cd.x;
            let wd = bd.x * ad.y - bd.y * ad.x;
            // Keep exact signs even where the f32 cast would flush a tiny value to zero.
            u = f64_to_f32_keep_sign(ud);
            v = f64_to_f32_keep_sign(vd);
            w = f64_to_f32_keep_sign(wd);
            let det = ud + vd + wd;
            if det == 0.0 {
                return None;
            }
            let s = det.signum();
            let (ud, vd, wd) = (ud * s, vd * s, wd * s);
            if ud < 0.0 || vd < 0.0 || wd < 0.0 {
                return None;
            }
            // Tie-break exactly-zero edge functions (module docs). Edge directions, flipped with
            // the orientation so that the triangle is counter-clockwise.
            let dir = |p: DVec2, q: DVec2| (q - p) * s;
            if ud == 0.0 && !owns_edge(dir(cd, bd)) {
                return None;
            }
            if vd == 0.0 && !owns_edge(dir(ad, cd)) {
                return None;
            }
            if wd == 0.0 && !owns_edge(dir(bd, ad)) {
                return None;
            }
        } else if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let (det, t_scaled) = scaled_distance([u, v, w], a.z, b.z, c.z);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        if !(t > self.t_min && t < t_max) {
            return None;
        }
        Some(TriangleHit {
            t,
            u: v * inv,
            v: w * inv,
        })
    }
}

/// The half-open half-plane of edge directions that own their edge (module docs).
#[inline]
fn owns_edge(d: DVec2) -> bool {
    d.y < 0.0 || (d.y == 0.0 && d.x > 0.0)
}

/// `x as f32`, but never rounding a non-zero value to zero (keeps the sign the tests need).
#[inline]
fn f64_to_f32_keep_sign(x: f64) -> f32 {
    let cast = x as f32;
    if cast == 0.0 && x != 0.0 {
        f32::MIN_POSITIVE.copysign(cast)
    } else {
        cast
    }
}

/// Möller & Trumbore 1997: the classic test, fast but not watertight. Kept as the simple twin
/// for cross-checks; the BVH uses [`WatertightRay`].
pub fn intersect_triangle_moller(ray: &Ray, p0: Vec3, p1: Vec3, p2: Vec3) -> Option<TriangleHit> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = ray.dir.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = ray.origin - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = ray.dir.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(qv) * inv;
    (t > ray.t_min && t < ray.t_max).then_some(TriangleHit { t, u, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free permutation equals the paper's nested form, over ties, signed zeros,
    /// infinities and NaN components.
    #[test]
    fn permutation_equals_the_nested_form() {
        let nested = |d: Vec3| {
            let a = d.abs();
            let kz = if a.x > a.y {
                if a.x > a.z { 0 } else { 2 }
            } else if a.y > a.z {
                1
            } else {
                2
            };
            let kx = (kz + 1) % 3;
            let ky = (kx + 1) % 3;
            if d[kz] < 0.0 {
                [ky, kx, kz]
            } else {
                [kx, ky, kz]
            }
        };
        let vals = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            2.0,
            -2.0,
            f32::INFINITY,
            -f32::INFINITY,
            f32::NAN,
        ];
        for &x in &vals {
            for &y in &vals {
                for &z in &vals {
                    let d = Vec3::new(x, y, z);
                    assert_eq!(watertight_permutation(d), nested(d), "{d:?}");
                }
            }
        }
    }

    fn hit(o: Vec3, d: Vec3, p: [Vec3; 3]) -> Option<TriangleHit> {
        WatertightRay::new(&Ray::new(o, d)).intersect(p[0], p[1], p[2])
    }

    #[test]
    fn hits_interior_with_correct_barycentrics() {
        let tri = [
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(1.0, 0.0, -1.0),
            Vec3::new(0.0, 1.0, -1.0),
        ];
        let h = hit(Vec3::new(0.25, 0.25, 0.0), -Vec3::Z, tri).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6);
        // Both faces are hit.
        let h = hit(Vec3::new(0.25, 0.25, -2.0), Vec3::Z, tri).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!(hit(Vec3::new(0.75, 0.75, 0.0), -Vec3::Z, tri).is_none());
        assert!(hit(Vec3::new(0.25, 0.25, -2.0), -Vec3::Z, tri).is_none());
    }

    #[test]
    fn shared_edge_is_owned_by_exactly_one_triangle() {
        // Square split along its diagonal; rays through points on the diagonal.
        let q = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let t0 = [q[0], q[1], q[2]];
        let t1 = [q[0], q[2], q[3]];
        // Interior points of the diagonal (its end points lie on the open boundary).
        for i in 1..64 {
            let s = i as f32 / 64.0;
            for d in [-Vec3::Z, Vec3::Z, Vec3::new(0.1, -0.2, -1.0)] {
                let o = Vec3::new(s, s, 0.0) - d * 3.0;
                let n = hit(o, d, t0).is_some() as u32 + hit(o, d, t1).is_some() as u32;
                assert_eq!(n, 1, "s = {s}, d = {d}");
            }
        }
    }

    #[test]
    fn shared_vertex_is_owned_by_exactly_one_triangle_of_a_fan() {
        for k in [3usize, 4, 5, 6, 8] {
            let c = Vec3::new(0.3, -0.2, 1.0);
            let rim: Vec<Vec3> = (0..k)
                .map(|i| {
                    let a = i as f32 / k as f32 * std::f32::consts::TAU + 0.1;
                    c + Vec3::new(a.cos(), a.sin(), 0.2 * (i % 2) as f32)
                })
                .collect();
            for d in [
                -Vec3::Z,
                Vec3::Z,
                Vec3::new(0.3, 0.1, -1.0),
                Vec3::new(-0.2, 0.4, 1.0),
            ] {
                let o = c - d * 2.0;
                let n = (0..k)
                    .filter(|&i| hit(o, d, [c, rim[i], rim[(i + 1) % k]]).is_some())
                    .count();
                assert_eq!(n, 1, "fan of {k}, d = {d}");
            }
        }
    }

    /// The lane form ([`watertight_lanes`], as the BVH's `Tri4Ray` and HVVR's packet kernels run
    /// it) against the scalar test, lane by lane: the same hits and bit-identical `t`, `u`, `v`
    /// wherever no edge function is exactly zero (those lanes go to the scalar test).
    fn lanes_match_scalar<L: Lanes>() {
        let mut state = 777u32;
        let mut rnd = || {
            state = state.wrapping_mul(747796405).wrapping_add(2891336453);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        let mut hits = 0;
        for _ in 0..500 {
            let o = Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0;
            let d = (Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0).normalize();
            let wt = WatertightRay::new(&Ray::new(o, d));
            // Triangles around points of the ray (about half are hit), of both orientations.
            let tris: Vec<[Vec3; 3]> = (0..L::N)
                .map(|_| {
                    let q = o + d * (0.5 + 3.0 * rnd());
                    std::array::from_fn(|_| q + Vec3::new(rnd(), rnd(), rnd()) - 0.5)
                })
                .collect();
            let k = [wt.kx, wt.ky, wt.kz];
            let vertex = |v: usize| k.map(|a| L::from_fn(|l| tris[l][v][a]));
            let (ol, shear) = (
                k.map(|a| L::splat(wt.origin[a])),
                [wt.sx, wt.sy, wt.sz].map(L::splat),
            );
            let [a, b, c] = [0, 1, 2].map(|v| shear_vertex(vertex(v), ol, shear));
            let r = watertight_lanes(a, b, c);
            let dist = r.distance(a[2], b[2], c[2]);
            for (l, p) in tris.iter().enumerate() {
                if r.exact >> l & 1 == 1 {
                    continue;
                }
                let t = dist.t.get(l);
                let inside = r.same_sign & dist.nonzero;
                let lane_hit = inside >> l & 1 == 1 && t > wt.t_min && t < wt.t_max;
                let scalar = wt.intersect(p[0], p[1], p[2]);
                assert_eq!(lane_hit, scalar.is_some(), "lane {l}");
                if let Some(h) = scalar {
                    hits += 1;
                    let inv = dist.inv_det.get(l);
                    assert_eq!(h.t.to_bits(), t.to_bits());
                    assert_eq!(h.u.to_bits(), (r.e[1].get(l) * inv).to_bits());
                    assert_eq!(h.v.to_bits(), (r.e[2].get(l) * inv).to_bits());
                }
            }
        }
        assert!(
            hits * 5 > 500 * L::N,
            "only {hits} hits: the test would not see a difference"
        );
    }

    #[test]
    fn lanes_equal_the_scalar_test() {
        lanes_match_scalar::<f32>();
        lanes_match_scalar::<glam::Vec4>();
        lanes_match_scalar::<crate::simd::F8>();
    }

    #[test]
    fn permutation_keeps_the_dominant_axis_last() {
        assert_eq!(watertight_permutation(Vec3::new(0.1, -0.2, 1.0)), [0, 1, 2]);
        assert_eq!(
            watertight_permutation(Vec3::new(0.1, -0.2, -1.0)),
            [1, 0, 2]
        );
        assert_eq!(watertight_permutation(Vec3::new(3.0, -0.2, 1.0)), [1, 2, 0]);
        assert_eq!(watertight_permutation(Vec3::new(0.0, -3.0, 1.0)), [0, 2, 1]);
    }

    #[test]
    fn agrees_with_moller_away_from_edges() {
        let mut state = 12345u32;
        let mut rnd = || {
            state = state.wrapping_mul(747796405).wrapping_add(2891336453);
            (state >> 8) as f32 / (1 << 24) as f32
        };
        for _ in 0..2000 {
            let p: [Vec3; 3] = std::array::from_fn(|_| Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0);
            let o = Vec3::new(rnd(), rnd(), rnd()) * 4.0 - 2.0;
            let d = (Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0).normalize();
            let ray = Ray::new(o, d);
            let a = WatertightRay::new(&ray).intersect(p[0], p[1], p[2]);
            let b = intersect_triangle_moller(&ray, p[0], p[1], p[2]);
            match (a, b) {
                (Some(a), Some(b)) => assert!((a.t - b.t).abs() < 1e-3 * (1.0 + a.t.abs())),
                (None, None) => {}
                (a, b) => {
                    // Disagreement allowed only right at an edge.
                    let h = a.or(b).unwrap();
                    let w = 1.0 - h.u - h.v;
                    assert!(h.u.min(h.v).min(w).abs() < 1e-4, "{a:?} vs {b:?}");
                }
            }
        }
    }
}
