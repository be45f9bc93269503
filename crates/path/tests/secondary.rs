//! The secondary-ray renderer (Bürger et al. 2007, §2): images do not depend on the thread
//! count, the LDC's image is close to the BVH's (PSNR) on the Cornell box and on the bunny in
//! the room, shadows only ever remove light, the BVH agrees with itself on replayed rays, and
//! bad input is an error.

use parallax_core::image::GBuffer;
use parallax_path::secondary::replay::{RayBatch, replay_rows, score};
use parallax_path::secondary::{Effects, SecondaryError, SecondaryOptions, compare, render};
use parallax_path::tracers::{BuiltTracer, LdcSettings, TracerKind, TracerOptions, build_tracer};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, Pinhole};

fn shared(rel: &str) -> String {
    format!(
        "{}/../../../shared/scenes/{rel}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn view(scene: &Scene, w: u32, h: u32) -> (Pinhole, GBuffer) {
    let cam = Pinhole::new(&scene.camera(None).unwrap(), w, h).unwrap();
    let v = parallax_raster::View::from_pinhole(&cam).unwrap();
    let g = parallax_raster::capture_gbuffer(scene, &v)
        .unwrap()
        .layers
        .layers
        .remove(0);
    (cam, g)
}

fn build(scene: &Scene, kind: TracerKind, ldc: LdcSettings) -> parallax_path::Result<BuiltTracer> {
    let cam = Camera::Pinhole(Pinhole::new(&scene.camera(None).unwrap(), 8, 8).unwrap());
    build_tracer(
        kind,
        scene,
        &cam,
        &TracerOptions {
            ldc,
            ..TracerOptions::default()
        },
    )
}

fn built(scene: &Scene, kind: TracerKind, res: u32) -> BuiltTracer {
    let s = LdcSettings {
        resolution: res.max(1),
        ..LdcSettings::default()
    };
    build(scene, kind, s).unwrap()
}

#[test]
fn images_are_identical_at_one_and_two_threads() {
    let scene = Scene::load("cornell").unwrap();
    let (cam, g) = view(&scene, 64, 48);
    let opts = SecondaryOptions::default();
    for kind in [TracerKind::Bvh, TracerKind::Ldc] {
        let t = built(&scene, kind, 128);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&scene, &cam, &g, t.tracer.as_ref(), &opts).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.image.data(), b.image.data(), "{kind:?}");
        assert_eq!(a.rays(), b.rays());
        assert!(a.batches.len() >= 3, "shadow, reflect and refract batches");
    }
}

#[test]
fn the_ldc_image_is_close_to_the_bvh_image() {
    let scene = Scene::load("cornell").unwrap();
    let (cam, g) = view(&scene, 96, 72);
    let bvh = built(&scene, TracerKind::Bvh, 0);
    let ldc = built(&scene, TracerKind::Ldc, 512);
    let c = compare(
        &scene,
        &cam,
        &g,
        &bvh,
        std::slice::from_ref(&ldc),
        &SecondaryOptions::default(),
        1,
        1e-3,
    )
    .unwrap();
    let l = &c.tracers[1];
    eprintln!(
        "cornell 96x72, LDC 512^2: {:.2} dB, SSIM {:.4}",
        l.psnr, l.ssim
    );
    assert!(l.psnr >= 36.0, "{}", l.psnr);
    // The BVH agrees with itself on its own rays; the LDC on most of them.
    for r in c.rows.iter().filter(|r| r.bounce == -1) {
        if r.method == "bvh" {
            assert_eq!(r.agreement, 1.0, "{}", r.effect);
        } else {
            assert!(
                r.agreement > 0.97,
                "{} {}: {}",
                r.method,
                r.effect,
                r.agreement
            );
        }
    }
}

#[test]
fn the_bunny_in_the_room_through_the_ldc() {
    let bunny = shared("stanford_bunny/bunny.glb");
    if !std::path::Path::new(&bunny).exists() {
        eprintln!("skipping missing {bunny}");
        return;
    }
    let scene = Scene::load(&format!("room:{bunny}")).unwrap();
    let (cam, g) = view(&scene, 80, 60);
    let bvh = built(&scene, TracerKind::Bvh, 0);
    let ldc = built(&scene, TracerKind::Ldc, 512);
    let opts = SecondaryOptions::default();
    let truth = render(&scene, &cam, &g, bvh.tracer.as_ref(), &opts).unwrap();
    let image = render(&scene, &cam, &g, ldc.tracer.as_ref(), &opts).unwrap();
    let (psnr, ssim) = score(&image.image, &truth.image).unwrap();
    eprintln!("room(bunny) 80x60, LDC 512^2: {psnr:.2} dB, SSIM {ssim:.4}");
    assert!(psnr >= 40.0, "{psnr}");
}

#[test]
fn shadows_only_remove_light() {
    let scene = Scene::load("cornell").unwrap();
    let (cam, g) = view(&scene, 48, 36);
    let bvh = built(&scene, TracerKind::Bvh, 0);
    let lit = SecondaryOptions {
        effects: Effects::parse("reflect,refract").unwrap(),
        ..SecondaryOptions::default()
    };
    let a = render(&scene, &cam, &g, bvh.tracer.as_ref(), &lit).unwrap();
    let b = render(
        &scene,
        &cam,
        &g,
        bvh.tracer.as_ref(),
        &SecondaryOptions::default(),
    )
    .unwrap();
    let (mut darker, mut total) = (0, 0);
    for (u, s) in a.image.data().iter().zip(b.image.data()) {
        assert!(s.cmple(*u + 1e-6).all(), "{s} brighter than unshadowed {u}");
        darker += (s.max_element() < u.max_element() - 1e-3) as usize;
        total += 1;
    }
    assert!(
        darker > total / 20,
        "some pixels are in shadow: {darker} of {total}"
    );
    assert!(
        a.batches
            .iter()
            .all(|b| b.effect != parallax_path::secondary::Effect::Shadow)
    );
    // Replaying the BVH's own batches through it agrees everywhere.
    let batches: Vec<RayBatch> = b.batches.iter().map(RayBatch::from).collect();
    let contenders = [parallax_path::secondary::replay::Contender {
        tracer: bvh.tracer.as_ref(),
        build_ms: 0.0,
        bounds: None,
    }];
    for r in replay_rows(&batches, &contenders, 1, 1e-6) {
        assert_eq!(r.agreement, 1.0, "{} {}", r.effect, r.bounce);
    }
}

#[test]
fn bad_input_is_an_error() {
    let scene = Scene::load("cornell").unwrap();
    let (cam, g) = view(&scene, 16, 12);
    let bvh = built(&scene, TracerKind::Bvh, 0);
    let too_deep = SecondaryOptions {
        bounces: 1000,
        ..SecondaryOptions::default()
    };
    assert!(matches!(
        render(&scene, &cam, &g, bvh.tracer.as_ref(), &too_deep),
        Err(SecondaryError::InvalidOptions(_))
    ));
    let (other, _) = view(&scene, 17, 12);
    assert!(
        render(
            &scene,
            &other,
            &g,
            bvh.tracer.as_ref(),
            &SecondaryOptions::default()
        )
        .is_err()
    );
    assert!(Effects::parse("reflect,sparkle").is_err());
    assert!(TracerKind::parse("octree").is_err());
    for res in [0, 1 << 20] {
        let s = LdcSettings {
            resolution: res,
            ..LdcSettings::default()
        };
        let e = build(&scene, TracerKind::Ldc, s)
            .err()
            .expect("an error")
            .to_string();
        assert!(e.contains("resolution"), "{e}");
    }
    let mut s = LdcSettings::default();
    s.trace.eps = 0.0;
    s.resolution = 32;
    let e = build(&scene, TracerKind::Ldc, s)
        .err()
        .expect("an error")
        .to_string();
    assert!(e.contains("eps"), "{e}");
}

#[test]
fn the_view_fitted_region_of_interest_is_kept_only_when_it_buys_resolution() {
    use parallax_path::secondary::roi::{DEFAULT_MARGIN, DEFAULT_TRIM, view_roi};
    let scene = Scene::load("cornell").unwrap();
    let (cam, g) = view(&scene, 64, 48);
    // The camera sees the whole box: fitting would only cut geometry off.
    assert_eq!(
        view_roi(&scene, &cam, &g, DEFAULT_TRIM, DEFAULT_MARGIN),
        None
    );
    // A far copy of the box stretches the bounds 50-fold; the view still sees the first box.
    let box_bounds = scene.mesh.bounds();
    let mut far = scene.clone();
    let mut copy = scene.mesh.clone();
    for p in &mut copy.positions {
        *p += glam::Vec3::new(100.0, 0.0, 0.0);
    }
    far.mesh.append(&copy, 0);
    let (cam, g) = view(&far, 64, 48);
    let [lo, hi] = view_roi(&far, &cam, &g, DEFAULT_TRIM, DEFAULT_MARGIN).expect("a fit");
    assert!(lo.cmplt(hi).all());
    let far_bounds = far.mesh.bounds();
    assert!(lo.cmpge(far_bounds.min).all() && hi.cmple(far_bounds.max).all());
    assert!((hi - lo).max_element() * 10.0 < far_bounds.extent().max_element());
    // The margin keeps the first box whole (walls, floor and ceiling the view sees).
    assert!(
        lo.cmple(box_bounds.min).all() && hi.cmpge(box_bounds.max).all(),
        "{lo} .. {hi}"
    );
    // A view of nothing fits nothing.
    let mut empty = g.clone();
    empty.depth.fill(f32::INFINITY);
    assert_eq!(
        view_roi(&far, &cam, &empty, DEFAULT_TRIM, DEFAULT_MARGIN),
        None
    );
}
