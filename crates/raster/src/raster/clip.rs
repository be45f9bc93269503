//! Homogeneous clipping of a triangle against the near and far planes and an x/y guard band
//! (Sutherland & Hodgman 1974 polygon clipping, done in homogeneous clip space before the
//! divide as in Blinn & Newell 1978, "Clipping using homogeneous coordinates").
//!
//! The guard band (e.g. the "guard-band clipping" of D3D/GPU rasterizers) keeps screen
//! coordinates within the fixed-point range: x and y are only clipped when a vertex lies
//! beyond `|x| <= g w`, `|y| <= g w`, far outside the viewport, so almost every visible
//! triangle is rasterized unclipped and its edges stay exactly those of the mesh.

use glam::DVec4;

/// At most 3 + one vertex per plane (6 planes).
pub const MAX_POLY: usize = 9;

/// A clip-space polygon on the stack.
#[derive(Clone, Copy, Debug)]
pub struct Poly {
    pub v: [DVec4; MAX_POLY],
    pub n: usize,
}

impl Poly {
    pub fn triangle(a: DVec4, b: DVec4, c: DVec4) -> Self {
        let mut v = [DVec4::ZERO; MAX_POLY];
        v[0] = a;
        v[1] = b;
        v[2] = c;
        Self { v, n: 3 }
    }
}

/// The clip planes as signed distance functions of a clip vector `(x, y, d, w)`; a vertex is
/// inside where all are `>= 0`.
#[derive(Clone, Copy, Debug)]
pub struct Planes {
    pub near: f64,
    pub far: f64,
    /// Guard band half-extent in NDC units (>= 1).
    pub guard: f64,
}

impl Planes {
    #[inline]
    fn dist(&self, i: usize, c: DVec4) -> f64 {
        match i {
            0 => c.z - self.near,
            1 => self.far - c.z,
            2 => self.guard * c.w - c.x,
            3 => self.guard * c.w + c.x,
            4 => self.guard * c.w - c.y,
            _ => self.guard * c.w + c.y,
        }
    }

    /// Out-codes: bit `i` set when the vertex is outside plane `i`.
    #[inline]
    pub fn outcode(&self, c: DVec4) -> u8 {
        let mut code = 0;
        for i in 0..6 {
            // `!(>= 0)` also flags NaN as outside.
            if !(self.dist(i, c) >= 0.0) {
                code |= 1 << i;
            }
        }
        code
    }

    /// Clips `poly` against the planes whose bits are set in `planes`; returns the clipped
    /// polygon (possibly empty).
    pub fn clip(&self, poly: &Poly, planes: u8) -> Poly {
        let mut cur = *poly;
        for i in 0..6 {
            if planes & (1 << i) == 0 || cur.n == 0 {
                continue;
            }
            let mut out = Poly {
                v: [DVec4::ZERO; MAX_POLY],
                n: 0,
            };
            for k in 0..cur.n {
                let a = cur.v[k];
                let b = cur.v[(k + 1) % cur.n];
                let (da, db) = (self.dist(i, a), self.dist(i, b));
                if da >= 0.0 && out.n < MAX_POLY {
                    out.v[out.n] = a;
                    out.n += 1;
                }
                if (da >= 0.0) != (db >= 0.0) && out.n < MAX_POLY {
                    // The crossing point; `da - db` is non-zero since the signs differ.
                    let t = da / (da - db);
                    out.v[out.n] = a + (b - a) * t;
                    out.n += 1;
                }
            }
            cur = out;
        }
        if cur.n < 3 {
            cur.n = 0;
        }
        cur
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_plane_cuts_a_triangle_into_a_quad() {
        let p = Planes {
            near: 1.0,
            far: f64::INFINITY,
            guard: 4.0,
        };
        let t = Poly::triangle(
            DVec4::new(0.0, 0.0, 0.5, 0.5),
            DVec4::new(1.0, 0.0, 2.0, 2.0),
            DVec4::new(0.0, 1.0, 2.0, 2.0),
        );
        assert_eq!(p.outcode(t.v[0]), 1);
        let c = p.clip(&t, 1);
        assert_eq!(c.n, 4);
        for v in &c.v[..c.n] {
            assert!(v.z >= 1.0 - 1e-12, "{v}");
        }
        let all_out = Poly::triangle(DVec4::splat(-1.0), DVec4::splat(-1.0), DVec4::splat(-2.0));
        assert_eq!(p.clip(&all_out, 1).n, 0);
    }
}
