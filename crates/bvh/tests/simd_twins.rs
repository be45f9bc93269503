//! Every fast path against its slow twin, bit for bit: the 8-wide traversal with the AVX2 node
//! test ([`Bvh::closest_hit`], [`Bvh::any_hit`], [`Bvh::all_hits`]) against its portable
//! node test ([`Bvh::closest_hit8_portable`], [`Bvh::any_hit8_portable`]) and the 4-wide tree
//! ([`Bvh::closest_hit4`], ...), and the 4-wide SIMD leaf test against the scalar
//! per-triangle test ([`Bvh::closest_hit_scalar`], [`Bvh::any_hit_scalar`]), on rays that hit interiors and on
//! rays aimed exactly at shared vertices and edges (where the SIMD lanes fall back to the
//! scalar double-precision test and its tie-break), with leaves of 1, 4 and 15 triangles; and
//! the packet traversals ([`Bvh::closest_hit_packet_with`], [`Bvh::closest_hit_packet64_with`])
//! on every lane type the CPU supports (AVX2, AVX-512, portable) against single rays.

mod common;

use common::*;
use glam::{Vec2, Vec3};
use parallax_bvh::{BuildOptions, Bvh, PacketLanes};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;
use parallax_scene::camera::{CameraModel, Pinhole};

/// Rays aimed at every vertex and edge midpoint from random points around the mesh, plus
/// random rays through the bounds.
fn rays_for(mesh: &TriangleMesh, seed: u64, cap: usize) -> Vec<Ray> {
    let b = mesh.bounds();
    let pad = b.extent() + Vec3::ONE;
    let (lo, hi) = (b.min - pad, b.max + pad);
    let mut rng = Rng::new(seed);
    let mut rays = random_rays(cap, lo, hi, seed);
    let step = (mesh.indices.len() / cap).max(1);
    for tri in mesh.indices.iter().step_by(step) {
        for k in 0..3 {
            let p = mesh.positions[tri[k] as usize];
            let q = mesh.positions[tri[(k + 1) % 3] as usize];
            for target in [p, (p + q) * 0.5] {
                let o = rng.vec3_in(lo, hi);
                rays.push(Ray::new(o, target - o));
            }
        }
    }
    rays
}

/// Asserts the twins agree on every ray; returns how many rays hit.
fn check_twins(bvh: &Bvh, rays: &[Ray], what: &str) -> usize {
    let mut hits = 0;
    let bits = |h: Option<parallax_bvh::Hit>| {
        // Bit-identical t, u, v (PartialEq on f32 would accept -0.0 == 0.0).
        h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
    };
    let (mut all8, mut all4) = (Vec::new(), Vec::new());
    for r in rays {
        let fast = bvh.closest_hit(r);
        let slow = bvh.closest_hit_scalar(r);
        assert_eq!(
            bits(fast),
            bits(slow),
            "{what}: closest hit differs for {r:?}"
        );
        assert_eq!(
            bits(fast),
            bits(bvh.closest_hit4(r)),
            "{what}: 4-wide, {r:?}"
        );
        assert_eq!(
            bits(fast),
            bits(bvh.closest_hit8_portable(r)),
            "{what}: portable, {r:?}"
        );
        assert_eq!(
            bvh.any_hit(r),
            bvh.any_hit4(r),
            "{what}: any hit 4-wide, {r:?}"
        );
        assert_eq!(
            bvh.any_hit(r),
            bvh.any_hit8_portable(r),
            "{what}: any hit, {r:?}"
        );
        bvh.all_hits(r, &mut all8);
        bvh.all_hits4(r, &mut all4);
        assert_eq!(all8, all4, "{what}: all hits, {r:?}");
        assert_eq!(
            bvh.any_hit(r),
            bvh.any_hit_scalar(r),
            "{what}: any hit, {r:?}"
        );
        assert_eq!(
            bvh.any_hit(r),
            fast.is_some(),
            "{what}: any vs closest, {r:?}"
        );
        hits += fast.is_some() as usize;
    }
    check_packet_twins(bvh, rays, what);
    hits
}

/// The packet traversals (16 and 64 rays per packet, consecutive rays) on every lane type the
/// CPU supports against the portable lanes and against single rays, bit for bit.
fn check_packet_twins(bvh: &Bvh, rays: &[Ray], what: &str) {
    let bits = |h: Option<parallax_bvh::Hit>| {
        h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
    };
    let single: Vec<_> = rays.iter().map(|r| bits(bvh.closest_hit(r))).collect();
    for lanes in PacketLanes::supported() {
        let mut out = vec![None; rays.len()];
        bvh.closest_hit_packet_with(lanes, rays, &mut out);
        let mut out64 = vec![None; rays.len()];
        bvh.closest_hit_packet64_with(lanes, rays, &mut out64);
        for (i, r) in rays.iter().enumerate() {
            assert_eq!(bits(out[i]), single[i], "{what}: {lanes:?} packet, {r:?}");
            assert_eq!(
                bits(out64[i]),
                single[i],
                "{what}: {lanes:?} packet64, {r:?}"
            );
        }
    }
}

fn meshes() -> Vec<(&'static str, TriangleMesh)> {
    vec![
        ("cube", cube()),
        ("icosphere 3", icosphere(3)),
        ("uv sphere", uv_sphere(12, 20)),
        ("grid", grid(16)),
        ("lattice", cube_lattice(4)),
        ("soup", soup(2000, 0.1, 5)),
    ]
}

#[test]
fn simd_leaf_test_equals_scalar_twin_on_procedural_meshes() {
    for leaf in [1, 4, 15] {
        let opts = BuildOptions {
            max_leaf_size: leaf,
            ..Default::default()
        };
        for (name, mesh) in meshes() {
            let bvh = Bvh::build_with(&mesh, &opts);
            let rays = rays_for(&mesh, 3 + leaf as u64, 600);
            let hits = check_twins(&bvh, &rays, name);
            assert!(
                hits * 10 > rays.len(),
                "{name}, leaf {leaf}: {hits}/{}",
                rays.len()
            );
        }
    }
}

/// Axis-parallel rays through the grid's vertices: every edge function of many triangles is
/// exactly zero, so the exact lanes decide.
#[test]
fn exact_lanes_on_grid_vertices() {
    let mesh = grid(8);
    let bvh = Bvh::build(&mesh);
    let mut rays = Vec::new();
    // Direction by direction: consecutive rays share it, so packets of them take the interval
    // test and the 16-lane triangle test, whose exactly-zero lanes go to the scalar test.
    for d in [
        -Vec3::Y,
        Vec3::new(0.25, -1.0, 0.5),
        Vec3::new(-0.5, -1.0, 0.0),
    ] {
        for p in &mesh.positions {
            rays.push(Ray::new(*p - d * 2.0, d));
        }
    }
    let hits = check_twins(&bvh, &rays, "grid vertices");
    // Every vertex strictly inside the grid is owned by exactly one triangle of its fan.
    assert!(hits >= 7 * 7 * 3, "{hits}");
}

#[test]
fn simd_leaf_test_equals_scalar_twin_on_builtin_scenes() {
    for name in parallax_scene::builtin::NAMES.iter() {
        let scene = parallax_scene::builtin::by_name(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let mut rays = rays_for(&scene.mesh, 9, 400);
        let cam = Pinhole::new(&scene.camera(None).unwrap(), 32, 24).unwrap();
        for y in 0..24 {
            for x in 0..32 {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if let Some(cr) = cam.generate_ray(film, Vec2::splat(0.5), 0) {
                    rays.push(cr.ray);
                }
            }
        }
        let hits = check_twins(&bvh, &rays, name);
        assert!(hits > 0, "{name}");
    }
}
