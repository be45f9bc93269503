use glam::Vec3;
use parallax_scene::TriangleMesh;

use crate::{EmbreeError, EmbreeScene, Options};

fn one_triangle() -> TriangleMesh {
    TriangleMesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, -2.0),
            Vec3::new(1.0, -1.0, -2.0),
            Vec3::new(0.0, 1.0, -2.0),
        ],
        indices: vec![[0, 1, 2]],
        material_ids: vec![0],
        ..Default::default()
    }
}

#[test]
fn bad_indices_are_rejected_with_or_without_embree() {
    let mut m = one_triangle();
    m.indices[0][2] = 3;
    assert!(matches!(
        EmbreeScene::new(&m, Options::default()),
        Err(EmbreeError::BadIndex { index: 3, .. })
    ));
}

#[cfg(not(feature = "embree"))]
#[test]
fn without_the_feature_the_constructor_says_how_to_enable_it() {
    let e = EmbreeScene::new(&one_triangle(), Options::default())
        .err()
        .unwrap();
    assert!(matches!(e, EmbreeError::NotEnabled));
    let msg = e.to_string();
    assert!(
        msg.contains("--features embree") && msg.contains("install-embree.sh"),
        "{msg}"
    );
}

#[cfg(feature = "embree")]
mod with_embree {
    use super::*;
    use crate::{EmbreeHit, Quality};
    use glam::Vec2;
    use parallax_bvh::Bvh;
    use parallax_core::Ray;
    use parallax_scene::camera::{CameraModel, Pinhole};

    fn closest(s: &EmbreeScene, r: Ray) -> Option<EmbreeHit> {
        let mut o = [None];
        s.closest_hits(&[r], &mut o);
        o[0]
    }

    #[test]
    fn single_triangle_hit_miss_and_segment() {
        let s = EmbreeScene::new(&one_triangle(), Options::default()).unwrap();
        let h = closest(&s, Ray::new(Vec3::ZERO, -Vec3::Z)).expect("hit");
        assert_eq!(h.prim, 0);
        assert!((h.t - 2.0).abs() < 1e-6, "t = {}", h.t);
        // t in units of the (non-unit) direction.
        let h = closest(&s, Ray::new(Vec3::ZERO, -2.0 * Vec3::Z)).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6, "t = {}", h.t);
        assert_eq!(closest(&s, Ray::new(Vec3::ZERO, Vec3::Z)), None);
        let short = Ray::segment(Vec3::ZERO, -Vec3::Z, 0.0, 1.5);
        assert_eq!(closest(&s, short), None);
        let mut occ = [true, false];
        s.occluded(&[short, Ray::new(Vec3::ZERO, -Vec3::Z)], &mut occ);
        assert_eq!(occ, [false, true]);
        // An empty mesh builds and misses.
        let empty = EmbreeScene::new(&TriangleMesh::default(), Options::default()).unwrap();
        assert_eq!(closest(&empty, Ray::new(Vec3::ZERO, Vec3::X)), None);
    }

    /// Camera rays of the built-in atrium (4x4 tiles, tile order).
    fn atrium_rays() -> (parallax_scene::Scene, Vec<Ray>) {
        let scene = parallax_scene::builtin::by_name("atrium").unwrap();
        let cam = Pinhole::new(&scene.camera(None).unwrap(), 64, 48).unwrap();
        let mut rays = Vec::new();
        for ty in (0..48).step_by(4) {
            for tx in (0..64).step_by(4) {
                for y in ty..ty + 4 {
                    for x in tx..tx + 4 {
                        let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                        rays.push(cam.generate_ray(film, Vec2::splat(0.5), 0).unwrap().ray);
                    }
                }
            }
        }
        (scene, rays)
    }

    #[test]
    fn packets_and_streams_equal_single_rays_and_agree_with_the_bvh() {
        let (scene, rays) = atrium_rays();
        let bvh = Bvh::build(&scene.mesh);
        for quality in [Quality::Low, Quality::Medium, Quality::High] {
            let s = EmbreeScene::new(
                &scene.mesh,
                Options {
                    quality,
                    robust: false,
                },
            )
            .unwrap();
            let mut single = vec![None; rays.len()];
            s.closest_hits(&rays, &mut single);
            // A partial last packet too (the slice is not a multiple of the width).
            let n = rays.len() - 5;
            for width in [8, 16] {
                let mut p = vec![None; n];
                s.closest_hit_packets(&rays[..n], width, &mut p);
                assert_eq!(p, single[..n], "{quality:?}, packets of {width}");
            }
            for coherent in [false, true] {
                let mut st = vec![None; n];
                s.closest_hit_stream(&rays[..n], coherent, &mut st);
                assert_eq!(st, single[..n], "{quality:?}, stream, coherent {coherent}");
            }
            let hits = single.iter().filter(|h| h.is_some()).count();
            let same = rays
                .iter()
                .zip(&single)
                .filter(|(r, e)| bvh.closest_hit(r).map(|h| h.prim) == e.map(|e| e.prim))
                .count();
            assert!(hits > rays.len() / 2, "{hits} of {} rays hit", rays.len());
            // Embree's (non-watertight) test may pick the other triangle at a shared edge.
            assert!(
                same as f64 >= 0.999 * rays.len() as f64,
                "{same} of {}",
                rays.len()
            );
        }
    }
}
