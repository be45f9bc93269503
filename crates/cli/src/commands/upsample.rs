//! `parallax upsample`: 15 -> 60 Hz temporal upsampling along the scene's camera path
//! (Widmer et al. 2015, §5.1, Table 3): every 4th frame is a rendered reference with N layers,
//! the frames in between are synthesised from the previous reference with the chosen method.
//! Writes `frame_NNNN.png` (and `frame_NNNN.hits.png` for synthesised frames), prints timings
//! and the mean PSNR / SSIM of the synthesised frames against the BVH render of their cameras.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::png;
use parallax_render::score::{SCORE_TONEMAP, ground_truth, score};
use parallax_synth::method::cube_near_name;
use parallax_synth::upsample::{UpsampleOptions, default_path, scene_path, upsample};

use crate::args::{MethodArgs, SynthArgs, SynthSize, ViewArgs, frame_count};
use crate::progress;

#[derive(Args, Debug)]
pub struct UpsampleArgs {
    /// Scene; --eye/--target (or --camera) replace its camera path by a short dolly from that view.
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub size: SynthSize,
    #[command(flatten)]
    pub choice: MethodArgs,
    /// Output frames at 60 Hz (1..=100000).
    #[arg(long, default_value_t = 60, allow_negative_numbers = true, value_parser = frame_count)]
    pub frames: u32,
    /// Output folder.
    #[arg(long, default_value = "out/upsample")]
    pub out: PathBuf,
}

pub fn run(a: &UpsampleArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.upsample_options()?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let path = if a.view.eye.is_some() || a.view.camera.is_some() {
        default_path(&a.view.camera_desc(&scene)?)?
    } else {
        scene_path(&scene)?
    };
    let uo = UpsampleOptions {
        frames: a.frames,
        fps: 60.0,
        period: 4,
        layers: a.choice.capture_layers(),
        method: a.choice.method,
        method_opts: opts,
        shading: a.synth.shading(),
        seed: a.synth.seed,
    };
    let pb = progress::bar(a.frames as u64, "upsample", quiet);
    let (mut psnr, mut ssim, mut scored) = (0.0, 0.0, 0u32);
    let times = upsample(
        &scene,
        &bvh,
        &path,
        a.size.width,
        a.size.height,
        &uo,
        &mut |f| {
            let p = a.out.join(format!("frame_{:04}.png", f.index));
            png::write_png(&p, f.image(), &SCORE_TONEMAP)?;
            if let Some(v) = &f.view {
                let h = a.out.join(format!("frame_{:04}.hits.png", f.index));
                png::write_png(&h, &v.hit_type_image(), &SCORE_TONEMAP)?;
                if !a.synth.no_score {
                    let truth = ground_truth(&scene, &bvh, &f.camera, uo.shading, a.synth.seed);
                    let s = score(&v.image, &truth)?;
                    psnr += s.psnr;
                    ssim += s.ssim;
                    scored += 1;
                }
            }
            pb.inc(1);
            Ok(())
        },
    )?;
    pb.finish_and_clear();
    if !quiet {
        let refs: Vec<f64> = times
            .iter()
            .filter(|t| t.is_reference)
            .map(|t| t.ms_ref)
            .collect();
        let syns: Vec<f64> = times
            .iter()
            .filter(|t| !t.is_reference)
            .map(|t| t.ms_syn)
            .collect();
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
        let amt = (refs.iter().sum::<f64>() + syns.iter().sum::<f64>()) / times.len() as f64;
        println!("wrote {} frames to {}", times.len(), a.out.display());
        println!(
            "{} {} layer(s) {}x{}, cube near {}: {} references, T_ref {:.1} ms; {} synthesised, T_syn {:.1} ms; amortised {:.1} ms/frame",
            a.choice.method,
            uo.layers,
            a.size.width,
            a.size.height,
            cube_near_name(uo.method_opts.cube_near),
            refs.len(),
            mean(&refs),
            syns.len(),
            mean(&syns),
            amt
        );
        if scored > 0 {
            println!(
                "synthesised frames vs BVH: mean PSNR {:.2} dB, mean SSIM {:.4}",
                psnr / scored as f64,
                ssim / scored as f64
            );
        }
    }
    Ok(())
}
