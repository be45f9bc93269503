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
//! [`intersect_triangle_moller`] (Möller & Trumbore 1997) is kept as the simple, non-watertight
//! twin used by tests and benchmarks.

use glam::{DVec2, Vec3};

use super::Ray;

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
        let d = ray.dir;
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
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

    /// Projects a vertex into the ray's sheared frame: `(x, y, z)` where the ray is the +z axis.
    /// Every triangle sharing a vertex gets bit-identical projected coordinates.
    #[inline(always)]
    fn project(&self, p: Vec3) -> Vec3 {
        let a = p - self.origin;
        let az = a[self.kz];
        Vec3::new(
            a[self.kx] - self.sx * az,
            a[self.ky] - self.sy * az,
            self.sz * az,
        )
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
        let mut u = c.x * b.y - c.y * b.x;
        let mut v = a.x * c.y - a.y * c.x;
        let mut w = b.x * a.y - b.y * a.x;
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
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * a.z + v * b.z + w * c.z;
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
