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

pub fn run(a: &DemoArgs, quiet: bool) -> Result<()> {
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
    super::warp::demo_stereo(&scene, &bvh, &desc, w, h, &a.out, quiet)?;
    if !quiet {
        println!("images in {}", a.out.display());
    }
    Ok(())
}
