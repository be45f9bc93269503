//! Exact `t` ties between different triangles: the closest hit is the lowest primitive id at
//! the smallest `t` (brute force's rule), on every path (8- and 4-wide single rays, the scalar
//! twin, 16-ray packets, 64-ray packets, every lane type) and in every tree: the object-split
//! build and builds with spatial splits (the default among them), which duplicate references,
//! give the same primitive for every ray. The mesh is made of ties: each triangle of a random soup and of two overlapping
//! coplanar grids is stored three times under scattered indices.

mod common;

use common::*;
use glam::Vec3;
use parallax_bvh::{BuildOptions, Bvh, Hit, PacketLanes, brute_force_all, brute_force_closest};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

/// Every triangle of `base` three times (same vertices, same order), the copies' indices
/// scattered by a seeded shuffle.
fn tripled(base: &TriangleMesh, seed: u64) -> TriangleMesh {
    let mut tris: Vec<[Vec3; 3]> = (0..base.triangle_count())
        .flat_map(|i| [base.triangle(i); 3])
        .collect();
    let mut rng = Rng::new(seed);
    for i in (1..tris.len()).rev() {
        tris.swap(i, rng.next_u32() as usize % (i + 1));
    }
    let positions = tris.iter().flatten().copied().collect();
    let indices = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    mesh_from(positions, indices)
}

/// A random soup, a grid in the plane y = 0 and a second, coplanar grid over it with another
/// triangulation (overlapping triangles at equal depth), each triangle tripled.
fn tie_mesh() -> TriangleMesh {
    let mut p = Vec::new();
    let mut idx = Vec::new();
    let shifted = {
        let mut g = grid(7);
        for v in &mut g.positions {
            *v = Vec3::new(v.x * 0.9 + 0.05, 0.0, v.z * 0.9 - 0.03);
        }
        g
    };
    for m in [soup(300, 0.3, 17), grid(6), shifted] {
        let o = p.len() as u32;
        p.extend_from_slice(&m.positions);
        idx.extend(m.indices.iter().map(|t| t.map(|i| i + o)));
    }
    tripled(&mesh_from(p, idx), 5)
}

/// Random rays through the bounds and rays from above aimed at the grids, the latter in
/// runs of 16 neighbours (coherent packets).
fn tie_rays() -> Vec<Ray> {
    let mut rays = random_rays(3000, Vec3::splat(-1.2), Vec3::splat(1.2), 99);
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        let o = Vec3::new(
            rng.range(-0.5, 0.5),
            rng.range(0.5, 2.0),
            rng.range(-0.5, 0.5),
        );
        let c = Vec3::new(rng.range(-0.9, 0.9), 0.0, rng.range(-0.9, 0.9));
        for k in 0..16 {
            let d = Vec3::new((k % 4) as f32 * 0.01, 0.0, (k / 4) as f32 * 0.01);
            rays.push(Ray::new(o, c + d - o));
        }
    }
    rays
}

fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
}

/// Every closest-hit path of `bvh` returns `expected` for every ray, bit for bit.
fn check_paths(bvh: &Bvh, rays: &[Ray], expected: &[Option<Hit>], what: &str) {
    for (r, &e) in rays.iter().zip(expected) {
        assert_eq!(bits(bvh.closest_hit(r)), bits(e), "{what}: {r:?}");
        assert_eq!(
            bits(bvh.closest_hit8_portable(r)),
            bits(e),
            "{what}, portable: {r:?}"
        );
        assert_eq!(bits(bvh.closest_hit4(r)), bits(e), "{what}, 4-wide: {r:?}");
        assert_eq!(
            bits(bvh.closest_hit_scalar(r)),
            bits(e),
            "{what}, scalar: {r:?}"
        );
        assert_eq!(bvh.any_hit(r), e.is_some(), "{what}, any hit: {r:?}");
    }
    type Packets = fn(&Bvh, &[Ray], &mut [Option<Hit>]);
    let packets: [(&str, Packets); 5] = [
        ("packet", Bvh::closest_hit_packet),
        ("packet portable", Bvh::closest_hit_packet_portable),
        ("packet64", Bvh::closest_hit_packet64),
        ("packet64 portable", Bvh::closest_hit_packet64_portable),
        ("packet4", Bvh::closest_hit_packet4),
    ];
    let mut out = vec![None; rays.len()];
    for (name, f) in packets {
        f(bvh, rays, &mut out);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(bits(out[i]), bits(expected[i]), "{what}, {name}: {r:?}");
        }
    }
    for lanes in PacketLanes::supported() {
        bvh.closest_hit_packet_with(lanes, rays, &mut out);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(bits(out[i]), bits(expected[i]), "{what}, {lanes:?}: {r:?}");
        }
        bvh.closest_hit_packet64_with(lanes, rays, &mut out);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(
                bits(out[i]),
                bits(expected[i]),
                "{what}, 64 {lanes:?}: {r:?}"
            );
        }
    }
}

#[test]
fn exact_ties_go_to_the_lowest_primitive_in_every_tree_and_path() {
    let mesh = tie_mesh();
    let rays = tie_rays();
    let expected: Vec<Option<Hit>> = rays.iter().map(|r| brute_force_closest(&mesh, r)).collect();
    // The test is about ties: count the rays whose closest `t` is shared by two or more
    // primitives, and those where the lowest such primitive is not the first copy the
    // tripling put in the mesh's order (so "first index in the BVH's own order" would differ
    // from brute force in some tree).
    let (mut tied, mut coplanar) = (0, 0);
    let mut all = Vec::new();
    for (r, e) in rays.iter().zip(&expected) {
        let Some(e) = e else { continue };
        brute_force_all(&mesh, r, &mut all);
        let at_min: Vec<&Hit> = all.iter().filter(|h| h.t == e.t).collect();
        assert_eq!(at_min[0].prim, e.prim);
        tied += (at_min.len() >= 2) as usize;
        // Overlapping coplanar triangles of the two grids: more than one copy group.
        coplanar += (at_min.len() > 3) as usize;
    }
    assert!(tied > 2000, "{tied} tied rays");
    assert!(
        coplanar > 10,
        "{coplanar} rays at a tie of different triangles"
    );

    let builds = [
        (
            "object splits",
            BuildOptions {
                spatial_splits: false,
                ..Default::default()
            },
        ),
        ("default (spatial splits)", BuildOptions::default()),
        (
            "spatial splits, alpha 0, overlap 0, budget 4, one triangle per leaf",
            BuildOptions {
                spatial_splits: true,
                split_alpha: 0.0,
                split_overlap: 0.0,
                split_budget: 4.0,
                max_leaf_size: 1,
                ..Default::default()
            },
        ),
        (
            "object splits, one triangle per leaf",
            BuildOptions {
                spatial_splits: false,
                max_leaf_size: 1,
                ..Default::default()
            },
        ),
    ];
    for (what, opts) in &builds {
        let bvh = Bvh::build_with(&mesh, opts);
        if opts.spatial_splits {
            assert!(
                bvh.reference_count() > mesh.triangle_count(),
                "{what}: no split"
            );
        }
        check_paths(&bvh, &rays, &expected, what);
    }
}
