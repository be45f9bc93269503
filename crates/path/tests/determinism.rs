//! Images do not depend on the thread count, on how samples are split into passes, or on
//! whether a time budget or a sample count chose the number of samples; the ray record is
//! reproducible.

use parallax_bvh::Bvh;
use parallax_path::{LightOverrides, PathOptions, PathTracer, apply_lighting};
use parallax_render::bsdf::MaterialMode;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

fn setup(name: &str, model: ModelKind) -> (Scene, Camera) {
    let mut scene = Scene::load(name).unwrap();
    apply_lighting(&mut scene, &LightOverrides::default()).unwrap();
    let desc = scene.camera(None).unwrap();
    let cam = Camera::new(model, &desc, 40, 24, &CameraOptions::default()).unwrap();
    (scene, cam)
}

fn bits(img: &parallax_core::Image<parallax_core::Rgb>) -> Vec<[u32; 3]> {
    img.data()
        .iter()
        .map(|c| [c.x.to_bits(), c.y.to_bits(), c.z.to_bits()])
        .collect()
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    for (name, model, materials) in [
        ("atrium", ModelKind::Pinhole, MaterialMode::AsIs),
        ("cornell", ModelKind::Pinhole, MaterialMode::Diffuse),
        ("cornell", ModelKind::Distorted, MaterialMode::AsIs),
    ] {
        let (scene, cam) = setup(name, model);
        let bvh = Bvh::build(&scene.mesh);
        let opts = PathOptions {
            spp: 3,
            seed: 9,
            materials,
            ..PathOptions::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let pt = PathTracer::new(&scene, &cam, &bvh, opts.clone()).unwrap();
                let out = pt.render(&|_| {});
                (bits(&out.image), bits(&out.variance), out.stats.rays())
            })
        };
        let (a, b) = (run(1), run(2));
        assert!(a.2 > 0);
        assert_eq!(a, b, "{name} {model:?}: 1 and 2 threads differ");
    }
}

#[test]
fn passes_and_time_budgets_do_not_change_the_image() {
    let (scene, cam) = setup("cornell", ModelKind::Pinhole);
    let bvh = Bvh::build(&scene.mesh);
    let base = PathOptions {
        spp: 5,
        seed: 3,
        ..PathOptions::default()
    };
    let pt = PathTracer::new(&scene, &cam, &bvh, base.clone()).unwrap();
    let whole = pt.render(&|_| {});
    // The same samples in three passes of different sizes.
    let mut film = pt.film();
    for r in [0..1, 1..3, 3..5] {
        pt.render_samples(&mut film, r, false, &|_| {});
    }
    assert_eq!(bits(&whole.image), bits(&film.mean()));
    assert_eq!(bits(&whole.variance), bits(&film.variance_of_mean()));
    assert!(film.counts().data().iter().all(|&n| n == 5));
    // A time budget takes whole passes, at least one sample, the same count everywhere, and
    // gives the image of that many samples.
    let timed = PathTracer::new(
        &scene,
        &cam,
        &bvh,
        PathOptions {
            spp: 64,
            time_budget: Some(0.05),
            ..base.clone()
        },
    )
    .unwrap()
    .render(&|_| {});
    assert!(timed.spp >= 1 && timed.spp <= 64);
    assert!(timed.counts.data().iter().all(|&n| n == timed.spp));
    let fixed = PathTracer::new(
        &scene,
        &cam,
        &bvh,
        PathOptions {
            spp: timed.spp,
            ..base
        },
    )
    .unwrap()
    .render(&|_| {});
    assert_eq!(bits(&timed.image), bits(&fixed.image));
}

#[test]
fn budgeted_units_give_the_image_of_their_sample_count_at_any_thread_count() {
    // 40x24 with 16-pixel tiles: 6 tiles, fewer than the units in flight at 3 threads near the
    // end of a round, so workers run ahead into the next round while others finish.
    let (scene, cam) = setup("cornell", ModelKind::Pinhole);
    let bvh = Bvh::build(&scene.mesh);
    let base = PathOptions {
        spp: 48,
        seed: 5,
        tile: 16,
        ..PathOptions::default()
    };
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let (timed, fixed) = pool.install(|| {
            let budget = PathOptions {
                time_budget: Some(0.03),
                ..base.clone()
            };
            let timed = PathTracer::new(&scene, &cam, &bvh, budget)
                .unwrap()
                .render(&|_| {});
            let fixed = PathOptions {
                spp: timed.spp,
                ..base.clone()
            };
            let fixed = PathTracer::new(&scene, &cam, &bvh, fixed)
                .unwrap()
                .render(&|_| {});
            (timed, fixed)
        });
        assert!(timed.spp >= 1 && timed.spp <= 48);
        assert!(timed.counts.data().iter().all(|&n| n == timed.spp));
        assert_eq!(bits(&timed.image), bits(&fixed.image), "{threads} threads");
        assert_eq!(bits(&timed.variance), bits(&fixed.variance));
        assert_eq!(timed.stats.paths, 40 * 24 * timed.spp as u64);
        assert!(timed.stats.work_ns > 0);
    }
}

#[test]
fn the_ray_record_is_reproducible_and_matches_the_statistics() {
    let (scene, cam) = setup("atrium", ModelKind::Pinhole);
    let bvh = Bvh::build(&scene.mesh);
    let opts = PathOptions {
        spp: 2,
        ..PathOptions::default()
    };
    let pt = PathTracer::new(&scene, &cam, &bvh, opts).unwrap();
    let (out, rec) = pt.render_recorded(&|_| {});
    let (out2, rec2) = pt.render_recorded(&|_| {});
    assert_eq!(rec, rec2);
    assert_eq!(bits(&out.image), bits(&out2.image));
    assert_eq!(
        rec.rays.len() as u64,
        out.stats.bounces.iter().map(|b| b.rays).sum::<u64>()
    );
    assert_eq!(
        rec.shadows.len() as u64,
        out.stats.bounces.iter().map(|b| b.shadow_rays).sum::<u64>()
    );
    // Camera rays: one per pixel and sample; every recorded hit is the BVH's answer.
    assert_eq!(rec.bounce(0).count(), 40 * 24 * 2);
    for r in rec.rays.iter().step_by(7) {
        let h = bvh.closest_hit(&r.ray);
        assert_eq!(h.map_or(parallax_core::NO_ID, |h| h.prim), r.prim);
    }
    for s in rec.shadows.iter().step_by(5) {
        assert_eq!(bvh.any_hit(&s.ray), s.occluded);
    }
    // A recorded render gives the image of an unrecorded one.
    assert_eq!(bits(&out.image), bits(&pt.render(&|_| {}).image));
}
