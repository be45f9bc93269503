//! Depth of field (Widmer et al. 2015, §5.2) on small images: scored against the converged
//! BVH thin-lens image, thread-count independence, the pinhole limit, secondary samples,
//! bad input.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_scene::camera::ThinLens;
use parallax_synth::dof::setup::guard_px;
use parallax_synth::dof::truth::{discontinuity_mask, masked_psnr, thin_lens_truth};
use parallax_synth::dof::{
    DofOptions, DofSetup, DofStructure, capture_dof_reference, lens_strata, render_dof,
};
use parallax_synth::method::{Method, MethodOptions};
use parallax_synth::warp::warp_view;
use parallax_synth::{Shading, score};

const W: u32 = 160;
const H: u32 = 90;

fn atrium() -> (Scene, Bvh) {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    (scene, bvh)
}

/// The atrium's default view as a thin lens focused on its target, aperture `a`.
fn setup(scene: &Scene, bvh: &Bvh, a: f32) -> DofSetup {
    let desc = scene.camera(None).unwrap();
    let lens = ThinLens::new(&desc, W, H, a, None).unwrap();
    let guard = guard_px(bvh, &lens);
    DofSetup { lens, guard }
}

fn opts(n_pri: u32, n_sec: u32) -> DofOptions {
    DofOptions {
        n_pri,
        n_sec,
        ..DofOptions::default()
    }
}

#[test]
fn strata_tile_the_lens() {
    assert_eq!(lens_strata(8), (4, 2));
    assert_eq!(lens_strata(4), (2, 2));
    assert_eq!(lens_strata(7), (7, 1));
    assert_eq!(lens_strata(1), (1, 1));
    assert_eq!(lens_strata(32), (8, 4));
}

#[test]
fn zero_aperture_is_the_warp_to_the_reference_view() {
    let (scene, bvh) = atrium();
    let s = setup(&scene, &bvh, 0.0);
    assert_eq!(s.guard, 1, "no circle of confusion, the minimal guard");
    let s = DofSetup { guard: 0, ..s };
    let r = capture_dof_reference(&scene, &bvh, &s, 2, Shading::Fixed, 0).unwrap();
    let st = DofStructure::build(Method::QuadTree, &r, &MethodOptions::default()).unwrap();
    let dof = render_dof(&st, &r, &s.lens, &opts(4, 4)).unwrap();
    let warped = warp_view(st.tracer(), &r, &s.lens.pinhole);
    // Every lens ray is the pixel-centre ray (lens radius 0; the thin lens normalises
    // `focus * dir` instead of `dir`, a rounding apart), every secondary sample too.
    let sc = score(&dof.image, &warped.image).unwrap();
    assert!(sc.psnr > 60.0, "{sc:?}");
    assert!(dof.secondary.samples > 0);
    assert!(
        dof.secondary.mean_weight() > 0.999,
        "a secondary sample equal to its primary weighs 1: {}",
        dof.secondary.mean_weight()
    );
}

#[test]
fn same_image_on_one_and_two_threads() {
    let (scene, bvh) = atrium();
    let s = setup(&scene, &bvh, 0.08);
    let r = capture_dof_reference(&scene, &bvh, &s, 2, Shading::Fixed, 0).unwrap();
    let st = DofStructure::build(Method::QuadTree, &r, &MethodOptions::default()).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| render_dof(&st, &r, &s.lens, &opts(4, 4)).unwrap())
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.image.data(), b.image.data());
    assert_eq!(a.stats, b.stats);
    assert_eq!(a.secondary, b.secondary);
}

#[test]
fn layers_inpainting_and_secondary_samples_against_the_converged_lens() {
    let (scene, bvh) = atrium();
    let s = setup(&scene, &bvh, 0.12);
    let truth = thin_lens_truth(&scene, &bvh, &s.lens, 64, Shading::Fixed, 0).unwrap();
    let mut rows = Vec::new();
    for (layers, inpaint) in [(1, false), (1, true), (2, false)] {
        let r = capture_dof_reference(&scene, &bvh, &s, layers, Shading::Fixed, 0).unwrap();
        let mo = MethodOptions {
            inpaint,
            ..MethodOptions::default()
        };
        let st = DofStructure::build(Method::QuadTree, &r, &mo).unwrap();
        let mask = discontinuity_mask(&r, s.guard, W, H, s.guard);
        for (p, q) in [(4, 1), (4, 4), (16, 1)] {
            let d = render_dof(&st, &r, &s.lens, &opts(p, q)).unwrap();
            let sc = score(&d.image, &truth).unwrap();
            let edge = masked_psnr(&d.image, &truth, &mask).unwrap();
            eprintln!(
                "layers {layers} inpaint {inpaint} {p}/{q}: {:.2} dB (edges {edge:.2}), ssim {:.4}, deep {:.2}%, sec weight {:.3}",
                sc.psnr,
                sc.ssim,
                d.pct_deep(),
                d.secondary.mean_weight()
            );
            rows.push(((layers, inpaint, p, q), sc.psnr, edge));
        }
    }
    let get =
        |k: (usize, bool, u32, u32)| rows.iter().find(|r| r.0 == k).map(|r| (r.1, r.2)).unwrap();
    let one = get((1, false, 16, 1));
    let two = get((2, false, 16, 1));
    let inp = get((1, true, 16, 1));
    assert!(two.1 > one.1, "two layers beat one at the discontinuities");
    assert!(
        inp.1 > one.1,
        "inpainting beats one layer at the discontinuities"
    );
    let plain = get((2, false, 4, 1));
    let sec = get((2, false, 4, 4));
    assert!(
        sec.0 > plain.0,
        "secondary samples reduce the error at equal rays"
    );
    assert!(two.0 > 25.0, "{two:?}");
}

#[test]
fn bad_input_is_an_error() {
    let (scene, bvh) = atrium();
    let s = setup(&scene, &bvh, 0.05);
    let r = capture_dof_reference(&scene, &bvh, &s, 1, Shading::Fixed, 0).unwrap();
    let st = DofStructure::build(Method::QuadTree, &r, &MethodOptions::default()).unwrap();
    for (o, what) in [
        (opts(0, 1), "N_pri"),
        (opts(1_000_000, 1), "N_pri"),
        (opts(4, 0), "N_sec"),
        (opts(4, 100_000), "N_sec"),
        (
            DofOptions {
                sigma: 0.0,
                ..DofOptions::default()
            },
            "sigma",
        ),
        (
            DofOptions {
                sigma: -1.0,
                ..DofOptions::default()
            },
            "sigma",
        ),
        (
            DofOptions {
                sigma: f32::NAN,
                ..DofOptions::default()
            },
            "sigma",
        ),
    ] {
        let e = render_dof(&st, &r, &s.lens, &o).unwrap_err().to_string();
        assert!(e.contains(what), "{e}");
    }
    let dda = DofStructure::build(Method::Dda, &r, &MethodOptions::default()).unwrap();
    let e = render_dof(&dda, &r, &s.lens, &opts(4, 4))
        .unwrap_err()
        .to_string();
    assert!(e.contains("quad-tree"), "{e}");
    assert!(capture_dof_reference(&scene, &bvh, &s, 0, Shading::Fixed, 0).is_err());
    assert!(thin_lens_truth(&scene, &bvh, &s.lens, 0, Shading::Fixed, 0).is_err());
}
