//! Refit: after vertices move, the refitted BVH answers exactly like a fresh build and like
//! brute force.

mod common;

use common::*;
use glam::{Mat3, Vec3};
use parallax_bvh::{BuildOptions, Bvh, BvhError};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

/// Three objects: an icosphere, a grid and a random soup.
fn scene() -> TriangleMesh {
    let mut m = icosphere(3);
    let mut g = grid(20);
    for p in &mut g.positions {
        *p = *p * 2.0 - Vec3::Y;
    }
    m.append(&g, 0);
    let mut s = soup(500, 0.1, 3);
    for p in &mut s.positions {
        *p += Vec3::new(2.5, 0.0, 0.0);
    }
    m.append(&s, 0);
    m
}

fn compare(refitted: &Bvh, mesh: &TriangleMesh, rays: &[Ray], what: &str) {
    let fresh = Bvh::build(mesh);
    assert_eq!(refitted.bounds(), fresh.bounds(), "{what}: bounds");
    let mut hits = 0;
    for r in rays {
        let a = check_closest(refitted, mesh, r, what);
        let b = fresh.closest_hit(r);
        assert_eq!(
            a.map(|h| h.t),
            b.map(|h| h.t),
            "{what}: refit vs fresh build"
        );
        hits += a.is_some() as usize;
    }
    assert!(hits > rays.len() / 5, "{what}: {hits} hits");
    for r in rays.iter().step_by(10) {
        check_all(refitted, mesh, r, what);
    }
}

/// The default build (SBVH) and the object-split build (`spatial_splits: false`).
fn builds() -> [(&'static str, BuildOptions); 2] {
    [
        ("default", BuildOptions::default()),
        (
            "object splits",
            BuildOptions {
                spatial_splits: false,
                ..Default::default()
            },
        ),
    ]
}

#[test]
fn rigid_motion_of_one_object() {
    for (what, opts) in builds() {
        let mut mesh = scene();
        let mut bvh = Bvh::build_with(&mesh, &opts);
        let obj = mesh.objects[0].clone();
        let rot = Mat3::from_rotation_y(0.7) * Mat3::from_rotation_x(-0.4);
        let range = obj.first_vertex as usize..(obj.first_vertex + obj.vertex_count) as usize;
        for p in &mut mesh.positions[range] {
            *p = rot * *p + Vec3::new(1.5, 0.8, -0.5);
        }
        let t = bvh.refit(&mesh).unwrap();
        assert!(t.as_secs_f64() < 1.0);
        let rays = random_rays(
            1500,
            Vec3::new(-2.0, -1.5, -2.0),
            Vec3::new(3.5, 2.0, 2.0),
            4,
        );
        compare(&bvh, &mesh, &rays, &format!("rigid, {what}"));
    }
}

/// A BVH built with spatial splits (duplicated triangles, clipped leaf boxes) refits to the
/// moved triangles' whole boxes and still answers like brute force.
#[test]
fn rigid_motion_with_spatial_splits() {
    let mut mesh = scene();
    // Long overlapping triangles, which spatial splits cut.
    mesh.append(&soup(600, 0.6, 11), 0);
    let opts = BuildOptions {
        spatial_splits: true,
        split_alpha: 0.0,
        split_overlap: 0.0,
        split_budget: 1.0,
        ..Default::default()
    };
    let mut bvh = Bvh::build_with(&mesh, &opts);
    assert!(bvh.reference_count() > bvh.triangle_count());
    let obj = mesh.objects[1].clone();
    let rot = Mat3::from_rotation_z(0.5);
    let range = obj.first_vertex as usize..(obj.first_vertex + obj.vertex_count) as usize;
    for p in &mut mesh.positions[range] {
        *p = rot * *p + Vec3::new(0.3, 0.5, 0.2);
    }
    bvh.refit(&mesh).unwrap();
    let rays = random_rays(
        1500,
        Vec3::new(-2.0, -1.5, -2.0),
        Vec3::new(3.5, 2.0, 2.0),
        9,
    );
    compare(&bvh, &mesh, &rays, "rigid, spatial splits");
}

#[test]
fn random_jitter_of_every_vertex() {
    for (what, opts) in builds() {
        let mut mesh = scene();
        let mut bvh = Bvh::build_with(&mesh, &opts);
        let mut rng = Rng::new(9);
        for round in 0..3 {
            for p in &mut mesh.positions {
                *p += rng.vec3_in(Vec3::splat(-0.05), Vec3::splat(0.05));
            }
            bvh.refit(&mesh).unwrap();
            let rays = random_rays(800, Vec3::splat(-2.0), Vec3::new(3.5, 2.0, 2.0), round);
            compare(&bvh, &mesh, &rays, &format!("jitter, {what}"));
        }
    }
}

#[test]
fn refit_rejects_a_different_topology() {
    let mesh = scene();
    let mut bvh = Bvh::build(&mesh);
    let smaller = icosphere(1);
    assert!(matches!(
        bvh.refit(&smaller),
        Err(BvhError::TopologyChanged { .. })
    ));
    let mut broken = mesh.clone();
    broken.positions.truncate(3);
    assert!(matches!(
        bvh.refit(&broken),
        Err(BvhError::IndexOutOfRange { .. })
    ));
    // The empty BVH refits to the empty mesh.
    let mut empty = Bvh::build(&TriangleMesh::default());
    assert!(empty.refit(&TriangleMesh::default()).is_ok());
}
