//! DIRT's tracer (Vardis et al. 2017, §4.2, Algorithm 1) against the BVH: the same closest
//! triangle with bit-identical `t` and barycentrics, and the same occlusion answer, on random
//! triangle soups with random views and options (proptest) and on the atrium, Sponza and the
//! classroom for primary, visibility, specular, glossy and diffuse rays; plus the defined
//! answers of rays that leave every view and of bad options.

use glam::{Mat3, Vec2, Vec3};
use parallax_bvh::Bvh;
use parallax_core::math::Frame;
use parallax_core::sampling::{Rng, warp};
use parallax_core::{Ray, WorldHit, WorldStats, WorldTracer};
use parallax_raster::dirt::{DirtError, DirtOptions, DirtViews, DirtViewsOptions};
use parallax_scene::camera::{CameraFrame, CameraModel, Pinhole};
use parallax_scene::{CameraDesc, Scene, TriangleMesh};
use parallax_screen::{DirtCounters, DirtTracer};
use proptest::prelude::*;

/// How DIRT's answers compare with the BVH's over a set of rays.
#[derive(Debug, Default)]
struct Agreement {
    rays: u64,
    /// Same triangle (or both miss), same `t` and barycentrics bit for bit.
    same: u64,
    /// Different triangles at exactly the same `t` (coplanar overlaps).
    ties: u64,
    /// Anything else (listed).
    differ: Vec<String>,
    /// Rays whose occlusion answer differs.
    occlusion_differ: u64,
    truncated: u64,
    /// Rays left out: their closest BVH hit is nearer to the eye than the capture's near plane.
    near_eye: u64,
}

impl Agreement {
    fn same_fraction(&self) -> f64 {
        self.same as f64 / self.rays.max(1) as f64
    }
}

fn compare(bvh: &Bvh, dirt: &DirtTracer, rays: &[Ray]) -> Agreement {
    let mut a = Agreement::default();
    let mut stats = WorldStats::default();
    let views = dirt.views();
    let (eye, near) = (views.cube.cube.eye, views.options.capture.near);
    for ray in rays {
        let want = bvh.closest_hit(ray);
        // Surfaces closer to the cube's centre than the near plane (in every face's depth,
        // the max-norm) are captured by no view, by design: such rays are not compared.
        if want.is_some_and(|h| (ray.at(h.t) - eye).abs().max_element() < near * 1.01) {
            a.near_eye += 1;
            continue;
        }
        a.rays += 1;
        let got = dirt.closest_hit(ray, &mut stats);
        match (want, got) {
            (None, None) => a.same += 1,
            (Some(w), Some(g)) if w.prim == g.prim => {
                if w.t == g.t && w.u == g.barycentrics.x && w.v == g.barycentrics.y {
                    a.same += 1;
                } else {
                    a.differ.push(format!("{ray:?}: same prim, {w:?} vs {g:?}"));
                }
            }
            (Some(w), Some(g)) if w.t == g.t => a.ties += 1,
            (w, g) => a.differ.push(format!("{ray:?}: bvh {w:?} dirt {g:?}")),
        }
        if bvh.any_hit(ray) != dirt.occluded(ray, &mut stats) {
            a.occlusion_differ += 1;
        }
    }
    a.truncated = stats.truncated;
    a
}

/// The tracer's instruction-set copies (`DirtTracer::copies`: the portable twin and every copy
/// the CPU runs) give bit-identical answers and identical counters on every ray, closest hit
/// and occlusion.
fn twins_agree(dirt: &DirtTracer, rays: &[Ray]) {
    let copies = dirt.copies();
    let key = |h: Option<WorldHit>| {
        h.map(|h| {
            (
                h.prim,
                h.t.to_bits(),
                h.barycentrics.x.to_bits(),
                h.barycentrics.y.to_bits(),
            )
        })
    };
    let base = &copies[0].1;
    for (name, copy) in &copies[1..] {
        for ray in rays {
            let (mut ca, mut cb) = (DirtCounters::default(), DirtCounters::default());
            let a = key(copy.closest_hit_counted(ray, &mut ca));
            let b = key(base.closest_hit_counted(ray, &mut cb));
            assert_eq!(a, b, "{name} {ray:?}");
            assert_eq!(
                copy.occluded_counted(ray, &mut ca),
                base.occluded_counted(ray, &mut cb),
                "{name} {ray:?}"
            );
            assert_eq!(ca, cb, "{name} {ray:?}");
        }
    }
}

fn soup(tris: &[[[f32; 3]; 3]]) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    for t in tris {
        let base = m.positions.len() as u32;
        m.positions.extend(t.iter().map(|&p| Vec3::from(p)));
        m.normals.extend([Vec3::ZERO; 3]);
        m.uvs.extend([Vec2::ZERO; 3]);
        m.indices.push([base, base + 1, base + 2]);
        m.material_ids.push(0);
    }
    m
}

fn views_opts(face: u32, tile: u32, buckets: u32) -> DirtViewsOptions {
    DirtViewsOptions {
        face_size: face,
        capture: DirtOptions {
            tile_size: tile,
            buckets,
            ..DirtOptions::default()
        },
        camera_tile_size: None,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    /// Random soups, a random camera (or none), random options and random rays from anywhere
    /// (inside and outside the soup, through the eye's neighbourhood, with random `t` ranges).
    #[test]
    fn equals_the_bvh_on_random_soups(
        tris in prop::collection::vec(
            prop::array::uniform3(prop::array::uniform3(-4.0f32..4.0)), 1..30),
        eye in prop::array::uniform3(-3.0f32..3.0),
        yaw in -3.2f32..3.2, pitch in -1.0f32..1.0,
        with_camera in any::<bool>(),
        tile_pow in 0u32..3, buckets in 1u32..12, face in 3u32..24,
        seed in any::<u64>(),
    ) {
        let mesh = soup(&tris);
        let bvh = Bvh::build(&mesh);
        let camera = Pinhole::from_frame(
            CameraFrame {
                position: Vec3::from(eye),
                basis: Mat3::from_rotation_y(yaw) * Mat3::from_rotation_x(pitch),
            },
            20,
            12,
            0.6,
        );
        let views = DirtViews::build(
            &mesh,
            with_camera.then_some(&camera),
            Vec3::from(eye),
            &views_opts(face, 1 << tile_pow, buckets),
        ).unwrap();
        let dirt = DirtTracer::new(views);
        let mut rng = Rng::new(seed, 3);
        let mut rays = Vec::new();
        for i in 0..300 {
            let o = (Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0) * 5.0;
            let d = warp::uniform_sphere(rng.next_vec2());
            let ray = match i % 4 {
                0 => Ray::new(o, d),
                1 => Ray::segment(o, d, rng.next_f32(), 1.0 + 8.0 * rng.next_f32()),
                // From the eye (camera rays and the eye's neighbourhood).
                2 => Ray::new(Vec3::from(eye), d),
                // Towards a triangle's corner region.
                _ => {
                    let t = tris[i % tris.len()];
                    let target = Vec3::from(t[0]) * 0.8 + Vec3::from(t[1]) * 0.1 + Vec3::from(t[2]) * 0.1;
                    Ray::new(o, (target - o).normalize_or(Vec3::X))
                }
            };
            rays.push(ray);
        }
        twins_agree(&dirt, &rays);
        let a = compare(&bvh, &dirt, &rays);
        prop_assert!(a.differ.is_empty(), "{} differences, first: {}", a.differ.len(), a.differ[0]);
        prop_assert_eq!(a.occlusion_differ, 0);
        prop_assert_eq!(a.truncated, 0);
    }
}

// ------------------------------------------------------------------------ real scenes

fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The ray types of DIRT Table 1, from the primary hits of a `w x h` view: primary rays, and
/// per hit a visibility ray (towards a point outside the scene's extents), a specular ray
/// (mirror direction), a glossy ray (GGX visible normals, alpha 0.3) and a diffuse ray
/// (cosine hemisphere).
fn ray_sets(scene: &Scene, bvh: &Bvh, cam: &Pinhole) -> Vec<(&'static str, Vec<Ray>)> {
    let bounds = scene.mesh.bounds();
    let light = bounds.center() + Vec3::new(0.3, 1.0, 0.2) * bounds.extent().length();
    let (mut primary, mut vis, mut spec, mut glossy, mut diffuse) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let ggx = warp::Ggx::isotropic(0.3);
    for y in 0..cam.height {
        for x in 0..cam.width {
            let r = cam
                .generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::ZERO, 0)
                .unwrap()
                .ray;
            primary.push(r);
            let Some(h) = bvh.closest_hit(&r) else {
                continue;
            };
            let p = r.at(h.t);
            let mut n = scene.mesh.geometric_normal(h.prim as usize);
            if n.dot(r.dir) > 0.0 {
                n = -n;
            }
            let o = p + n * (1e-4 * p.abs().max_element().max(1.0));
            let mut rng = Rng::for_pixel(11, x, y, 0);
            let to_light = light - o;
            vis.push(Ray::segment(
                o,
                to_light.normalize(),
                0.0,
                to_light.length(),
            ));
            spec.push(Ray::new(o, r.dir - 2.0 * r.dir.dot(n) * n));
            let f = Frame::from_normal(n);
            let wo = f.to_local(-r.dir);
            let m = ggx.sample_visible(wo, rng.next_vec2());
            let wi = warp::reflect(wo, m);
            if wi.z > 0.0 {
                glossy.push(Ray::new(o, f.to_world(wi)));
            }
            diffuse.push(Ray::new(
                o,
                f.to_world(warp::cosine_hemisphere(rng.next_vec2())),
            ));
        }
    }
    vec![
        ("primary", primary),
        ("visibility", vis),
        ("specular", spec),
        ("glossy", glossy),
        ("diffuse", diffuse),
    ]
}

/// Every ray type agrees with the BVH on >= 99.99 % of rays (up to exact ties); prints the
/// figures and any difference.
fn check_scene(name: &str, scene: &Scene, desc: &CameraDesc, opts: &DirtViewsOptions) {
    let bvh = Bvh::build(&scene.mesh);
    let cam = Pinhole::new(desc, 96, 54).unwrap();
    let views = DirtViews::build(&scene.mesh, Some(&cam), desc.eye, opts).unwrap();
    let dirt = DirtTracer::new(views);
    for (kind, rays) in ray_sets(scene, &bvh, &cam) {
        twins_agree(&dirt, &rays);
        let a = compare(&bvh, &dirt, &rays);
        println!(
            "{name} {kind}: {} rays, {:.5} same, {} ties, {} differ, {} occlusion differ",
            a.rays,
            a.same_fraction(),
            a.ties,
            a.differ.len(),
            a.occlusion_differ
        );
        for d in a.differ.iter().take(5) {
            println!("  {d}");
        }
        assert!(rays.len() > 1000, "{name} {kind}: too few rays");
        let agree = (a.same + a.ties) as f64 / a.rays as f64;
        assert!(agree >= 0.9999, "{name} {kind}: {agree} agree");
        assert_eq!(a.occlusion_differ, 0, "{name} {kind}");
        assert_eq!(a.truncated, 0, "{name} {kind}");
    }
}

#[test]
fn equals_the_bvh_on_the_atrium() {
    let scene = Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    check_scene("atrium", &scene, &desc, &views_opts(32, 1, 8));
    check_scene("atrium", &scene, &desc, &views_opts(24, 2, 3));
}

#[test]
fn equals_the_bvh_on_sponza() {
    let scene = Scene::load(&shared("sponza_dabrovic/sponza_dabrovic.glb")).unwrap();
    let desc = CameraDesc::new(
        Vec3::new(-9.0, 3.5, 0.0),
        Vec3::new(8.0, 5.0, 0.0),
        Vec3::Y,
        60.0,
    );
    check_scene("sponza", &scene, &desc, &views_opts(32, 2, 16));
}

#[test]
fn equals_the_bvh_on_the_classroom() {
    let scene = Scene::load(&shared("japanese_classroom/japanese_classroom.glb")).unwrap();
    let desc = CameraDesc::new(
        Vec3::new(-1.69, 1.272, 5.887),
        Vec3::new(-1.539, 1.3, 4.898),
        Vec3::Y,
        55.0,
    );
    check_scene("classroom", &scene, &desc, &views_opts(32, 1, 8));
}

// ---------------------------------------------------------------- defined answers

#[test]
fn rays_that_leave_every_view_miss() {
    let scene = Scene::load("cornell").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 32, 24).unwrap();
    let views = DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &views_opts(16, 1, 4)).unwrap();
    let dirt = DirtTracer::new(views);
    let bounds = scene.mesh.bounds();
    let mut stats = WorldStats::default();
    // From outside the scene, pointing away from it.
    let outside = bounds.max + Vec3::splat(1.0);
    let away = Ray::new(outside, Vec3::new(1.0, 0.5, 0.25).normalize());
    assert!(dirt.closest_hit(&away, &mut stats).is_none());
    assert!(!dirt.occluded(&away, &mut stats));
    // A segment that ends before the first surface.
    let r = cam
        .generate_ray(Vec2::new(16.0, 12.0), Vec2::ZERO, 0)
        .unwrap()
        .ray;
    let short = Ray::segment(r.origin, r.dir, 0.0, 1e-3);
    assert!(dirt.closest_hit(&short, &mut stats).is_none());
    // Invalid rays.
    for bad in [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
    ] {
        assert!(dirt.closest_hit(&bad, &mut stats).is_none());
        assert!(!dirt.occluded(&bad, &mut stats));
    }
    // An empty capture answers every ray with a miss.
    let empty = DirtTracer::new(
        DirtViews::build(
            &TriangleMesh::default(),
            Some(&cam),
            desc.eye,
            &views_opts(8, 1, 4),
        )
        .unwrap(),
    );
    assert!(empty.closest_hit(&r, &mut stats).is_none());
    assert_eq!(stats.truncated, 0);
}

#[test]
fn out_of_range_options_are_errors() {
    let scene = Scene::load("cornell").unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 32, 24).unwrap();
    let err = |o: DirtViewsOptions| {
        let e = DirtViews::build(&scene.mesh, Some(&cam), desc.eye, &o).unwrap_err();
        assert!(matches!(e, DirtError::InvalidOptions(_)), "{e}");
        e.to_string()
    };
    assert!(err(views_opts(0, 1, 4)).contains("face size 0"));
    assert!(err(views_opts(100_000, 1, 4)).contains("face size 100000"));
    assert!(err(views_opts(16, 1, 0)).contains("buckets 0"));
    assert!(err(views_opts(16, 1, 5000)).contains("buckets 5000"));
    assert!(err(views_opts(16, 3, 4)).contains("tile_size 3"));
    let e = DirtViews::build(&scene.mesh, None, Vec3::NAN, &views_opts(16, 1, 4)).unwrap_err();
    assert!(matches!(e, DirtError::InvalidView(_)), "{e}");
}
