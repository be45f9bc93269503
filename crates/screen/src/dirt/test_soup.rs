//! A random triangle soup for the unit tests of the tracer's per-cell structures
//! (`cells.rs`, `slabs.rs`): small triangles scattered through a box, so every view of a
//! DIRT capture sees overlapping lists in many buckets.

use glam::{Vec2, Vec3};
use parallax_core::sampling::Rng;
use parallax_scene::TriangleMesh;

/// `count` triangles with centres uniform in a 20-unit box around the origin and corners
/// within 1 unit of their centre, drawn from `rng` (which a test may go on drawing from).
pub(super) fn random_soup(rng: &mut Rng, count: usize) -> TriangleMesh {
    let mut r = |s: f32| (rng.next_f32() - 0.5) * s;
    let mut m = TriangleMesh::default();
    for _ in 0..count {
        let c = Vec3::new(r(20.0), r(20.0), r(20.0));
        let base = m.positions.len() as u32;
        for _ in 0..3 {
            m.positions.push(c + Vec3::new(r(2.0), r(2.0), r(2.0)));
            m.normals.push(Vec3::ZERO);
            m.uvs.push(Vec2::ZERO);
        }
        m.indices.push([base, base + 1, base + 2]);
        m.material_ids.push(0);
    }
    m
}
