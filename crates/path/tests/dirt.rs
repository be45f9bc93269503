//! DIRT's path tracer is the reference path tracer with DIRT behind the tracer interface
//! (Vardis et al. 2017, §4.2): with the same seed both find the same primitive for >= 99.99 %
//! of the rays of every bounce on the atrium, Sponza and the classroom, and their images agree
//! to >= 60 dB. The tracer factory builds DIRT and rejects options out of range.

use glam::Vec3;
use parallax_path::bench::dirt_path::path_agreement;
use parallax_path::{
    LightOverrides, PathOptions, PathTracer, TracerKind, TracerOptions, apply_lighting,
    build_tracer,
};
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};

fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn check(name: &str, mut scene: Scene, desc: &CameraDesc) {
    apply_lighting(&mut scene, &LightOverrides::default()).unwrap();
    let camera = Camera::new(ModelKind::Pinhole, desc, 64, 36, &CameraOptions::default()).unwrap();
    let opts = PathOptions {
        spp: 2,
        seed: 5,
        max_depth: 5,
        ..PathOptions::default()
    };
    let (a, ..) = path_agreement(&scene, &camera, &opts, &TracerOptions::default()).unwrap();
    println!(
        "{name}: PSNR {:.1} dB, {} pixels differ",
        a.psnr, a.pixels_differ
    );
    for b in &a.bounces {
        println!(
            "  bounce {}: {} rays, same {:.5}, ties {}, unmatched {}, shadows {}/{} same",
            b.bounce,
            b.rays,
            b.same_fraction(),
            b.ties,
            b.unmatched,
            b.shadow_same,
            b.shadow_rays
        );
        assert!(
            b.same_or_tie_fraction() >= 0.9999,
            "{name} bounce {}: {b:?}",
            b.bounce
        );
        assert_eq!(b.shadow_same, b.shadow_rays, "{name} bounce {}", b.bounce);
    }
    assert!(a.bounces[0].rays >= 64 * 36 * 2);
    assert!(a.bounces.len() >= 3, "{name}: paths end early");
    assert!(a.psnr >= 60.0, "{name}: {} dB", a.psnr);
}

#[test]
fn dirt_path_tracer_equals_the_bvh_path_tracer_on_the_atrium() {
    let scene = Scene::load("atrium").unwrap();
    let desc = scene.camera(None).unwrap();
    check("atrium", scene, &desc);
}

#[test]
fn dirt_path_tracer_equals_the_bvh_path_tracer_on_sponza() {
    let scene = Scene::load(&shared("sponza_dabrovic/sponza_dabrovic.glb")).unwrap();
    let desc = CameraDesc::new(
        Vec3::new(-9.0, 3.5, 0.0),
        Vec3::new(8.0, 5.0, 0.0),
        Vec3::Y,
        60.0,
    );
    check("sponza", scene, &desc);
}

#[test]
fn dirt_path_tracer_equals_the_bvh_path_tracer_on_the_classroom() {
    let scene = Scene::load(&shared("japanese_classroom/japanese_classroom.glb")).unwrap();
    let desc = CameraDesc::new(
        Vec3::new(-1.69, 1.272, 5.887),
        Vec3::new(-1.539, 1.3, 4.898),
        Vec3::Y,
        55.0,
    );
    check("classroom", scene, &desc);
}

#[test]
fn dirt_path_tracer_is_the_same_at_one_and_two_threads() {
    let mut scene = Scene::load("atrium").unwrap();
    apply_lighting(&mut scene, &LightOverrides::default()).unwrap();
    let desc = scene.camera(None).unwrap();
    let camera = Camera::new(ModelKind::Pinhole, &desc, 40, 24, &CameraOptions::default()).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let built =
                build_tracer(TracerKind::Dirt, &scene, &camera, &TracerOptions::default()).unwrap();
            let opts = PathOptions {
                spp: 2,
                seed: 3,
                ..PathOptions::default()
            };
            let pt = PathTracer::new(&scene, &camera, built.tracer.as_ref(), opts).unwrap();
            let out = pt.render(&|_| {});
            let bits: Vec<[u32; 3]> = out
                .image
                .data()
                .iter()
                .map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
                .collect();
            (bits, out.stats.rays())
        })
    };
    let (a, b) = (run(1), run(2));
    assert!(a.1 > 0);
    assert_eq!(a, b, "1 and 2 threads differ");
}
