//! Axis-aligned bounding boxes.

use glam::Vec3;

use super::Ray;

/// An axis-aligned box. The empty box has `min = +inf, max = -inf`, so that growing it by any
/// point gives that point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The bounds of a set of points.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    #[inline]
    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area (0 for the empty box), the cost measure of the SAH.
    #[inline]
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index of the longest axis.
    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Slab test (Kay & Kajiya 1986) with the conservative far-distance scaling of Ize 2013
    /// ("Robust BVH Ray Traversal", JCGT 2(2)): `t_far *= 1 + 2 * gamma(3)`, so that rounding in
    /// the slab distances never culls a box the ray truly touches. Returns the entry and exit
    /// distances clamped to the ray's interval, or `None`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, inv_dir: Vec3) -> Option<(f32, f32)> {
        let t0 = (self.min - ray.origin) * inv_dir;
        let t1 = (self.max - ray.origin) * inv_dir;
        let near = t0.min(t1);
        let far = t0.max(t1);
        let t_near = near.max_element().max(ray.t_min);
        let t_far = far.min_element() * ROBUST_FAR_SCALE;
        let t_far = t_far.min(ray.t_max);
        (t_near <= t_far).then_some((t_near, t_far))
    }
}

/// `1 + 2 * gamma(3)` with `gamma(n) = n * eps / (1 - n * eps)`, eps = 2^-24 (Ize 2013; pbrt-v3 §3.9).
pub const ROBUST_FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_box_grows_to_point_and_has_zero_area() {
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
        let b = Aabb::EMPTY.grow(Vec3::ONE);
        assert_eq!(b.min, Vec3::ONE);
        assert_eq!(b.max, Vec3::ONE);
    }

    #[test]
    fn slab_test_hits_and_misses() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
        let (n, f) = b.intersect(&r, r.dir.recip()).unwrap();
        assert!((n - 4.0).abs() < 1e-6 && (f - 6.0).abs() < 1e-4);
        let r = Ray::new(Vec3::new(2.0, 0.0, 5.0), -Vec3::Z);
        assert!(b.intersect(&r, r.dir.recip()).is_none());
        // Axis-parallel ray on the box face plane: inf * 0 gives NaN, which min/max discard.
        let r = Ray::new(Vec3::new(0.5, 0.5, 5.0), -Vec3::Z);
        assert!(b.intersect(&r, r.dir.recip()).is_some());
    }
}
