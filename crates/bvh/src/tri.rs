//! The BVH's copy of the triangles, in leaf order.

use glam::Vec3;
use parallax_core::Aabb;

/// A triangle's three corners, gathered from the mesh in the order the BVH's leaves reference
/// them, so a leaf test reads one contiguous run of memory (HVVR §5.2, "gather vertices").
/// Corner order is the mesh's, so barycentrics `(u, v)` refer to the mesh's vertices 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Tri {
    pub p0: Vec3,
    pub p1: Vec3,
    pub p2: Vec3,
}

impl Tri {
    #[inline]
    pub fn new([p0, p1, p2]: [Vec3; 3]) -> Self {
        Self { p0, p1, p2 }
    }

    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.p0.min(self.p1).min(self.p2),
            self.p0.max(self.p1).max(self.p2),
        )
    }
}
