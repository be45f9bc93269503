//! View synthesis (Widmer et al. 2015, §5.1) on small images with the brute-force tracer:
//! stereo warping scored against the BVH eye views, the mesh warp, colour + depth input.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_core::image::write_exr;
use parallax_render::reference::render_gbuffer;
use parallax_render::score::ground_truth;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel, Pinhole};
use parallax_screen::TraceResult;
use parallax_synth::build_tracer;
use parallax_synth::input::{
    Intrinsics, input_desc, read_color, read_depth, reference_from_images,
};
use parallax_synth::method::{Method, MethodOptions, Synthesizer};
use parallax_synth::stereo::{stereo_eyes, warp_stereo};
use parallax_synth::warp::{OcclusionFill, Resample, WarpOptions, warp_view_with};
use parallax_synth::{HiddenLayers, Shading, capture_reference, capture_reference_with, score};

const W: u32 = 160;
const H: u32 = 120;
/// A wide baseline (4x a human IPD) so that disocclusions are visible at this size.
const IPD: f32 = 0.065 * 4.0;
/// Margins of `bilinear_resampling_and_layers_per_method` (dB), set from the measured table
/// in that test's comment.
const BILINEAR_GAIN: f64 = 0.08;
const LAYER_GAIN: f64 = 0.25;
const MESH_GAIN: f64 = 0.3;
/// Single-layer gain of the nearest-background occlusion fill (measured >= 0.25 dB).
const FILL_GAIN: f64 = 0.12;
/// With the background fill (defaults) two layers score above one at this size by at least this
/// much (measured +0.18 .. +0.50 dB, the DDA lowest).
const FILL_LAYER_GAIN: f64 = 0.08;
/// The background fill applied to two-layer occlusion-volume answers loses at most this much
/// at this size (measured -0.01 .. +0.01 dB: deeper-layer occlusion volumes take layer 0's
/// background; before that up to 0.17 dB).
const FILL_TWO_LAYER_SLACK: f64 = 0.1;

fn atrium() -> (Scene, Bvh) {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::try_build(&scene.mesh).unwrap();
    (scene, bvh)
}

/// Mean PSNR / SSIM of both eyes of `method` with `layers` layers.
fn stereo_psnr(scene: &Scene, bvh: &Bvh, layers: usize, method: Method) -> (f64, f64, f64) {
    stereo_psnr_with(scene, bvh, layers, method, &MethodOptions::default())
}

fn stereo_psnr_with(
    scene: &Scene,
    bvh: &Bvh,
    layers: usize,
    method: Method,
    opts: &MethodOptions,
) -> (f64, f64, f64) {
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let mut r = capture_reference(scene, bvh, &cam, layers, Shading::Fixed, 0).unwrap();
    let sv = warp_stereo(&mut r, &desc, IPD, method, opts).unwrap();
    let (mut p, mut s) = (0.0, 0.0);
    for (eye, v) in sv.eyes.iter().zip(&sv.views) {
        let truth = ground_truth(scene, bvh, eye, Shading::Fixed, 0);
        let sc = score(&v.image, &truth).unwrap();
        p += sc.psnr / 2.0;
        s += sc.ssim / 2.0;
    }
    (p, s, sv.views[0].frac_deep())
}

#[test]
fn stereo_brute_layers_against_bvh_eye_views() {
    let (scene, bvh) = atrium();
    let (p1, s1, deep1) = stereo_psnr(&scene, &bvh, 1, Method::Brute);
    let (p2, s2, deep2) = stereo_psnr(&scene, &bvh, 2, Method::Brute);
    eprintln!(
        "1 layer: {p1:.2} dB ssim {s1:.4}; 2 layers: {p2:.2} dB ssim {s2:.4} deep {deep2:.4}"
    );
    // Measured at 160x120 (atrium default camera, ipd 0.26; bilinear resampling + layer-0
    // guard + nearest-background fill of single-layer occlusion answers): 20.71 dB / 0.8645
    // and 21.23 dB / 0.8790 (1.4% of the pixels answered from layer 1; front-facing hidden
    // layers, see `front_facing_hidden_layers`). With the crossed-pixel fill 1 layer was
    // 20.44 / 0.853; with nearest colour and no guard 20.28 / 0.846 and 20.73 / 0.863.
    assert_eq!(deep1, 0.0);
    assert!(deep2 > 0.005 && deep2 < 0.05, "{deep2}");
    assert!(p1 > 19.5 && s1 > 0.83, "{p1} {s1}");
    assert!(p2 > 20.2 && s2 > 0.85, "{p2} {s2}");
    assert!(p2 > p1 + 0.15, "{p1} vs {p2}");
}

#[test]
fn zero_ipd_reproduces_the_reference_exactly() {
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let mut r = capture_reference(&scene, &bvh, &cam, 2, Shading::Fixed, 0).unwrap();
    let truth = ground_truth(&scene, &bvh, &cam, Shading::Fixed, 0);
    // Layer 0 shaded == the BVH render of the same camera (same shading, same streams).
    let ref_score = score(&r.colors[0], &truth).unwrap();
    assert!(ref_score.psnr > 60.0, "{ref_score:?}");
    let sv = warp_stereo(&mut r, &desc, 0.0, Method::Brute, &MethodOptions::default()).unwrap();
    for v in &sv.views {
        // Bilinear resampling at (nearly) exact pixel centres: equal up to the rounding of
        // the projected hit position.
        let same = score(&v.image, &r.colors[0]).unwrap();
        assert!(same.psnr > 60.0, "{same:?}");
        // A few pixels may answer from layer 1 at the same depth (coincident surfaces in the
        // k-buffer); the colour is the same.
        let deep = v
            .kinds
            .iter()
            .filter(|k| k.layer().unwrap_or(0) != 0)
            .count();
        assert!(deep * 100 < v.kinds.len(), "{deep}");
    }
}

#[test]
fn mesh_warp_scores() {
    let (scene, bvh) = atrium();
    let (p, s, _) = stereo_psnr(&scene, &bvh, 1, Method::Mesh);
    let split = MethodOptions {
        mesh_max_rel_jump: 0.05,
        ..MethodOptions::default()
    };
    let (ps, ss, _) = stereo_psnr_with(&scene, &bvh, 1, Method::Mesh, &split);
    eprintln!("mesh: {p:.2} dB {s:.4}; split at 5%: {ps:.2} dB {ss:.4}");
    // Measured: 18.16 dB / 0.859 stretched; 11.42 dB / 0.560 torn at 5% depth jumps (the
    // holes show the environment).
    assert!(p > 17.5 && s > 0.84, "{p} {s}");
    assert!(ps < p - 3.0, "{ps} vs {p}");
}

#[test]
fn layer_one_answers_vs_bvh() {
    // Primitive agreement with the BVH G-buffer of the left eye, per answering layer, for
    // both kinds of hidden layers.
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let mut layer1 = Vec::new();
    for hidden in [HiddenLayers::All, HiddenLayers::FrontFacing] {
        let mut r =
            capture_reference_with(&scene, &bvh, &cam, 2, hidden, Shading::Fixed, 0).unwrap();
        let opts = MethodOptions::default();
        let tracer = build_tracer(Method::Brute, &r.cube, &r.layers, &opts).unwrap();
        let sv = warp_stereo(&mut r, &desc, IPD, Method::Brute, &opts).unwrap();
        let eye = &sv.eyes[0];
        let g = render_gbuffer(&scene, &bvh, &Camera::Pinhole(eye.clone()));
        let mut agree = [[0u32; 2]; 2]; // [layer][same, different]
        for y in 0..H {
            for x in 0..W {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let ray = eye.generate_ray(film, Vec2::splat(0.5), 1).unwrap().ray;
                let res = tracer.trace(&ray, &mut Default::default());
                if let TraceResult::Hit { layer, pixel, .. } = res {
                    let p = r.layers[layer as usize].get(pixel.x, pixel.y).primitive_id;
                    let l = layer.min(1) as usize;
                    agree[l][(p != g.get(x, y).primitive_id) as usize] += 1;
                }
            }
        }
        eprintln!(
            "{hidden:?}: layer 0 same/diff {:?}, layer 1 same/diff {:?}",
            agree[0], agree[1]
        );
        assert!(agree[0][0] > 5 * agree[0][1], "{agree:?}");
        layer1.push(agree[1]);
    }
    // Measured: all surfaces: layer 1 7 same / 302 different (back faces behind cracks);
    // front-facing: 192 / 145.
    assert!(layer1[0][0] * 10 < layer1[0][1], "{layer1:?}");
    assert!(layer1[1][0] > layer1[1][1], "{layer1:?}");
}

#[test]
fn color_depth_input_round_trip() {
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let truth = ground_truth(&scene, &bvh, &cam, Shading::Fixed, 0);
    let g = render_gbuffer(&scene, &bvh, &Camera::Pinhole(cam.clone()));
    let dir = std::env::temp_dir().join(format!("parallax-synth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (cpath, dpath) = (dir.join("color.exr"), dir.join("depth.exr"));
    let ch = |c: usize| truth.data().iter().map(|v| v[c]).collect::<Vec<f32>>();
    let (r, gg, b) = (ch(0), ch(1), ch(2));
    write_exr(&cpath, W, H, &[("R", &r), ("G", &gg), ("B", &b)]).unwrap();
    write_exr(&dpath, W, H, &[("Z", &g.depth)]).unwrap();
    let color = read_color(&cpath).unwrap();
    let depth = read_depth(&dpath).unwrap();
    assert!(read_depth(&cpath).is_ok()); // falls back to R
    assert!(read_depth(&dir.join("missing.exr")).is_err());
    let d = input_desc(
        Intrinsics::FovYDeg(desc.fov_y_deg),
        H,
        Some((desc.eye, desc.target, desc.up)),
    )
    .unwrap();
    let mut reference = reference_from_images(color, &depth, &d, scene.environment).unwrap();
    let sv = warp_stereo(
        &mut reference,
        &d,
        0.0,
        Method::Brute,
        &MethodOptions::default(),
    )
    .unwrap();
    let sc = score(&sv.views[0].image, &truth).unwrap();
    eprintln!("round trip {sc:?}");
    assert!(sc.psnr > 60.0, "{sc:?}");
    // Focal length in pixels gives the same camera.
    let f = 0.5 * H as f32 / (desc.fov_y_deg.to_radians() * 0.5).tan();
    let d2 = input_desc(
        Intrinsics::FocalPx(f),
        H,
        Some((desc.eye, desc.target, desc.up)),
    )
    .unwrap();
    assert!((d2.fov_y_deg - desc.fov_y_deg).abs() < 1e-3);
    assert!(input_desc(Intrinsics::FocalPx(-1.0), H, None).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn method_names_and_every_tracer_builds() {
    for m in Method::ALL {
        assert_eq!(m.name().parse::<Method>().unwrap(), m);
    }
    assert!("bogus".parse::<Method>().is_err());
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, 16, 12).unwrap();
    let r = capture_reference(&scene, &bvh, &cam, 1, Shading::Fixed, 0).unwrap();
    for m in Method::ALL {
        let s = Synthesizer::build(m, &r, &MethodOptions::default());
        assert!(s.is_ok(), "{m}: {:?}", s.err());
    }
    // The DDA marches at most two layers: asking for three is an error, not a silent clamp.
    let r3 = capture_reference(&scene, &bvh, &cam, 3, Shading::Fixed, 0).unwrap();
    let e = Synthesizer::build(Method::Dda, &r3, &MethodOptions::default())
        .err()
        .unwrap();
    assert!(e.to_string().contains("1 or 2 layers"), "{e}");
}

#[test]
fn front_facing_hidden_layers() {
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let mut scores = Vec::new();
    for hidden in [HiddenLayers::All, HiddenLayers::FrontFacing] {
        let mut r =
            capture_reference_with(&scene, &bvh, &cam, 2, hidden, Shading::Fixed, 0).unwrap();
        let sv = warp_stereo(&mut r, &desc, IPD, Method::Brute, &MethodOptions::default()).unwrap();
        let mut p = 0.0;
        for (eye, v) in sv.eyes.iter().zip(&sv.views) {
            let truth = ground_truth(&scene, &bvh, eye, Shading::Fixed, 0);
            p += score(&v.image, &truth).unwrap().psnr / 2.0;
        }
        eprintln!("{hidden:?}: {p:.2} dB, deep {:.4}", sv.views[0].frac_deep());
        scores.push(p);
    }
    // Measured: 21.06 dB (all) vs 21.27 dB (front-facing) (nearest, no guard: 19.95 / 20.73;
    // before deeper-layer hits blended layer-0 samples first and the guard rejected contact
    // samples: 20.22 / 20.98).
    assert!(scores[1] > scores[0] + 0.12, "{scores:?}");
}

/// Mean PSNR of both eyes at `W x H` (atrium, ipd `IPD`) for every tracer method x layers x
/// warp options; returns `[method][layers - 1][variant]` with variants (nearest, no guard),
/// (bilinear, no guard), (bilinear, guard), all with the crossed-pixel occlusion fill, and
/// (bilinear, guard, nearest-background fill) = the default.
fn warp_table(methods: &[Method]) -> Vec<[[f64; 4]; 2]> {
    let (scene, bvh) = atrium();
    let desc = scene.camera(None).unwrap();
    let cam = Pinhole::new(&desc, W, H).unwrap();
    let eyes = stereo_eyes(&desc, W, H, IPD).unwrap();
    let truths = eyes
        .clone()
        .map(|e| ground_truth(&scene, &bvh, &e, Shading::Fixed, 0));
    let refs: Vec<_> = [1, 2]
        .map(|n| capture_reference(&scene, &bvh, &cam, n, Shading::Fixed, 0).unwrap())
        .into();
    let variants = [
        (Resample::Nearest, false, OcclusionFill::Crossed),
        (Resample::Bilinear, false, OcclusionFill::Crossed),
        (Resample::Bilinear, true, OcclusionFill::Crossed),
        (Resample::Bilinear, true, OcclusionFill::NearestBackground),
    ];
    methods
        .iter()
        .map(|&m| {
            let mut row = [[0.0; 4]; 2];
            for (l, r) in refs.iter().enumerate() {
                let tracer =
                    build_tracer(m, &r.cube, &r.layers, &MethodOptions::default()).unwrap();
                for (k, (resample, layer0_guard, fill)) in variants.into_iter().enumerate() {
                    let wo = WarpOptions {
                        resample,
                        fill,
                        ..WarpOptions::default()
                    }
                    .with_layer0_guard(layer0_guard);
                    row[l][k] = eyes
                        .iter()
                        .zip(&truths)
                        .map(|(e, t)| {
                            let v = warp_view_with(tracer.as_ref(), r, e, &wo);
                            score(&v.image, t).unwrap().psnr / 2.0
                        })
                        .sum();
                }
            }
            eprintln!("{m}: 1 layer {:.2?}, 2 layers {:.2?}", row[0], row[1]);
            row
        })
        .collect()
}

/// Measured (160x120, ipd 0.26; nearest / bilinear / bilinear + guard, crossed-pixel fill /
/// bilinear + guard + nearest-background fill = default):
///
/// | method | 1 layer | 2 layers |
/// |---|---|---|
/// | brute | 20.28 / 20.44 / 20.44 / 20.71 | 20.73 / 21.06 / 21.23 / 21.23 |
/// | quadtree | 20.22 / 20.37 / 20.37 / 20.65 | 20.60 / 20.94 / 21.15 / 21.15 |
/// | dda | 18.48 / 18.82 / 18.82 / 19.17 | 18.61 / 18.97 / 19.34 / 19.35 |
/// | minmax | 20.38 / 20.56 / 20.56 / 20.81 | 20.52 / 20.73 / 21.24 / 21.24 |
/// | hiz | 20.36 / 20.54 / 20.54 / 20.79 | 20.49 / 20.70 / 21.23 / 21.23 |
///
/// (With guard parts (d), (e) of `warp.rs`; before them the guarded 2-layer columns were
/// 0.03-0.04 dB higher at this size, see `two_layers_beat_one_layer`.)
///
/// mesh 18.16 dB. Bilinear gains >= 0.14 dB, two layers >= 0.52 dB above one (crossed fill),
/// one layer >= 0.66 dB above the mesh warp, the background fill >= 0.25 dB for one layer;
/// with two layers it changes little (-0.01 .. +0.01 dB), and two layers stay >= 0.18 dB above
/// one with the defaults.
#[test]
fn bilinear_resampling_and_layers_per_method() {
    let methods = [
        Method::Brute,
        Method::QuadTree,
        Method::Dda,
        Method::MinMax,
        Method::HiZ,
    ];
    let t = warp_table(&methods);
    let (mesh, _, _) = stereo_psnr(&atrium().0, &atrium().1, 1, Method::Mesh);
    eprintln!("mesh {mesh:.2}");
    for (m, row) in methods.iter().zip(&t) {
        for l in 0..2 {
            // Bilinear beats nearest (same tracer answers).
            assert!(row[l][1] > row[l][0] + BILINEAR_GAIN, "{m} {l}: {row:?}");
        }
        // Bilinear + guard with the crossed-pixel fill: two layers above one, both above the
        // mesh warp.
        assert!(row[1][2] > row[0][2] + LAYER_GAIN, "{m}: {row:?}");
        assert!(row[0][2] > mesh + MESH_GAIN, "{m}: {row:?} mesh {mesh}");
        // The default: the nearest-background fill gains for one layer, costs little for two,
        // and two layers score above one.
        assert!(row[0][3] > row[0][2] + FILL_GAIN, "{m}: {row:?}");
        assert!(row[1][3] > row[1][2] - FILL_TWO_LAYER_SLACK, "{m}: {row:?}");
        assert!(row[1][3] > row[0][3] + FILL_LAYER_GAIN, "{m}: {row:?}");
    }
}

/// Widmer et al. 2015, Fig. 6e: occlusion-volume answers filled with the nearest background
/// pixel. A red square at 2 m over a blue wall at 6 m seen from 0.3 m to the right: every
/// occlusion-volume pixel takes the wall's colour with [`OcclusionFill::NearestBackground`],
/// and the square's (the crossed pixel's) with [`OcclusionFill::Crossed`].
#[test]
fn occlusion_fill_takes_nearest_background() {
    use parallax_core::Image;
    use parallax_synth::warp::{HitKind, OcclusionFill};
    let (w, h) = (64u32, 48u32);
    let (red, blue, env) = (
        glam::Vec3::new(1.0, 0.0, 0.0),
        glam::Vec3::new(0.0, 0.0, 1.0),
        glam::Vec3::new(0.0, 1.0, 0.0),
    );
    let square = |x: u32, y: u32| (24..40).contains(&x) && (16..32).contains(&y);
    let mut color = Image::new(w, h, blue).unwrap();
    let mut depth = Image::new(w, h, 6.0f32).unwrap();
    for y in 0..h {
        for x in 0..w {
            if square(x, y) {
                *color.get_mut(x, y) = red;
                *depth.get_mut(x, y) = 2.0;
            }
        }
    }
    let desc = input_desc(Intrinsics::FovYDeg(60.0), h, None).unwrap();
    let reference = reference_from_images(color, &depth, &desc, env).unwrap();
    let eye = glam::Vec3::new(0.3, 0.0, 0.0);
    let target_desc =
        parallax_scene::CameraDesc::new(eye, eye + glam::Vec3::NEG_Z, glam::Vec3::Y, 60.0);
    let target = Pinhole::new(&target_desc, w, h).unwrap();
    let tracer = build_tracer(
        Method::Brute,
        &reference.cube,
        &reference.layers,
        &MethodOptions::default(),
    )
    .unwrap();
    let view = |fill| {
        let wo = WarpOptions {
            fill,
            ..WarpOptions::default()
        };
        warp_view_with(tracer.as_ref(), &reference, &target, &wo)
    };
    let (bg, crossed) = (
        view(OcclusionFill::NearestBackground),
        view(OcclusionFill::Crossed),
    );
    assert_eq!(bg.kinds, crossed.kinds);
    let ov: Vec<usize> = (0..bg.kinds.len())
        .filter(|&i| matches!(bg.kinds[i], HitKind::Occlusion(0)))
        .collect();
    let near = |a: glam::Vec3, b: glam::Vec3| (a - b).abs().max_element() < 1e-4;
    let n_bg = ov
        .iter()
        .filter(|&&i| near(bg.image.data()[i], blue))
        .count();
    let n_red = ov
        .iter()
        .filter(|&&i| near(crossed.image.data()[i], red))
        .count();
    eprintln!(
        "{} occlusion pixels: background fill blue {n_bg}, crossed red {n_red}",
        ov.len()
    );
    assert!(ov.len() >= 16, "{}", ov.len());
    assert_eq!(n_bg, ov.len());
    assert!(n_red * 2 > ov.len(), "{n_red} of {}", ov.len());
    // Everything else is unchanged.
    for i in 0..bg.kinds.len() {
        if !matches!(bg.kinds[i], HitKind::Occlusion(_)) {
            assert_eq!(bg.image.data()[i], crossed.image.data()[i]);
        }
    }
}

/// Mean PSNR of both eyes of `method` on `scene` (pose `desc`) at `W x H`, ipd `ipd`, with
/// `layers` layers and warp options `wo` (fitted cube, as `bench warp`).
fn stereo_psnr_scene(
    scene: &Scene,
    bvh: &Bvh,
    desc: &parallax_scene::CameraDesc,
    ipd: f32,
    layers: usize,
    method: Method,
    wo: WarpOptions,
) -> f64 {
    let cam = Pinhole::new(desc, W, H).unwrap();
    let mut r = capture_reference(scene, bvh, &cam, layers, Shading::Fixed, 0).unwrap();
    let opts = MethodOptions {
        warp: wo,
        ..MethodOptions::default()
    };
    let sv = warp_stereo(&mut r, desc, ipd, method, &opts).unwrap();
    sv.eyes
        .iter()
        .zip(&sv.views)
        .map(|(eye, v)| {
            let truth = ground_truth(scene, bvh, eye, Shading::Fixed, 0);
            score(&v.image, &truth).unwrap().psnr / 2.0
        })
        .sum()
}

/// Two layers score above one (defaults: bilinear, layer-0 guard (a)-(e), background fill)
/// for the quad-tree and brute force on atrium and Sponza at 160x120 with the wide baseline
/// `IPD` (0.26 m: at a human ipd and this size layer 1 answers a handful of pixels and the
/// difference is noise). Measured (2 layers - 1 layer, dB): atrium quadtree +0.51, brute
/// +0.52; Sponza quadtree +0.23, brute +0.23 (see the printout). Also printed: the guard's
/// parts (d) and (e) off (at this size they cost 0.03 dB on atrium, 0.005 dB on Sponza; at
/// 1600x900, ipd 0.065, they gain 0.02-0.03 dB, see `warp.rs`).
#[test]
fn two_layers_beat_one_layer() {
    let (atrium, atrium_bvh) = atrium();
    let sponza = Scene::load("../../../shared/scenes/sponza_dabrovic/sponza_dabrovic.glb").unwrap();
    let sponza_bvh = Bvh::try_build(&sponza.mesh).unwrap();
    let sponza_desc = parallax_scene::CameraDesc::new(
        glam::Vec3::new(-9.0, 3.5, 0.0),
        glam::Vec3::new(8.0, 5.0, 0.0),
        glam::Vec3::Y,
        60.0,
    );
    let scenes = [
        (&atrium, &atrium_bvh, atrium.camera(None).unwrap()),
        (&sponza, &sponza_bvh, sponza_desc),
    ];
    let no_de = WarpOptions {
        silhouette_check: false,
        nearer_neighbour_check: false,
        ..WarpOptions::default()
    };
    for (scene, bvh, desc) in &scenes {
        for m in [Method::QuadTree, Method::Brute] {
            let p = |layers, wo| stereo_psnr_scene(scene, bvh, desc, IPD, layers, m, wo);
            let p1 = p(1, WarpOptions::default());
            let p2 = p(2, WarpOptions::default());
            let p2_no_de = p(2, no_de);
            let p2_no_e = p(
                2,
                WarpOptions {
                    nearer_neighbour_check: false,
                    ..WarpOptions::default()
                },
            );
            eprintln!("   e off: {p2_no_e:.3}");
            eprintln!(
                "{} {m}: 1 layer {p1:.3} dB, 2 layers {p2:.3} dB (guard d, e off: {p2_no_de:.3})",
                scene.name
            );
            assert!(p2 > p1 + TWO_LAYER_GAIN, "{} {m}: {p1} vs {p2}", scene.name);
        }
    }
}

/// Margin of `two_layers_beat_one_layer` (dB; measured >= 0.23).
const TWO_LAYER_GAIN: f64 = 0.1;
