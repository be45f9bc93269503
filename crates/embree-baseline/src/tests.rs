use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

use crate::procedural::{random_triangles, uv_sphere};
use crate::{EmbreeError, EmbreeScene, hits_agree};

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
fn single_triangle_hit_miss_and_segment() {
    let s = EmbreeScene::new(&one_triangle()).unwrap();
    let (prim, t) = s.closest_hit(&Ray::new(Vec3::ZERO, -Vec3::Z)).expect("hit");
    assert_eq!(prim, 0);
    assert!((t - 2.0).abs() < 1e-6, "t = {t}");
    // Non-unit direction: t in units of dir.
    let (_, t) = s
        .closest_hit(&Ray::new(Vec3::ZERO, -2.0 * Vec3::Z))
        .unwrap();
    assert!((t - 1.0).abs() < 1e-6, "t = {t}");
    assert_eq!(s.closest_hit(&Ray::new(Vec3::ZERO, Vec3::Z)), None);
    assert_eq!(
        s.closest_hit(&Ray::new(Vec3::new(3.0, 0.0, 0.0), -Vec3::Z)),
        None
    );
    let short = Ray::segment(Vec3::ZERO, -Vec3::Z, 0.0, 1.5);
    assert_eq!(s.closest_hit(&short), None);
    assert!(!s.occluded(&short));
    assert!(s.occluded(&Ray::new(Vec3::ZERO, -Vec3::Z)));
}

#[test]
fn packets_equal_single_rays() {
    let s = EmbreeScene::new(&uv_sphere(1.0, 16, 32)).unwrap();
    // 16 rays from (0,0,3) fanning across the sphere's silhouette: some hit, some miss.
    let rays: Vec<Ray> = (0..16)
        .map(|i| {
            let x = -0.6 + 1.2 * i as f32 / 15.0;
            Ray::new(
                Vec3::new(0.0, 0.0, 3.0),
                Vec3::new(x, 0.1, -1.0).normalize(),
            )
        })
        .collect();
    let single: Vec<_> = rays.iter().map(|r| s.closest_hit(r)).collect();
    let hits = single.iter().filter(|h| h.is_some()).count();
    assert!((4..16).contains(&hits), "{hits} of 16 hit: want a mix");
    let p = s.closest_hit_packet(&rays);
    let mut p8 = [None; 16];
    s.closest_hit_packet8(&rays[..8], &mut p8[..8]);
    s.closest_hit_packet8(&rays[8..], &mut p8[8..]);
    let mut p16 = [None; 16];
    s.closest_hit_packet16(&rays, &mut p16);
    for i in 0..16 {
        assert_eq!(p[i], single[i], "lane {i}");
        assert_eq!(p8[i], single[i], "lane {i} (8-wide)");
        assert_eq!(p16[i], single[i], "lane {i} (16-wide)");
    }
    // A partial packet leaves the other lanes empty.
    let part = s.closest_hit_packet(&rays[..5]);
    assert_eq!(&part[..5], &single[..5]);
    assert!(part[5..].iter().all(Option::is_none));
}

#[test]
fn rejects_out_of_range_indices() {
    let mut m = one_triangle();
    m.indices[0][2] = 3;
    assert!(matches!(
        EmbreeScene::new(&m),
        Err(EmbreeError::BadIndex { index: 3, .. })
    ));
    assert!(
        EmbreeScene::new(&TriangleMesh::default())
            .unwrap()
            .closest_hit(&Ray::new(Vec3::ZERO, Vec3::X))
            .is_none()
    );
}

#[test]
fn agrees_with_parallax_bvh_on_random_triangles() {
    let mesh = random_triangles(3000, 0.08, 5);
    let emb = EmbreeScene::new(&mesh).unwrap();
    let bvh = Bvh::build(&mesh);
    let mut agree = 0;
    let mut hits = 0;
    let n = 4000;
    for i in 0..n {
        let a = (i as f32 * 0.618_034).fract() * std::f32::consts::TAU;
        let b = (i as f32 * 0.414_213).fract() * 2.0 - 1.0;
        let origin = Vec3::new(a.cos() * 3.0, b * 1.5, a.sin() * 3.0);
        let target = Vec3::new(
            (i as f32 * 0.3).sin(),
            (i as f32 * 0.7).cos(),
            (i as f32 * 1.3).sin(),
        ) * 0.9;
        let ray = Ray::new(origin, (target - origin).normalize());
        let e = emb.closest_hit(&ray);
        let p = bvh.closest_hit(&ray).map(|h| (h.prim, h.t));
        hits += usize::from(p.is_some());
        agree += usize::from(hits_agree(e, p, 1e-4));
    }
    assert!(
        hits > n / 2,
        "only {hits} of {n} rays hit: the test mesh is too sparse"
    );
    assert!(agree as f64 >= 0.999 * n as f64, "agreement {agree} of {n}");
}
