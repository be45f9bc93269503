//! `parallax demo`: the README's first command. Renders the built-in atrium through several
//! camera models into a folder and prints a summary table.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_render::reference::{self, RenderOptions};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel, CameraOptions, ModelKind};

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
    // (file, model, width, height, spp)
    let views: [(&str, ModelKind, u32, u32, u32); 7] = [
        ("pinhole", ModelKind::Pinhole, w, h, 4),
        ("thinlens", ModelKind::ThinLens, w, h, 16),
        ("stereo", ModelKind::Stereo, w / 2, h / 2, 4),
        ("fisheye_210x130", ModelKind::Fisheye, w, w * 130 / 210, 4),
        ("equirect", ModelKind::Equirect, w, w / 2, 4),
        ("cube", ModelKind::Cube, h / 2, h / 2, 4),
        ("hmd_distorted", ModelKind::Distorted, w / 2, h, 4),
    ];
    if !quiet {
        println!(
            "{}: {} triangles, BVH built in {:.1} ms",
            scene.name,
            scene.mesh.triangle_count(),
            build_ms
        );
        println!("| view | model | size | spp | Mrays/s | ms | file |");
        println!("|---|---|---|---|---|---|---|");
    }
    for (name, model, vw, vh, spp) in views {
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
        let path = a.out.join(format!("{name}.png"));
        let aovs = if ro.gbuffer {
            vec![Aov::Depth, Aov::Normal]
        } else {
            vec![]
        };
        output::write_render(&path, &out.image, out.gbuffer.as_ref(), &aovs)?;
        if !quiet {
            println!(
                "| {name} | {} | {cw}x{ch} | {spp} | {:.1} | {:.0} | {} |",
                model.name(),
                out.rays as f64 / (ms * 1e3),
                ms,
                path.display()
            );
        }
    }
    super::path::demo_view(&scene, &desc, w, h, &a.out, quiet)?;
    super::bench_dirt::demo_view(&scene, &desc, w, h, &a.out, quiet)?;
    super::reflect::demo_reflect(&a.out, w / 2, h / 2, quiet)?;
    super::demo_synth::synth_views(&a.scene, w / 2, h / 2, &a.out, shell, quiet)?;
    vr_frame(a, &scene, &bvh, &desc, quiet)?;
    stereo_pair(&scene, &bvh, &desc, w, h, &a.out, quiet)?;
    super::secondary::demo_secondary(&a.out, w / 2, h / 2, quiet)?;
    super::reproject::demo_reproject(&a.scene, w / 6, h / 6, &a.out, quiet)?;
    let page = parallax_experiment::report::write_gallery(&a.out, "parallax demo")?;
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
    quiet: bool,
) -> Result<()> {
    use parallax_core::image::png::{self, ToneMapping, Tonemap};
    use parallax_vr::frame::{FrameOptions, Visibility, render_eye_set};
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
    for (name, cam) in [("vr_rift_left", l), ("vr_rift_right", r)] {
        let set = parallax_vr::patterns::eye_set(cam, opts.spp, true, Some([0.0, 0.0]))?;
        let eye = render_eye_set(scene, bvh, set, &opts)?;
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
    }
    let ms = t.elapsed().as_secs_f64() * 1e3;
    if !quiet {
        println!(
            "| vr_rift_left/right | hvvr rift-cv1 subpixel foveated, 8x MSAA ({:.2} shades/px) | 2x {}x{} | 8 | {:.1} | {:.0} | {} |",
            shades as f64 / nonempty.max(1) as f64,
            spec.width,
            spec.height,
            rays as f64 / (ms * 1e3),
            ms,
            a.out.join("vr_rift_left.png").display()
        );
    }
    Ok(())
}

/// The demo's stereo pair: the cyclopean view warped to both eyes (ipd 0.065, 2 layers) with
/// the quad-tree.
fn stereo_pair(
    scene: &parallax_scene::Scene,
    bvh: &Bvh,
    desc: &parallax_scene::CameraDesc,
    w: u32,
    h: u32,
    out: &std::path::Path,
    quiet: bool,
) -> Result<()> {
    use parallax_scene::camera::Pinhole;
    use parallax_synth::method::{Method, MethodOptions};
    use parallax_synth::{Shading, capture_reference, stereo::warp_stereo};

    let method = Method::QuadTree;
    let cam = Pinhole::new(desc, w, h)?;
    let mut r = capture_reference(scene, bvh, &cam, 2, Shading::Fixed, 1)?;
    let sv = warp_stereo(&mut r, desc, 0.065, method, &MethodOptions::default())?;
    let left = output::write_png(&out.join("stereo_warp_left.png"), &sv.views[0].image)?;
    let right = output::write_png(&out.join("stereo_warp_right.png"), &sv.views[1].image)?;
    if !quiet {
        println!(
            "| stereo warp ({method}, 2 layers) | pinhole | {w}x{h} x2 | - | - | {:.0} | {}, {} |",
            r.times.total_ms() + 2.0 * sv.ms_eye(),
            left.display(),
            right.display()
        );
    }
    Ok(())
}
