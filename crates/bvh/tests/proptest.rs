//! Property test: on arbitrary small triangle soups and rays, the BVH equals brute force.

mod common;

use common::*;
use glam::Vec3;
use parallax_bvh::{BuildOptions, Bvh};
use parallax_core::Ray;
use proptest::prelude::*;

fn v3() -> impl Strategy<Value = Vec3> {
    // Coarse coordinates so that coincident planes, shared edges and axis-parallel rays occur.
    (-8i32..=8, -8i32..=8, -8i32..=8)
        .prop_map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32) * 0.25)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn bvh_equals_brute_force(
        tris in prop::collection::vec((v3(), v3(), v3()), 1..120),
        rays in prop::collection::vec((v3(), v3()), 1..40),
        leaf in 1usize..8,
    ) {
        let mut p = Vec::new();
        for (a, b, c) in &tris {
            p.extend([*a, *b, *c]);
        }
        let idx = (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let mesh = mesh_from(p, idx);
        let bvh = Bvh::build_with(&mesh, &BuildOptions { max_leaf_size: leaf, ..Default::default() });
        for (o, d) in rays {
            let r = Ray::new(o, d);
            check_closest(&bvh, &mesh, &r, "proptest");
            check_all(&bvh, &mesh, &r, "proptest");
        }
    }
}
