//! Watertightness through the BVH: rays aimed exactly at shared vertices and edges of closed
//! meshes never slip through, and are never counted twice.

mod common;

use common::*;
use glam::Vec3;
use parallax_bvh::{BuildOptions, Bvh};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

/// Vertices and edge midpoints of a mesh: the points rays are aimed at.
fn targets(mesh: &TriangleMesh) -> Vec<Vec3> {
    let mut t = mesh.positions.clone();
    for tri in &mesh.indices {
        for k in 0..3 {
            let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            if a < b {
                t.push((mesh.positions[a] + mesh.positions[b]) * 0.5);
            }
        }
    }
    t
}

/// The BVH with the object-split build (`spatial_splits: false`), the default build (SBVH)
/// and with spatial splits forced everywhere (alpha 0, large budget, one triangle per leaf:
/// most triangles are cut into pieces).
fn builds(mesh: &TriangleMesh) -> [Bvh; 3] {
    let object = BuildOptions {
        spatial_splits: false,
        ..Default::default()
    };
    let spatial = BuildOptions {
        spatial_splits: true,
        split_alpha: 0.0,
        split_overlap: 0.0,
        split_budget: 4.0,
        max_leaf_size: 1,
        ..Default::default()
    };
    [
        Bvh::build_with(mesh, &object),
        Bvh::build(mesh),
        Bvh::build_with(mesh, &spatial),
    ]
}

fn closed_convex_meshes() -> Vec<(&'static str, TriangleMesh)> {
    vec![
        ("cube", cube()),
        ("icosphere 0", icosphere(0)),
        ("icosphere 3", icosphere(3)),
        ("uv sphere", uv_sphere(12, 20)),
    ]
}

/// From outside, along a line through the target and an interior point: the line crosses the
/// convex surface twice, so closest hit exists and all-hits counts exactly 2.
#[test]
fn rays_from_outside_through_vertices_and_edges_hit_twice() {
    let mut rng = Rng::new(21);
    let mut hits = Vec::new();
    for (name, mesh) in closed_convex_meshes() {
        for bvh in &builds(&mesh) {
            for p in targets(&mesh) {
                for _ in 0..3 {
                    let inner = rng.vec3_in(Vec3::splat(-0.4), Vec3::splat(0.4));
                    let o = p + (p - inner).normalize() * rng.range(0.5, 3.0);
                    let r = Ray::new(o, p - o);
                    let h = check_closest(bvh, &mesh, &r, name);
                    assert!(h.is_some(), "{name}: slipped through at {p}");
                    let n = check_all(bvh, &mesh, &r, name);
                    bvh.all_hits(&r, &mut hits);
                    assert_eq!(n, 2, "{name}: {n} hits aiming at {p}: {hits:?}");
                }
            }
        }
    }
}

/// From outside in any direction: all-hits counts are even (0 or 2 for a convex mesh).
#[test]
fn random_rays_from_outside_hit_an_even_number_of_times() {
    for (name, mesh) in closed_convex_meshes() {
        for bvh in &builds(&mesh) {
            let mut rng = Rng::new(5);
            let mut out = Vec::new();
            let mut crossing = 0;
            for _ in 0..2000 {
                let o = rng.dir() * rng.range(1.8, 4.0);
                let r = Ray::new(
                    o,
                    (rng.vec3_in(Vec3::splat(-1.2), Vec3::splat(1.2)) - o).normalize(),
                );
                bvh.all_hits(&r, &mut out);
                assert!(
                    out.is_empty() || out.len() == 2,
                    "{name}: {} hits",
                    out.len()
                );
                crossing += (out.len() == 2) as usize;
            }
            assert!(crossing > 500, "{name}: {crossing}");
        }
    }
}

/// Axis-parallel and diagonal rays pass exactly (bit-exactly, in the sheared frame) through the
/// cube's vertices and edges: counts stay even, and exactly 2 through the interior.
#[test]
fn exact_axis_and_diagonal_rays_through_cube_edges_and_corners() {
    let mesh = cube();
    for bvh in &builds(&mesh) {
        let c = [-1.0f32, -0.5, 0.0, 0.5, 1.0];
        for axis in 0..3 {
            for &a in &c {
                for &b in &c {
                    for sign in [1.0f32, -1.0] {
                        let mut o = Vec3::ZERO;
                        o[axis] = -4.0 * sign;
                        o[(axis + 1) % 3] = a;
                        o[(axis + 2) % 3] = b;
                        let mut d = Vec3::ZERO;
                        d[axis] = sign;
                        let r = Ray::new(o, d);
                        let n = check_all(bvh, &mesh, &r, "cube axis");
                        assert!(n.is_multiple_of(2), "{n} hits for {r:?}");
                        if a.abs() < 1.0 && b.abs() < 1.0 {
                            assert_eq!(n, 2, "{r:?}");
                            assert!(check_closest(bvh, &mesh, &r, "cube axis").is_some());
                        }
                    }
                }
            }
        }
        // Diagonals through the corners (the ray (t, t, t) meets corner (1, 1, 1) exactly).
        for sx in [-1.0f32, 1.0] {
            for sy in [-1.0f32, 1.0] {
                for sz in [-1.0f32, 1.0] {
                    let d = Vec3::new(sx, sy, sz);
                    let r = Ray::new(-3.0 * d, d);
                    assert_eq!(check_all(bvh, &mesh, &r, "cube diagonal"), 2, "{r:?}");
                }
            }
        }
    }
}

/// From inside a closed convex mesh every ray hits exactly once, also through vertices and
/// edge midpoints.
#[test]
fn rays_from_inside_hit_exactly_once() {
    let mut rng = Rng::new(77);
    for (name, mesh) in closed_convex_meshes() {
        for bvh in &builds(&mesh) {
            let mut out = Vec::new();
            let mut rays: Vec<Ray> = targets(&mesh)
                .into_iter()
                .map(|p| Ray::new(Vec3::ZERO, p))
                .collect();
            for _ in 0..1000 {
                // Inside the icosahedron's inscribed sphere (radius 0.79).
                rays.push(Ray::new(
                    rng.vec3_in(Vec3::splat(-0.4), Vec3::splat(0.4)),
                    rng.dir(),
                ));
            }
            // Exactly axis-aligned and diagonal directions from the centre.
            for d in [
                Vec3::X,
                -Vec3::Y,
                Vec3::Z,
                Vec3::ONE,
                Vec3::new(1.0, -1.0, 0.0),
            ] {
                rays.push(Ray::new(Vec3::ZERO, d));
            }
            for r in &rays {
                assert!(
                    check_closest(bvh, &mesh, r, name).is_some(),
                    "{name}: escaped {r:?}"
                );
                bvh.all_hits(r, &mut out);
                assert_eq!(out.len(), 1, "{name}: {out:?} for {r:?}");
            }
        }
    }
}

/// A fine grid (many shared edges and vertices in one plane): rays through every vertex and
/// edge midpoint hit exactly one triangle.
#[test]
fn grid_vertices_and_edges_are_hit_exactly_once() {
    let mesh = grid(16);
    for bvh in &builds(&mesh) {
        let mut out = Vec::new();
        for p in targets(&mesh) {
            if p.x.abs() >= 1.0 || p.z.abs() >= 1.0 {
                continue; // the open boundary may belong to no triangle
            }
            for d in [
                -Vec3::Y,
                Vec3::new(0.3, -1.0, 0.2),
                Vec3::new(-0.1, 1.0, 0.4),
            ] {
                let r = Ray::new(p - d * 2.0, d);
                bvh.all_hits(&r, &mut out);
                assert_eq!(out.len(), 1, "{p} {d}: {out:?}");
                check_closest(bvh, &mesh, &r, "grid");
            }
        }
    }
}
