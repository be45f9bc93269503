//! The BVH behind the world-space tracer interface: the exact reference every other
//! world-space structure (DIRT, the layered depth cube, cube-map quad-trees) is compared with.

use glam::Vec2;
use parallax_core::{Ray, WorldHit, WorldStats, WorldTracer};

use crate::bvh::Bvh;
use crate::stats::TraversalStats;

impl WorldTracer for Bvh {
    fn name(&self) -> &str {
        "bvh"
    }

    fn is_exact(&self) -> bool {
        true
    }

    fn closest_hit(&self, ray: &Ray, stats: &mut WorldStats) -> Option<WorldHit> {
        let mut s = TraversalStats::default();
        let hit = if ray.is_valid() {
            self.closest_hit_with_stats(ray, &mut s)
        } else {
            None
        };
        add(stats, &s);
        hit.map(|h| WorldHit::exact(ray, h.t, h.prim, Vec2::new(h.u, h.v)))
    }

    fn occluded(&self, ray: &Ray, stats: &mut WorldStats) -> bool {
        let mut s = TraversalStats::default();
        let hit = ray.is_valid() && self.any_hit_with_stats(ray, &mut s);
        add(stats, &s);
        hit
    }
}

#[inline]
fn add(stats: &mut WorldStats, s: &TraversalStats) {
    stats.rays += 1;
    stats.nodes += s.nodes_visited;
    stats.tests += s.triangle_tests;
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use parallax_core::HitSurface;
    use parallax_scene::TriangleMesh;

    use super::*;

    fn quad() -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            material_ids: vec![0, 0],
            ..Default::default()
        }
    }

    #[test]
    fn world_tracer_answers_as_the_bvh() {
        let mesh = quad();
        let bvh = Bvh::build(&mesh);
        let tracer: &dyn WorldTracer = &bvh;
        let mut stats = WorldStats::default();
        let ray = Ray::new(Vec3::new(0.3, -0.2, 2.0), -Vec3::Z);
        let h = tracer.closest_hit(&ray, &mut stats).expect("hits the quad");
        let b = bvh.closest_hit(&ray).unwrap();
        assert_eq!((h.t, h.prim), (b.t, b.prim));
        assert_eq!(h.surface, HitSurface::Exact);
        assert!((h.position - Vec3::new(0.3, -0.2, 0.0)).length() < 1e-6);
        assert!(tracer.occluded(&ray, &mut stats));
        let short = Ray::segment(ray.origin, ray.dir, 0.0, 1.0);
        assert!(!tracer.occluded(&short, &mut stats));
        assert!(tracer.closest_hit(&short, &mut stats).is_none());
        let nan = Ray::new(Vec3::NAN, -Vec3::Z);
        assert!(tracer.closest_hit(&nan, &mut stats).is_none());
        assert!(!tracer.occluded(&nan, &mut stats));
        assert_eq!(stats.rays, 6);
        assert!(stats.tests > 0);
    }
}
