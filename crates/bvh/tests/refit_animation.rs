//! HVVR §5.2 on the built-in scenes: after the scene's rigid animation moves its props, the
//! refitted BVH answers every closest-hit query like a fresh build of the animated mesh.

mod common;

use common::*;
use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_scene::animation::RigidAnimation;
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind};
use parallax_scene::{Scene, TriangleMesh};

/// Camera rays through a 48x36 grid plus random rays inside the scene bounds.
fn rays(scene: &Scene, mesh: &TriangleMesh, seed: u64) -> Vec<Ray> {
    let desc = scene.camera(None).unwrap();
    let cam = Camera::new(ModelKind::Pinhole, &desc, 48, 36, &CameraOptions::default()).unwrap();
    let mut out: Vec<Ray> = (0..36)
        .flat_map(|y| (0..48).map(move |x| Vec2::new(x as f32 + 0.5, y as f32 + 0.5)))
        .filter_map(|f| cam.generate_ray(f, Vec2::splat(0.5), 0).map(|r| r.ray))
        .collect();
    let b = mesh.bounds();
    out.extend(random_rays(1500, b.min, b.max, seed));
    out
}

/// Same triangle, or (a tie or a shared edge) the same t within 1e-5 relative to max(t, 1).
fn same_hits(refitted: &Bvh, mesh: &TriangleMesh, rays: &[Ray], what: &str) -> usize {
    let fresh = Bvh::build(mesh);
    assert_eq!(refitted.bounds(), fresh.bounds(), "{what}: root bounds");
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let a = refitted.closest_hit(r);
        let b = fresh.closest_hit(r);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                // Relative to max(t, 1 m): props resting on the floor make near-coplanar
                // surfaces that rays starting a few mm away hit 4e-8 m apart (measured).
                let close = (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(b.t.abs()).max(1.0);
                assert!(
                    a.prim == b.prim || close,
                    "{what}: ray {i}: refit {a:?} vs fresh {b:?}"
                );
                hits += 1;
            }
            _ => panic!("{what}: ray {i}: refit {a:?} vs fresh {b:?}"),
        }
    }
    hits
}

fn animate_and_compare(name: &str) {
    let scene = Scene::load(name).unwrap();
    let anim = RigidAnimation::for_scene(&scene);
    assert!(!anim.tracks.is_empty(), "{name}: nothing moves");
    let mut mesh = scene.mesh.clone();
    let mut bvh = Bvh::build(&mesh);
    for (k, t) in [0.4f32, 1.7, 3.1].into_iter().enumerate() {
        anim.apply(&mut mesh, t).unwrap();
        let moved = mesh
            .positions
            .iter()
            .zip(&scene.mesh.positions)
            .filter(|(a, b)| (**a - **b).length() > 1e-4)
            .count();
        assert!(moved > 100, "{name} t={t}: only {moved} vertices moved");
        bvh.refit(&mesh).unwrap();
        let rays = rays(&scene, &mesh, k as u64);
        let hits = same_hits(&bvh, &mesh, &rays, &format!("{name} t={t}"));
        assert!(
            hits > rays.len() / 4,
            "{name}: {hits} hits of {}",
            rays.len()
        );
    }
    // Back at t = 0 the refitted BVH answers like the rest pose's build.
    anim.apply(&mut mesh, 0.0).unwrap();
    bvh.refit(&mesh).unwrap();
    let rays = rays(&scene, &mesh, 9);
    same_hits(&bvh, &mesh, &rays, &format!("{name} t=0"));
}

#[test]
fn cornell_props_refit_like_a_fresh_build() {
    animate_and_compare("cornell");
}

#[test]
fn atrium_props_refit_like_a_fresh_build() {
    animate_and_compare("atrium");
}
