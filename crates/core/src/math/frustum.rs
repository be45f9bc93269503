//! Frusta: convex volumes bounded by planes (view frusta, beams, pixel frusta).

use glam::{Mat4, Vec3};

use super::{Aabb, Plane};

/// A convex volume: the points on the non-negative side of every plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Frustum {
    pub planes: Vec<Plane>,
}

/// How a box lies against a frustum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    Outside,
    Partial,
    Inside,
}

impl Frustum {
    /// The six planes of a clip-space frustum `-w <= x, y <= w`, `0 <= z <= w` (glam's
    /// right-handed, depth 0..1 projections) from a view-projection matrix (Gribb & Hartmann 2001).
    pub fn from_view_projection(m: &Mat4) -> Self {
        let r0 = m.row(0);
        let r1 = m.row(1);
        let r2 = m.row(2);
        let r3 = m.row(3);
        let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2]
            .into_iter()
            .map(|v| {
                let n = v.truncate();
                let l = n.length();
                Plane::new(n / l, v.w / l)
            })
            .collect();
        Self { planes }
    }

    pub fn contains_point(&self, p: Vec3) -> bool {
        self.planes.iter().all(|pl| pl.signed_distance(p) >= 0.0)
    }

    /// Conservative box classification by the box's nearest and farthest corners per plane.
    /// `Outside` is exact for "outside one plane"; boxes outside the frustum but not outside any
    /// single plane report `Partial` (the usual conservative answer).
    pub fn classify(&self, b: &Aabb) -> Containment {
        let mut inside = true;
        for pl in &self.planes {
            let n = pl.normal;
            let far = Vec3::select(n.cmpge(Vec3::ZERO), b.max, b.min);
            let near = Vec3::select(n.cmpge(Vec3::ZERO), b.min, b.max);
            if pl.signed_distance(far) < 0.0 {
                return Containment::Outside;
            }
            if pl.signed_distance(near) < 0.0 {
                inside = false;
            }
        }
        if inside {
            Containment::Inside
        } else {
            Containment::Partial
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn view_frustum_contains_points_in_front() {
        let proj = Mat4::perspective_rh(60f32.to_radians(), 1.0, 0.1, 100.0);
        let f = Frustum::from_view_projection(&proj);
        assert!(f.contains_point(Vec3::new(0.0, 0.0, -1.0)));
        assert!(!f.contains_point(Vec3::new(0.0, 0.0, 1.0)));
        assert!(!f.contains_point(Vec3::new(10.0, 0.0, -1.0)));
        let b = Aabb::new(Vec3::new(-0.1, -0.1, -2.0), Vec3::new(0.1, 0.1, -1.0));
        assert_eq!(f.classify(&b), Containment::Inside);
        let b = Aabb::new(Vec3::new(-0.1, -0.1, 1.0), Vec3::new(0.1, 0.1, 2.0));
        assert_eq!(f.classify(&b), Containment::Outside);
    }
}
