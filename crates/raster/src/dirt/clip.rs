//! Fixed-capacity convex polygon clipping (Sutherland & Hodgman 1974, "Reentrant polygon
//! clipping"), allocation-free, in f64.
//!
//! A polygon is a list of up to [`MAX_VERTS`] points `DVec3`. In camera space the three
//! components are `(x, y, z)`; on the film they are `(film x, film y, w = 1 / view depth)`:
//! `1 / depth` of a point on a 3-D segment is affine in the segment's projected 2-D parameter,
//! so linear interpolation of `w` during 2-D clipping is exact (perspective-correct), also for
//! triangles seen edge-on.
//!
//! Every clip keeps the closed half-space (`distance >= 0`), so a polygon touching a clip line
//! in a single point or an edge survives as a degenerate polygon: the footprint stays
//! conservative.

use glam::DVec3;

/// A triangle gains at most one vertex per clip plane: 3 + near + 4 guard planes + 2 row + 2
/// column clips = 12.
pub const MAX_VERTS: usize = 12;

/// A convex polygon with inline storage.
#[derive(Clone, Copy, Debug)]
pub struct Poly {
    pub v: [DVec3; MAX_VERTS],
    pub n: usize,
}

impl Poly {
    pub const EMPTY: Poly = Poly {
        v: [DVec3::ZERO; MAX_VERTS],
        n: 0,
    };

    pub fn from_triangle(t: [DVec3; 3]) -> Poly {
        let mut p = Poly::EMPTY;
        p.v[..3].copy_from_slice(&t);
        p.n = 3;
        p
    }

    #[inline]
    pub fn verts(&self) -> &[DVec3] {
        &self.v[..self.n]
    }

    #[inline]
    fn push(&mut self, p: DVec3) {
        // Capacity is guaranteed by MAX_VERTS (each clip adds at most one vertex); the check
        // only guards against misuse.
        if self.n < MAX_VERTS {
            self.v[self.n] = p;
            self.n += 1;
        }
    }

    /// Keeps the part with `plane.dot(p) + offset >= 0` (Sutherland-Hodgman, one plane).
    pub fn clip_plane(&self, plane: DVec3, offset: f64) -> Poly {
        self.clip_by(|p| plane.dot(p) + offset, |_| {})
    }

    /// Keeps the part with `sign * (p[axis] - value) >= 0`; output vertices created on the
    /// clip line get `p[axis] = value` exactly.
    pub fn clip_axis(&self, axis: usize, value: f64, sign: f64) -> Poly {
        self.clip_by(|p| sign * (p[axis] - value), |q| q[axis] = value)
    }

    /// Generic Sutherland-Hodgman step: `dist` is the signed distance (keep `>= 0`), `snap`
    /// may fix up a newly created intersection vertex.
    #[inline]
    fn clip_by(&self, dist: impl Fn(DVec3) -> f64, snap: impl Fn(&mut DVec3)) -> Poly {
        let mut out = Poly::EMPTY;
        let n = self.n;
        if n == 0 {
            return out;
        }
        let mut a = self.v[n - 1];
        let mut da = dist(a);
        for i in 0..n {
            let b = self.v[i];
            let db = dist(b);
            let a_in = da >= 0.0;
            let b_in = db >= 0.0;
            if a_in != b_in {
                // The edge crosses the plane: da and db have opposite signs (one may be 0 only
                // on the inside side), so t = da / (da - db) is in [0, 1].
                let t = da / (da - db);
                let mut q = a + (b - a) * t;
                snap(&mut q);
                out.push(q);
            }
            if b_in {
                out.push(b);
            }
            a = b;
            da = db;
        }
        out
    }

    /// Component-wise min and max over the polygon clipped to the slab
    /// `lo <= p[axis] <= hi` ([`span_in_slab`]).
    #[inline]
    pub fn span_in_slab(&self, axis: usize, lo: f64, hi: f64) -> Option<(DVec3, DVec3)> {
        span_in_slab(self.verts(), axis, lo, hi)
    }

    /// Min and max of `p.z` over the polygon clipped to the strip `left <= p.x <= right`
    /// ([`Self::span_in_slab`] along x).
    #[inline]
    pub fn z_range_in_strip(&self, left: f64, right: f64) -> Option<(f64, f64)> {
        self.span_in_slab(0, left, right)
            .map(|(lo, hi)| (lo.z, hi.z))
    }

    /// Min and max of component `axis` over the vertices (`None` if empty).
    #[inline]
    pub fn range(&self, axis: usize) -> Option<(f64, f64)> {
        if self.n == 0 {
            return None;
        }
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for p in self.verts() {
            lo = lo.min(p[axis]);
            hi = hi.max(p[axis]);
        }
        Some((lo, hi))
    }
}

/// Component-wise min and max over the convex polygon `verts` clipped to the slab
/// `lo <= p[axis] <= hi`, without building the clipped polygon: its vertices are the
/// polygon's vertices inside the slab plus its edges' crossings of the two lines (the same
/// points two Sutherland-Hodgman steps would produce). `None` if the slab misses the polygon.
#[inline]
pub fn span_in_slab(verts: &[DVec3], axis: usize, lo: f64, hi: f64) -> Option<(DVec3, DVec3)> {
    let &last = verts.last()?;
    let mut min = DVec3::INFINITY;
    let mut max = DVec3::NEG_INFINITY;
    let mut a = last;
    for &b in verts {
        if b[axis] >= lo && b[axis] <= hi {
            min = min.min(b);
            max = max.max(b);
        }
        for line in [lo, hi] {
            // Strict crossing (an endpoint on the line is a vertex handled above).
            if (a[axis] < line && b[axis] > line) || (a[axis] > line && b[axis] < line) {
                let t = (line - a[axis]) / (b[axis] - a[axis]);
                let mut p = a + (b - a) * t;
                p[axis] = line;
                min = min.min(p);
                max = max.max(p);
            }
        }
        a = b;
    }
    (min.x <= max.x).then_some((min, max))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_square_keeps_inside_and_interpolates() {
        // Triangle (0,0,w=1) (4,0,w=1) (0,4,w=3): w = 1 + y/2.
        let t = Poly::from_triangle([
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(4.0, 0.0, 1.0),
            DVec3::new(0.0, 4.0, 3.0),
        ]);
        let c = t
            .clip_axis(0, 1.0, 1.0)
            .clip_axis(0, 2.0, -1.0)
            .clip_axis(1, 1.0, 1.0)
            .clip_axis(1, 2.0, -1.0);
        assert!(c.n >= 4, "{c:?}");
        for p in c.verts() {
            assert!((1.0..=2.0).contains(&p.x) && (1.0..=2.0).contains(&p.y));
            assert!((p.z - (1.0 + p.y / 2.0)).abs() < 1e-12);
        }
        assert_eq!(c.range(2), Some((1.5, 2.0)));
        // The strip shortcut equals clipping.
        for (l, r) in [(1.0, 2.0), (-1.0, 0.5), (3.5, 9.0), (0.0, 0.0), (4.0, 4.0)] {
            let c = t.clip_axis(0, l, 1.0).clip_axis(0, r, -1.0);
            assert_eq!(t.z_range_in_strip(l, r), c.range(2), "[{l}, {r}]");
        }
        assert_eq!(t.z_range_in_strip(4.5, 5.0), None);
        // Touching in a single point survives; strictly outside does not.
        assert!(t.clip_axis(0, 4.0, 1.0).n > 0);
        assert_eq!(t.clip_axis(0, 4.5, 1.0).n, 0);
    }
}
