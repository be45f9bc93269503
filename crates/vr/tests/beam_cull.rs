//! Beam culling (HVVR §5.3-5.4): the beam/box test is conservative against brute-force points of
//! the beam, the SIMD and scalar culls give identical lists, and every triangle a bundle ray
//! hits is in its tile's list.

use glam::{Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_bvh::node::{leaf_count, leaf_first};
use parallax_core::{Aabb, Ray, Rng};
use parallax_scene::camera::{CameraModel, Pinhole};
use parallax_vr::beam::{BLOCK_ENTRIES, CullScratch, ScalarBeam, SimdBeam, block_cull, tile_cull};
use parallax_vr::beam::{Beam, BeamBuilder, BeamTest, PreparedBeam};
use proptest::prelude::*;

fn beam_strategy() -> impl Strategy<Value = Beam> {
    (
        0u8..3,
        any::<bool>(),
        (-2.0f32..2.0, 0.0f32..1.5),
        (-2.0f32..2.0, 0.0f32..1.5),
        prop::array::uniform3(-5.0f32..5.0),
        prop::array::uniform3(0.0f32..0.5),
    )
        .prop_map(|(axis, pos, (u0, du), (v0, dv), o, e)| {
            let o = Vec3::from(o);
            Beam {
                axis,
                sign: if pos { 1.0 } else { -1.0 },
                u: [u0, u0 + du],
                v: [v0, v0 + dv],
                origin: Aabb::new(o, o + Vec3::from(e)),
                everything: false,
            }
        })
}

/// A point of the beam: `o + λ (s e_a + u e_b + v e_c)` for parameters in [0, 1]^5.
fn beam_point(b: &Beam, r: [f32; 6]) -> Vec3 {
    let (a, x, y) = (b.axis as usize, b.side_axes().0, b.side_axes().1);
    let o = b.origin.min + (b.origin.max - b.origin.min) * Vec3::new(r[0], r[1], r[2]);
    let lam = r[3] * 20.0;
    let u = b.u[0] + (b.u[1] - b.u[0]) * r[4];
    let v = b.v[0] + (b.v[1] - b.v[0]) * r[5];
    let mut p = o;
    p[a] += b.sign * lam;
    p[x] += u * lam;
    p[y] += v * lam;
    p
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// A box holding a point of the beam is never a Miss; a Contained box's corners satisfy the
    /// beam's plane inequalities.
    #[test]
    fn boxes_touching_the_beam_are_not_missed(
        beam in beam_strategy(),
        r in prop::array::uniform6(0.0f32..=1.0),
        lo in prop::array::uniform3(0.0f32..3.0),
        hi in prop::array::uniform3(0.0f32..3.0),
    ) {
        let p = beam_point(&beam, r);
        let b = Aabb::new(p - Vec3::from(lo), p + Vec3::from(hi));
        prop_assert_ne!(beam.test_box(&b, 30.0), BeamTest::Miss);
        let point = Aabb::new(p, p);
        prop_assert_ne!(beam.test_box(&point, 30.0), BeamTest::Miss);
        if beam.test_box(&b, 30.0) == BeamTest::Contained {
            for (ca, x, cx, k) in beam.planes() {
                for i in 0..8 {
                    let c = Vec3::new(
                        if i & 1 == 0 { b.min.x } else { b.max.x },
                        if i & 2 == 0 { b.min.y } else { b.max.y },
                        if i & 4 == 0 { b.min.z } else { b.max.z },
                    );
                    let f = ca * c[beam.axis as usize] + cx * c[x];
                    prop_assert!(f >= k - 1e-3, "corner {c} outside a plane");
                }
            }
        }
    }
}

/// Tile beams of a pinhole camera on atrium: `(beam, rays)` per 16 x 8 tile of a 96 x 64 film.
fn tiles(spp: usize) -> Vec<(Beam, Vec<Ray>)> {
    let scene = parallax_scene::Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 96, 64).unwrap();
    let mut rng = Rng::new(3, 0);
    let mut out = Vec::new();
    for ty in 0..8 {
        for tx in 0..6 {
            let mut b = BeamBuilder::new();
            let mut rays = Vec::new();
            for y in 0..8 {
                for x in 0..16 {
                    for _ in 0..spp {
                        let f = Vec2::new(
                            (tx * 16 + x) as f32 + rng.next_f32(),
                            (ty * 8 + y) as f32 + rng.next_f32(),
                        );
                        let r = cam.generate_ray(f, Vec2::ZERO, 0).unwrap().ray;
                        b.add(&r);
                        rays.push(r);
                    }
                }
            }
            out.push((b.finish().unwrap(), rays));
        }
    }
    out
}

fn scale(bvh: &Bvh) -> f32 {
    let b = bvh.bounds();
    b.min.abs().max(b.max.abs()).max_element() + 10.0
}

#[test]
fn simd_and_scalar_culls_give_identical_lists() {
    let scene = parallax_scene::Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let tiles = tiles(1);
    // A "block" of four tiles.
    for group in tiles.chunks(4) {
        let mut acc = BeamBuilder::new();
        for (_, rays) in group {
            for r in rays {
                acc.add(r);
            }
        }
        let block = PreparedBeam::new(&acc.finish().unwrap(), scale(&bvh));
        let (mut s1, mut s2) = (CullScratch::default(), CullScratch::default());
        block_cull(&bvh, &SimdBeam::new(&block), BLOCK_ENTRIES, &mut s1);
        block_cull(&bvh, &ScalarBeam(&block), BLOCK_ENTRIES, &mut s2);
        assert_eq!(s1.entries, s2.entries);
        assert!(!s1.entries.is_empty());
        assert!(s1.entries.len() <= BLOCK_ENTRIES + 3);
        assert!(s1.entries.windows(2).all(|w| w[0].near <= w[1].near));
        let entries = s1.entries.clone();
        for (beam, _) in group {
            let tb = PreparedBeam::new(beam, scale(&bvh));
            tile_cull(&bvh, &SimdBeam::new(&tb), &entries, &mut s1);
            tile_cull(&bvh, &ScalarBeam(&tb), &entries, &mut s2);
            assert_eq!(s1.leaves, s2.leaves);
            assert!(s1.leaves.windows(2).all(|w| w[0].near <= w[1].near));
        }
    }
}

#[test]
fn every_triangle_a_tile_ray_hits_is_in_the_tile_list() {
    let scene = parallax_scene::Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let mut hits = Vec::new();
    let (mut checked, mut tris_total) = (0usize, 0usize);
    for (beam, rays) in tiles(2) {
        let pb = PreparedBeam::new(&beam, scale(&bvh));
        let mut s = CullScratch::default();
        block_cull(&bvh, &SimdBeam::new(&pb), BLOCK_ENTRIES, &mut s);
        let entries = s.entries.clone();
        tile_cull(&bvh, &SimdBeam::new(&pb), &entries, &mut s);
        let mut listed = std::collections::HashSet::new();
        for l in &s.leaves {
            let (first, count) = (leaf_first(l.leaf), leaf_count(l.leaf));
            for t in bvh.leaf_triangles(first, count) {
                listed.insert(bvh.prim_ids()[t]);
            }
        }
        tris_total += listed.len();
        for r in &rays {
            assert!(beam.contains_ray(r, 0.0));
            bvh.all_hits(r, &mut hits);
            for h in &hits {
                assert!(
                    listed.contains(&h.prim),
                    "triangle {} hit but culled",
                    h.prim
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 1000, "{checked}");
    // The culling culls: far fewer triangles per tile than the scene has.
    let per_tile = tris_total as f64 / 48.0;
    assert!(
        per_tile < bvh.triangle_count() as f64 * 0.5,
        "{per_tile} of {}",
        bvh.triangle_count()
    );
}
