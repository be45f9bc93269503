//! `parallax demo`: the README's first command. Renders the built-in atrium through several
//! camera models and every technique's piece into a folder, prints a summary table and writes
//! the folder's page (`index.html`): the pieces in sections by paper, each with what it shows,
//! its scores, and a wipe against its BVH ground truth where it has one.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_render::reference::{self, RenderOptions};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind};

use crate::demo_piece::{DemoPiece, section};
use crate::output::{self, Aov};
use crate::progress;

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Scene (built-in name or file).
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// Image width of the planar views.
    #[arg(long, default_value_t = 960)]
    pub width: u32,
    /// Image height of the planar views.
    #[arg(long, default_value_t = 540)]
    pub height: u32,
}

pub fn run(a: &DemoArgs, quiet: bool, shell: &super::run::Shell) -> Result<()> {
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let scene = Scene::load(&a.scene)?;
    let t = Instant::now();
    let bvh = Bvh::try_build(&scene.mesh)?;
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let desc = scene.camera(None)?;
    let (w, h) = (a.width, a.height);
    let opts = CameraOptions {
        focus_distance: Some(6.0),
        aperture_radius: 0.08,
        ..CameraOptions::default()
    };
    // (file, model, width, height, spp, what)
    let views: [(&str, ModelKind, u32, u32, u32, &str); 7] = [
        (
            "pinhole",
            ModelKind::Pinhole,
            w,
            h,
            4,
            "pinhole, with view depth and normals",
        ),
        (
            "thinlens",
            ModelKind::ThinLens,
            w,
            h,
            16,
            "thin lens, focus 6 m, aperture radius 0.08 m",
        ),
        (
            "stereo",
            ModelKind::Stereo,
            w / 2,
            h / 2,
            4,
            "stereo pair, side by side",
        ),
        (
            "fisheye_210x130",
            ModelKind::Fisheye,
            w,
            w * 130 / 210,
            4,
            "fisheye, 210 x 130 deg",
        ),
        (
            "equirect",
            ModelKind::Equirect,
            w,
            w / 2,
            4,
            "equirectangular, the whole sphere",
        ),
        (
            "cube",
            ModelKind::Cube,
            h / 2,
            h / 2,
            4,
            "cube map, six faces side by side",
        ),
        (
            "hmd_distorted",
            ModelKind::Distorted,
            w / 2,
            h,
            4,
            "HMD pincushion distortion, per colour channel",
        ),
    ];
    if !quiet {
        println!(
            "{}: {} triangles, BVH built in {:.1} ms",
            scene.name,
            scene.mesh.triangle_count(),
            build_ms
        );
        println!("| piece | what | size | spp | Mrays/s | ms | files |");
        println!("|---|---|---|---|---|---|---|");
    }
    let mut pieces: Vec<DemoPiece> = Vec::new();
    let mut show = |p: DemoPiece| {
        if !quiet {
            println!("{}", p.row(&a.out));
        }
        pieces.push(p);
    };
    for (name, model, vw, vh, spp, what) in views {
        let camera = Camera::new(model, &desc, vw.max(1), vh.max(1), &opts)?;
        let (cw, ch) = (camera.width(), camera.height());
        let pb = progress::bar(cw as u64 * ch as u64, name, quiet);
        let t = Instant::now();
        let ro = RenderOptions {
            spp,
            seed: 1,
            gbuffer: model == ModelKind::Pinhole,
        };
        let out = reference::render(&scene, &bvh, &camera, &ro, &|n| pb.inc(n));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        pb.finish_and_clear();
        let aovs = if ro.gbuffer {
            vec![Aov::Depth, Aov::Normal]
        } else {
            vec![]
        };
        output::write_render(
            &a.out.join(format!("{name}.png")),
            &out.image,
            out.gbuffer.as_ref(),
            &aovs,
        )?;
        let mut images = vec![format!("{name}.png")];
        if ro.gbuffer {
            images.extend([format!("{name}.depth.png"), format!("{name}.normal.png")]);
        }
        show(DemoPiece {
            label: name.into(),
            section: section::CAMERAS,
            title: format!("{} camera", model.name()),
            what: format!("{what}; {spp} samples per pixel, direct light with shadows"),
            size: format!("{cw}x{ch}"),
            spp: spp.to_string(),
            mrays: Some(out.rays as f64 / (ms * 1e3)),
            ms,
            images,
            truth: None,
        });
    }
    show(super::path::demo_view(&scene, &desc, w, h, &a.out, quiet)?);
    show(super::bench_dirt::demo_view(&scene, &desc, w, h, &a.out)?);
    show(stereo_pair(&scene, &bvh, &desc, w, h, &a.out)?);
    for p in super::demo_synth::synth_views(&a.scene, w / 2, h / 2, &a.out, shell)? {
        show(p);
    }
    show(super::reflect::demo_reflect(&a.out, w / 2, h / 2)?);
    show(vr_frame(a, &scene, &bvh, &desc)?);
    show(super::secondary::demo_secondary(&a.out, w / 2, h / 2)?);
    show(super::reproject::demo_reproject(
        &a.scene,
        w / 6,
        h / 6,
        &a.out,
    )?);
    // The papers' techniques first, the reference renderer's camera models after them.
    pieces.sort_by_key(|p| p.section == section::CAMERAS);
    let items: Vec<_> = pieces.iter().map(DemoPiece::gallery_item).collect();
    let intro = format!(
        "What parallax renders, on the {} scene ({} triangles): every technique of the five papers beside the exact BVH ray tracer it is scored against. Drag a slider to compare a result with its ground truth; the heatmap beside it shows where they differ. Regenerate with `parallax demo`.",
        scene.name,
        scene.mesh.triangle_count()
    );
    let page = parallax_experiment::report::write_captioned_gallery(
        &a.out,
        "parallax demo",
        &intro,
        &items,
    )?;
    if !quiet {
        println!("images in {}, page {}", a.out.display(), page.display());
    }
    Ok(())
}

/// The HVVR frame of the demo: both eyes of a Rift CV1 rendered directly into the distorted
/// display pattern, one ray set per colour channel (subpixel), 8x MSAA,
/// and a foveated pattern around the centre of each eye, visibility by the beam caster.
fn vr_frame(
    a: &DemoArgs,
    scene: &Scene,
    bvh: &Bvh,
    head: &parallax_scene::CameraDesc,
) -> Result<DemoPiece> {
    use parallax_core::image::png::{self, ToneMapping, Tonemap};
    use parallax_vr::frame::{EyeState, FrameOptions, Visibility, render_eye_with};
    use parallax_vr::presets::{Preset, eye_cameras};
    use parallax_vr::reconstruct::pattern_image;
    use parallax_vr::resolve::ShadingMode;
    use parallax_vr::shade::ShadeOptions;

    let mut spec = Preset::RiftCv1.spec();
    spec.width = (a.width / 2).max(1);
    spec.height = a.height.max(1);
    let opts = FrameOptions {
        spp: 8,
        mode: ShadingMode::Msaa,
        visibility: Visibility::Beam,
        shade: ShadeOptions { shadows: true },
    };
    let tm = ToneMapping {
        exposure: 0.0,
        tonemap: Tonemap::AcesFilmic,
    };
    let t = Instant::now();
    let mut rays = 0u64;
    let mut shades = 0u64;
    let mut nonempty = 0u64;
    let [l, r] = eye_cameras(&spec, head, None)?;
    // The head turned by 5 degrees for a next frame of the left eye: its hierarchy moved, not
    // rebuilt (HVVR §5.1).
    let [l_next, _] = eye_cameras(&spec, &head.turned(5.0), None)?;
    let mut left = EyeState::moving();
    let (mut built_ms, mut moved_ms) = (0.0, 0.0);
    for (name, cam) in [
        ("vr_rift_left", l),
        ("vr_rift_right", r),
        ("vr_rift_left_turned", l_next),
    ] {
        let set = parallax_vr::patterns::eye_set(cam, opts.spp, true, Some([0.0, 0.0]))?;
        let mut own = EyeState::new();
        let state = if name == "vr_rift_right" {
            &mut own
        } else {
            &mut left
        };
        let eye = render_eye_with(scene, bvh, set, &opts, state)?;
        match name {
            "vr_rift_left" => built_ms = eye.timings.hierarchy_ms,
            "vr_rift_left_turned" => moved_ms = eye.timings.hierarchy_ms,
            _ => {}
        }
        png::write_png(a.out.join(format!("{name}.png")), &eye.image, &tm)?;
        if name == "vr_rift_left" {
            png::write_png(
                a.out.join("vr_rift_pattern.png"),
                &pattern_image(&eye.set),
                &ToneMapping::default(),
            )?;
        }
        rays += eye.set.ray_count() as u64;
        shades += eye.resolved.shades;
        nonempty += eye.resolved.nonempty;
        if name == "vr_rift_left" {
            // The turned frame writes over this frame's visibility buffer.
            left.recycle(eye);
        }
    }
    let ms = t.elapsed().as_secs_f64() * 1e3;
    Ok(DemoPiece {
        label: "vr_rift_left/right".into(),
        section: section::HVVR,
        title: "A foveated VR frame, cast with beams".into(),
        what: format!(
            "both eyes of a Rift CV1 rendered straight into the distorted display pattern, one ray set per colour channel, foveated around the centre, 8x MSAA, visibility by the beam caster ({:.2} shades per pixel); then the left eye's next frame with the head turned 5 degrees, its tile and block beams moved in {moved_ms:.2} ms instead of rebuilt ({built_ms:.1} ms); the last image shows the sample pattern",
            shades as f64 / nonempty.max(1) as f64
        ),
        size: format!("3x {}x{}", spec.width, spec.height),
        spp: "8".into(),
        mrays: Some(rays as f64 / (ms * 1e3)),
        ms,
        images: [
            "vr_rift_left.png",
            "vr_rift_right.png",
            "vr_rift_left_turned.png",
            "vr_rift_pattern.png",
        ]
        .map(String::from)
        .to_vec(),
        truth: None,
    })
}

/// The demo's stereo pair: the cyclopean view warped to both eyes (ipd 0.065, 2 layers) with
/// the quad-tree, beside the BVH's renders of the two eyes.
fn stereo_pair(
    scene: &parallax_scene::Scene,
    bvh: &Bvh,
    desc: &parallax_scene::CameraDesc,
    w: u32,
    h: u32,
    out: &std::path::Path,
) -> Result<DemoPiece> {
    use parallax_scene::camera::Pinhole;
    use parallax_synth::bench::warp::{StereoSetup, eye_truths, score_pair};
    use parallax_synth::method::{Method, MethodOptions};
    use parallax_synth::{Shading, capture_reference, stereo::warp_stereo};

    let method = Method::QuadTree;
    let (ipd, seed) = (0.065, 1);
    let cam = Pinhole::new(desc, w, h)?;
    let mut r = capture_reference(scene, bvh, &cam, 2, Shading::Fixed, seed)?;
    let sv = warp_stereo(&mut r, desc, ipd, method, &MethodOptions::default())?;
    let ms = r.times.total_ms() + 2.0 * sv.ms_eye();
    let setup = StereoSetup {
        desc: *desc,
        width: w,
        height: h,
        ipd,
        shading: Shading::Fixed,
        seed,
        score: true,
        repeats: 1,
    };
    let truths = eye_truths(scene, bvh, &setup)?;
    let s = score_pair(&sv, &truths)?;
    let names = [
        "stereo_warp_left.png",
        "stereo_warp_left_bvh.png",
        "stereo_warp_right.png",
        "stereo_warp_right_bvh.png",
    ];
    let images = [
        &sv.views[0].image,
        &truths[0],
        &sv.views[1].image,
        &truths[1],
    ];
    for (name, img) in names.iter().zip(images) {
        output::write_png(&out.join(name), img)?;
    }
    Ok(DemoPiece {
        label: format!("stereo warp ({method}, 2 layers)"),
        section: section::WIDMER,
        title: "Stereo warping (§5.1)".into(),
        what: format!(
            "one 2-layer pinhole capture warped to both eyes ({ipd} m apart) by tracing each eye's rays through the quad-tree; vs the BVH's eye views: PSNR {:.2} dB, SSIM {:.4} (mean of both eyes)",
            s.psnr, s.ssim
        ),
        size: format!("{w}x{h} x2"),
        spp: "1".into(),
        mrays: None,
        ms,
        images: vec![names[0].into(), names[2].into(), names[3].into()],
        truth: Some(names[1].into()),
    })
}
