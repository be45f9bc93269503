//! Planes.

use glam::{Vec3, Vec4};

use super::Ray;

/// The plane `normal . p + d = 0`. `normal` is unit length for planes built by the constructors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: Vec3,
    pub d: f32,
}

impl Plane {
    pub fn new(normal: Vec3, d: f32) -> Self {
        Self { normal, d }
    }

    /// The plane through `p` with unit normal `n`.
    pub fn from_point_normal(p: Vec3, n: Vec3) -> Self {
        let n = n.normalize();
        Self {
            normal: n,
            d: -n.dot(p),
        }
    }

    /// The plane through three points, oriented by the right-hand rule `(b - a) x (c - a)`.
    pub fn from_points(a: Vec3, b: Vec3, c: Vec3) -> Option<Self> {
        let n = (b - a).cross(c - a);
        (n.length_squared() > 0.0).then(|| Self::from_point_normal(a, n))
    }

    /// Signed distance of `p` (in units of |normal|).
    #[inline]
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) + self.d
    }

    /// `t` where the ray meets the plane, if it is not parallel to it.
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<f32> {
        let denom = self.normal.dot(ray.dir);
        (denom != 0.0).then(|| -self.signed_distance(ray.origin) / denom)
    }

    /// As `(nx, ny, nz, d)`.
    pub fn to_vec4(&self) -> Vec4 {
        self.normal.extend(self.d)
    }
}
