//! `parallax upsample`: 15 -> 60 Hz temporal upsampling along the scene's camera path
//! (Widmer et al. 2015, §5.1, Table 3): every 4th frame is a rendered reference with N layers,
//! the frames in between are synthesised from the previous reference with the chosen method.
//! Writes `frame_NNNN.png` (and `frame_NNNN.hits.png` for synthesised frames), prints timings
//! and the mean PSNR / SSIM of the synthesised frames against the BVH render of their cameras
//! (`--truth` also writes that render as `frame_NNNN.bvh.png`). `--shard I/N` (or a Slurm /
//! Kubernetes array index) renders the I-th of N contiguous blocks of reference groups and a
//! `shard.json`; `parallax merge` joins the shards' folders into the unsharded output.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use parallax_bvh::Bvh;
use parallax_core::image::png;
use parallax_experiment::Shard;
use parallax_experiment::results::{MANIFEST_FILE, ShardManifest, write_json};
use parallax_render::score::{SCORE_TONEMAP, ground_truth, score};
use parallax_synth::method::cube_near_name;
use parallax_synth::upsample::{UpsampleOptions, default_path, scene_path, upsample_range};

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
    /// Also write the BVH ground truth of each synthesised frame (frame_NNNN.bvh.png).
    #[arg(long, conflicts_with = "no_score")]
    pub truth: bool,
    /// Render part I of N (0-based) of the frames: contiguous blocks of whole reference
    /// groups. Without it, SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT or
    /// JOB_COMPLETION_INDEX (+ --shard-count) when set.
    #[arg(long)]
    pub shard: Option<String>,
    /// Shard count for an environment index without its own count (Kubernetes Indexed Jobs).
    #[arg(long)]
    pub shard_count: Option<usize>,
}

pub fn run(a: &UpsampleArgs, quiet: bool) -> Result<()> {
    let opts = a.synth.upsample_options()?;
    a.size.check_memory(a.choice.capture_layers())?;
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
    let shard = Shard::from_flags(a.shard.as_deref(), a.shard_count)?;
    let groups = a.frames.div_ceil(uo.period) as usize;
    let (range, blocks) = match shard {
        Some(s) => {
            let b = s.block(groups);
            let end = (b.end as u32 * uo.period).min(a.frames);
            (b.start as u32 * uo.period..end, b)
        }
        None => (0..a.frames, 0..groups),
    };
    let pb = progress::bar(range.len() as u64, "upsample", quiet);
    let (mut psnr, mut ssim, mut scored) = (0.0, 0.0, 0u32);
    let methods = [(uo.method, uo.method_opts)];
    let times = upsample_range(
        &scene,
        &bvh,
        &path,
        a.size.width,
        a.size.height,
        &uo,
        &methods,
        range.clone(),
        &mut |_, f| {
            let p = a.out.join(format!("frame_{:04}.png", f.index));
            png::write_png(&p, f.image(), &SCORE_TONEMAP)?;
            if let Some(v) = &f.view {
                let h = a.out.join(format!("frame_{:04}.hits.png", f.index));
                png::write_png(&h, &v.hit_type_image(), &SCORE_TONEMAP)?;
                if !a.synth.no_score {
                    let truth = ground_truth(&scene, &bvh, &f.camera, uo.shading, a.synth.seed);
                    if a.truth {
                        let t = a.out.join(format!("frame_{:04}.bvh.png", f.index));
                        png::write_png(&t, &truth, &SCORE_TONEMAP)?;
                    }
                    let s = score(&v.image, &truth)?;
                    psnr += s.psnr;
                    ssim += s.ssim;
                    scored += 1;
                }
            }
            pb.inc(1);
            Ok(())
        },
    )
    .pop()
    .expect("one result per method")?;
    pb.finish_and_clear();
    if let Some(s) = shard {
        let m = ShardManifest {
            kind: "upsample".into(),
            shard: s,
            total: groups,
            items: blocks.collect(),
            results: None,
        };
        write_json(&a.out.join(MANIFEST_FILE), &m)?;
    }
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
        let amt = (refs.iter().sum::<f64>() + syns.iter().sum::<f64>()) / times.len().max(1) as f64;
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
