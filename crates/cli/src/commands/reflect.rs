//! `parallax reflect` and `parallax bench reflect`: specular and glossy reflections traced
//! through a cube map of colour + depth layers at the camera, one quad-tree (or DDA) per face
//! (Widmer et al. 2015, §5.4, Table 5, Figs. 11-13), scored against the same reflections
//! traced with the BVH. `--spp N` (a square `s x s`) renders `s x s` primary rays per pixel
//! (the view captured at `s` times its size) and box-filters them; the BVH truth is the same
//! rays with the same filter.

use std::path::PathBuf;

use anyhow::{Context, Result, ensure};
use clap::Args;
use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::image::png;
use parallax_render::score::{SCORE_TONEMAP, Shading, score};
use parallax_scene::CameraDesc;
use parallax_scene::camera::Pinhole;
use parallax_synth::bench::reflect::{self as bench_reflect, ReflectBench, ReflectRow, TABLE5};
use parallax_synth::dof::truth::masked_psnr;
use parallax_synth::lightfield::{spp_side, supersampled};
use parallax_synth::method::Method;
use parallax_synth::reflect::{
    BvhReflector, CubeAt, CubeMaps, CubeReflector, ReflectOptions, ReflectionCube, TruthColour,
    render_reflections,
};
use parallax_synth::{MethodOptions, capture_reference};

use super::bench_synth::{cell, reporter};
use crate::args::{SynthArgs, ViewArgs, layer_count};
use crate::demo_piece::{DemoPiece, section};
use crate::output::write_json;

/// DDA max steps of the reflection commands when `--dda-max-steps` is not given: the face
/// size in pixels (a ray crosses a face in up to ~1.4 face sizes of steps; measured minimal
/// artifact-free value with `bench reflect --dda-sweep`: docs/notes/synth.md).
pub fn dda_max_steps_reflect(face: u32) -> u32 {
    face.max(1)
}

/// Flags of the reflection renderer shared by `reflect` and `bench reflect`.
#[derive(Args, Clone, Debug)]
pub struct ReflectArgs {
    /// Cube map face size in pixels (the paper: 1024).
    #[arg(long, default_value_t = 512)]
    pub face: u32,
    /// Width of the extra samples' depth weight (relative depth, > 0).
    #[arg(long, default_value_t = parallax_synth::dof::DEFAULT_SIGMA)]
    pub sigma: f32,
    /// Reflection rays start this many cube-face pixel footprints off their surface (>= 0).
    #[arg(long, default_value_t = 1.5)]
    pub offset_px: f32,
    /// Relative thickness of the cube map's surfaces: a ray passing behind a surface at depth
    /// d further than d x (1 + THICKNESS) goes on instead of ending in its occlusion volume
    /// (default: occlusion volumes are final, as in the paper).
    #[arg(long)]
    pub thickness: Option<f32>,
    /// Extra samples whose plane-lookup weight is below this (0..=1) are traced through the
    /// cube map as paths instead (0: never, the paper's lookups).
    #[arg(long, default_value_t = 0.0)]
    pub trace_below: f32,
    /// Where the cube maps are: camera (the paper: one cube map at the eye) or objects (NOT
    /// the paper's method: one cube map at the centre of each reflective object's bounding
    /// box, Umenhoffer et al. 2007; a ray is traced in the cube map of the object it leaves).
    #[arg(long, default_value = "camera", value_parser = parse_cube_at)]
    pub cube_at: CubeAt,
    /// Also score against the physical truth: every BVH hit coloured by its radiance along the
    /// reflection ray (not the paper's measurement; the default truth colours hits towards
    /// the cube map's centre, as a cube-map sample holds them).
    #[arg(long)]
    pub physical_truth: bool,
}

fn parse_cube_at(s: &str) -> Result<CubeAt, String> {
    s.parse()
        .map_err(|e: parallax_synth::SynthError| e.to_string())
}

impl ReflectArgs {
    fn thickness(&self) -> Result<Option<f32>> {
        if let Some(t) = self.thickness {
            anyhow::ensure!(
                t.is_finite() && t > 0.0,
                "--thickness must be finite and > 0, got {t}"
            );
        }
        Ok(self.thickness)
    }

    fn options(&self, seed: u64, n_p: u32, n_s: u32, n_b: u32) -> Result<ReflectOptions> {
        let o = ReflectOptions {
            n_p,
            n_s,
            n_b,
            sigma: self.sigma,
            offset_px: self.offset_px,
            trace_below: self.trace_below,
            seed,
        };
        o.validate()?;
        Ok(o)
    }
}

#[derive(Args, Debug)]
pub struct ReflectCmdArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub reflect: ReflectArgs,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Depth layers of the cube map (1..=8).
    #[arg(long, default_value_t = 2, value_parser = layer_count)]
    pub layers: usize,
    /// quadtree or dda (in every cube face).
    #[arg(long, default_value = "quadtree", value_parser = crate::args::parse_method)]
    pub method: Method,
    /// Reflection rays per reflective pixel (N_p).
    #[arg(long, default_value_t = 3)]
    pub n_p: u32,
    /// Extra samples per glossy ray (N_s).
    #[arg(long, default_value_t = 8)]
    pub n_s: u32,
    /// Traced segments per path (N_b).
    #[arg(long, default_value_t = 1)]
    pub n_b: u32,
    /// Primary rays per pixel, a square s x s (1, 4, 9, ...): the view at s times its size,
    /// box-filtered; the BVH truth is the same rays with the same filter.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Output folder.
    #[arg(long, default_value = "out/reflect")]
    pub out: PathBuf,
}

fn method_options(s: &SynthArgs, face: u32) -> Result<MethodOptions> {
    let mut o = s.method_options()?;
    o.dda_max_steps = s.dda_max_steps.unwrap_or(dda_max_steps_reflect(face));
    Ok(o)
}

/// The cube map's eye: the camera's, with world-aligned faces.
fn cube_desc(camera: &Pinhole) -> CameraDesc {
    let eye = camera.frame.position;
    CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0)
}

pub fn run(a: &ReflectCmdArgs, quiet: bool) -> Result<()> {
    ensure!(
        matches!(a.method, Method::QuadTree | Method::Dda),
        "reflections trace the cube map with quadtree or dda, not {}",
        a.method
    );
    let ropts = a.reflect.options(a.synth.seed, a.n_p, a.n_s, a.n_b)?;
    let side = spp_side(a.spp).context("--spp")?;
    let opts = method_options(&a.synth, a.reflect.face)?;
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let camera = Pinhole::new(&a.view.camera_desc(&scene)?, a.width, a.height)?;
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let progress = reporter(quiet);
    progress("view");
    let fine = supersampled(&camera, side);
    let reference = capture_reference(&scene, &bvh, &fine, 1, Shading::Fixed, a.synth.seed)?;
    progress("cube map(s)");
    let eye = camera.frame.position;
    let cubes = CubeMaps::capture(
        &scene,
        &bvh,
        a.reflect.cube_at,
        eye,
        a.reflect.face,
        a.layers,
        a.synth.seed,
    )?;
    if let Some(c) = cubes.centres()
        && !quiet
    {
        for (name, p) in c.names.iter().zip(&c.centres) {
            println!("cube map of {name} at ({:.3}, {:.3}, {:.3})", p.x, p.y, p.z);
        }
    }
    let (reflector, times) = cubes.reflector(&scene, a.method, &opts, a.reflect.thickness()?)?;
    progress("reflections");
    let img = render_reflections(reflector.as_ref(), &reference, eye, a.reflect.face, &ropts)?
        .box_filtered(side)?;
    let mut written = Vec::new();
    let mut save = |name: &str, im: &parallax_core::Image<parallax_core::Rgb>| -> Result<()> {
        let p = a.out.join(name);
        png::write_png(&p, im, &SCORE_TONEMAP)?;
        written.push(p);
        Ok(())
    };
    save("reflect.png", &img.image)?;
    let scored = if a.synth.no_score {
        None
    } else {
        progress("BVH reflections");
        let truth = cubes.truth(&scene, &bvh, eye, a.synth.seed, TruthColour::TowardsCube);
        let t = render_reflections(&truth, &reference, eye, a.reflect.face, &ropts)?
            .box_filtered(side)?;
        save("reflect.bvh.png", &t.image)?;
        let physical = if a.reflect.physical_truth {
            let truth = cubes.truth(&scene, &bvh, eye, a.synth.seed, TruthColour::AlongTheRay);
            let t = render_reflections(&truth, &reference, eye, a.reflect.face, &ropts)?
                .box_filtered(side)?;
            save("reflect.bvh-physical.png", &t.image)?;
            Some(masked_psnr(&img.image, &t.image, &t.mask)?)
        } else {
            None
        };
        Some((
            masked_psnr(&img.image, &t.image, &t.mask)?,
            score(&img.image, &t.image)?,
            t.ms,
            physical,
        ))
    };
    if !quiet {
        for p in &written {
            println!("wrote {}", p.display());
        }
        println!(
            "{} ({} cube map(s) at the {}) {} layer(s), {}x{} ({} spp), faces {}^2, N_p/N_s/N_b {}/{}/{}: T_cm {:.1} ms (capture {:.1}, shade {:.1}, build {:.1}), T_ref {:.1} ms, T_rr {:.1} ms, {} reflective pixels, {:.2} Mrays/s{}",
            reflector.name(),
            cubes.count(),
            cubes.at(),
            a.layers,
            a.width,
            a.height,
            a.spp,
            a.reflect.face,
            a.n_p,
            a.n_s,
            a.n_b,
            times.total_ms(),
            times.capture_ms,
            times.shade_ms,
            times.build_ms,
            reference.times.capture_ms + reference.times.shade_ms,
            img.ms,
            img.reflective_pixels(),
            img.mrays_per_s(),
            if img.lookups > 0 {
                format!(", extra-sample weight {:.3}", img.mean_lookup_weight())
            } else {
                String::new()
            }
        );
        if let Some((p, s, ms, physical)) = scored {
            println!(
                "vs BVH reflections ({ms:.1} ms): PSNR {p:.2} dB over the reflective pixels, {:.2} dB over the image, SSIM {:.4}",
                s.psnr, s.ssim
            );
            if let Some(p) = physical {
                println!(
                    "vs physical BVH reflections (hits coloured along the ray): PSNR {p:.2} dB over the reflective pixels"
                );
            }
        }
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct ReflectBenchArgs {
    #[command(flatten)]
    pub view: ViewArgs,
    #[command(flatten)]
    pub synth: SynthArgs,
    #[command(flatten)]
    pub reflect: ReflectArgs,
    #[arg(long, default_value_t = 1280)]
    pub width: u32,
    #[arg(long, default_value_t = 720)]
    pub height: u32,
    /// Comma list of cube-map layer counts (each 1..=8).
    #[arg(long, value_delimiter = ',', default_value = "1,2", value_parser = layer_count)]
    pub layers: Vec<usize>,
    /// N_p/N_s/N_b configurations as a comma list of p/s/b (default: Table 5's).
    #[arg(long, value_delimiter = ',')]
    pub configs: Vec<String>,
    /// Comma list of primary rays per pixel, each a square s x s (1, 4, 9, ...): one set of
    /// rows per value, the view at s times its size box-filtered, the BVH truth the same
    /// rays with the same filter.
    #[arg(long, value_delimiter = ',', default_value = "1")]
    pub spp: Vec<u32>,
    /// DDA: one set of rows per max-steps value of this comma list instead of
    /// --dda-max-steps.
    #[arg(long, value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=10_000_000))]
    pub dda_sweep: Vec<u32>,
    /// Leave out the quad-tree rows (e.g. for a DDA sweep alone).
    #[arg(long)]
    pub no_quadtree: bool,
    /// Interleaved timing rounds (the best is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// A `p/s/b` configuration.
fn parse_config(s: &str) -> Result<(u32, u32, u32)> {
    let v: Vec<u32> = s
        .split('/')
        .map(|t| t.trim().parse::<u32>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("configuration {s:?}: expected N_p/N_s/N_b, e.g. 3/8/1"))?;
    ensure!(
        v.len() == 3,
        "configuration {s:?}: expected N_p/N_s/N_b, e.g. 3/8/1"
    );
    Ok((v[0], v[1], v[2]))
}

pub fn bench(a: &ReflectBenchArgs, quiet: bool) -> Result<()> {
    let configs = if a.configs.is_empty() {
        TABLE5.to_vec()
    } else {
        a.configs
            .iter()
            .map(|s| parse_config(s))
            .collect::<Result<_>>()?
    };
    for &(p, s, b) in &configs {
        a.reflect.options(a.synth.seed, p, s, b)?;
    }
    for &n in &a.spp {
        spp_side(n).context("--spp")?;
    }
    let opts = method_options(&a.synth, a.reflect.face)?;
    let dda_steps = if a.dda_sweep.is_empty() {
        vec![opts.dda_max_steps]
    } else {
        a.dda_sweep.clone()
    };
    let scene = a.view.load_scene()?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let camera = Pinhole::new(&a.view.camera_desc(&scene)?, a.width, a.height)?;
    let b = ReflectBench {
        camera,
        face: a.reflect.face,
        layers: a.layers.clone(),
        configs,
        spp: a.spp.clone(),
        dda_steps,
        quadtree: !a.no_quadtree,
        opts,
        reflect: a.reflect.options(a.synth.seed, 1, 0, 1)?,
        repeats: a.repeats.max(1),
        thickness: a.reflect.thickness()?,
        cube_at: a.reflect.cube_at,
        physical_truth: a.reflect.physical_truth,
    };
    let rows = bench_reflect::run(&scene, &bvh, &b, &reporter(quiet))?;
    if !quiet {
        println!(
            "{} {}x{}, cube map(s) at the {}, cube faces {}^2, sigma {}, offset {} px, thickness {}, {} threads, best of {} interleaved rounds\n",
            scene.name,
            a.width,
            a.height,
            b.cube_at,
            a.reflect.face,
            a.reflect.sigma,
            a.reflect.offset_px,
            b.thickness
                .map_or("none (occlusion volumes)".to_string(), |t| t.to_string()),
            rayon::current_num_threads(),
            b.repeats
        );
        print_rows(&rows);
    }
    write_json(a.json.as_deref(), &rows)
}

fn print_rows(rows: &[ReflectRow]) {
    println!(
        "| method | layers | N_p/N_s/N_b | spp | dda steps | T_cm ms | T_ref ms | T_rr ms | T_rr CPU ms | FPS | Mrays/s | rays/px | nodes/ray | % cut | extra weight | trace-only Mrays/s | hit agreement | PSNR refl. dB | PSNR refl. phys. dB | PSNR image dB | SSIM |"
    );
    println!(
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in rows {
        println!(
            "| {} | {} | {}/{}/{} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.1} | {:.2} | {} | {:.2} | {:.3} | {} | {} | {} | {:.4} |",
            r.method,
            r.layers,
            r.n_p,
            r.n_s,
            r.n_b,
            r.spp,
            r.dda_max_steps.map_or("-".into(), |n| n.to_string()),
            cell(r.ms_cm, 1),
            r.ms_ref,
            r.ms_rr,
            r.ms_rr_cpu,
            r.fps,
            r.mrays_per_s,
            r.rays_per_pixel,
            r.nodes_per_ray,
            r.pct_truncated,
            r.lookup_weight.map_or("-".into(), |w| format!("{w:.3}")),
            r.trace_mrays_per_s,
            r.agreement,
            if r.method == "bvh" {
                "(truth)".into()
            } else {
                format!("{:.2}", r.psnr)
            },
            r.psnr_physical.map_or("-".into(), |p| format!("{p:.2}")),
            if r.method == "bvh" {
                "(truth)".into()
            } else {
                format!("{:.2}", r.psnr_image)
            },
            r.ssim
        );
    }
}

/// The demo's reflections: the `mirrors` room at `width x height`, a 2-layer cube map of
/// 256^2 faces, quad-tree per face, N_p/N_s/N_b 3/8/1, scored against the BVH's reflections
/// of the same rays.
pub fn demo_reflect(out: &std::path::Path, width: u32, height: u32) -> Result<DemoPiece> {
    let t = std::time::Instant::now();
    let scene = parallax_scene::Scene::load("mirrors")?;
    let bvh = Bvh::try_build(&scene.mesh)?;
    let camera = Pinhole::new(&scene.camera(None)?, width.max(1), height.max(1))?;
    let face = 256;
    let reference = capture_reference(&scene, &bvh, &camera, 1, Shading::Fixed, 0)?;
    let cube = ReflectionCube::capture(&scene, &bvh, &cube_desc(&camera), face, 2, 0)?;
    let opts = MethodOptions::default();
    let reflector = CubeReflector::build(&scene, &cube, Method::QuadTree, &opts)?;
    let ropts = ReflectOptions {
        n_p: 3,
        n_s: 8,
        n_b: 1,
        ..ReflectOptions::default()
    };
    let eye = camera.frame.position;
    let img = render_reflections(&reflector, &reference, eye, face, &ropts)?;
    let truth = BvhReflector::new(&scene, &bvh, eye, 0);
    let t_img = render_reflections(&truth, &reference, eye, face, &ropts)?;
    png::write_png(out.join("reflect_cubemap.png"), &img.image, &SCORE_TONEMAP)?;
    png::write_png(out.join("reflect_bvh.png"), &t_img.image, &SCORE_TONEMAP)?;
    let p = masked_psnr(&img.image, &t_img.image, &t_img.mask)?;
    Ok(DemoPiece {
        label: "reflect_cubemap".into(),
        section: section::WIDMER,
        title: "Cube-map reflections (§5.4)".into(),
        what: format!(
            "built-in mirrors room: reflections traced through a 2-layer cube map at the eye, one quad-tree per face, N_p/N_s/N_b 3/8/1, vs the same rays through the BVH ({p:.2} dB over the mirrors)"
        ),
        size: format!("{}x{}", camera.width, camera.height),
        spp: "3/8/1".into(),
        mrays: Some(img.mrays_per_s()),
        ms: t.elapsed().as_secs_f64() * 1e3,
        images: vec!["reflect_cubemap.png".into()],
        truth: Some("reflect_bvh.png".into()),
    })
}
