//! `parallax`: the command-line front end. Subcommands live in [`commands`], one file each;
//! shared flags (scene, camera) in [`args`].

mod args;
mod commands;
mod demo_piece;
mod output;
mod progress;

use clap::{Parser, Subcommand};

/// Image-space ray tracing and flexible ray casting, measured against an exact BVH ground truth.
#[derive(Parser)]
#[command(name = "parallax", version, about, long_about = None)]
struct Cli {
    /// Print nothing but errors (no progress bars, no summaries).
    #[arg(long, global = true)]
    quiet: bool,
    /// Worker threads (default: all cores).
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with the exact BVH reference renderer.
    Render(commands::render::RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Print triangles, bounds, materials, lights and cameras of a scene.
    Info(commands::info::InfoArgs),
    /// Rasterized captures (depth layers, stereo, cube, DIRT) as EXR layers + PNG previews.
    Capture(commands::capture::CaptureArgs),
    /// Render the built-in atrium with several camera models into a folder.
    Demo(commands::demo::DemoArgs),
    /// One HVVR frame for a headset preset: both eyes, MSAA/SSAA, distortion, DoF.
    Vr(commands::vr::VrArgs),
    /// Stereo warping of a reference view by screen-space ray tracing (Widmer et al. 2015).
    Warp(commands::warp::WarpArgs),
    /// 15 -> 60 Hz temporal upsampling by screen-space ray tracing (Widmer et al. 2015).
    Upsample(commands::upsample::UpsampleArgs),
    /// Path-traced render (unidirectional, NEE + MIS) through any world-space tracer.
    Path(commands::path::PathArgs),
    /// Reflections, refractions and shadows through any world-space tracer (LDC vs BVH).
    Secondary(commands::secondary::SecondaryArgs),
    /// Thin-lens depth of field by screen-space ray tracing through layers (Widmer et al. 2015).
    Dof(commands::dof::DofArgs),
    /// Light fields through layers: a Looking Glass quilt or near-eye elemental images (Widmer et al. 2015).
    Lightfield(commands::lightfield::LightFieldArgs),
    /// Path-traced stereo with stereo and temporal sample reprojection (Mäkitalo et al. 2019).
    Reproject(commands::reproject::ReprojectArgs),
    /// Reflections traced through a cube map's per-face quad-trees (Widmer et al. 2015, §5.4).
    Reflect(commands::reflect::ReflectCmdArgs),
    /// Benchmarks that reproduce the papers' and issues' measurements.
    #[command(subcommand)]
    Bench(commands::bench::BenchCommand),
    /// Run a TOML experiment file (a bench over a parameter sweep): rows JSON + images + report.
    Run(commands::run::RunArgs),
    /// Write the HTML report of results folders of `parallax run`.
    Report(commands::report::ReportArgs),
    /// Merge the folders of a sharded job into the output of one unsharded run.
    Merge(commands::merge::MergeArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    if let Some(n) = cli.threads
        && let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
    {
        eprintln!("error: cannot set up {n} threads: {e}");
        return std::process::ExitCode::FAILURE;
    }
    match dispatch(cli.command, cli.quiet) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// The command line as `parallax run` sees it: the clap definition and a parser of whole
/// argument lists into jobs that [`dispatch`] them.
const SHELL: commands::run::Shell = commands::run::Shell {
    command: <Cli as clap::CommandFactory>::command,
    parse: parse_job,
};

fn parse_job(argv: &[String]) -> Result<commands::run::Job, clap::Error> {
    let cli = Cli::try_parse_from(argv)?;
    Ok(Box::new(move |quiet| dispatch(cli.command, quiet)))
}

/// Runs one subcommand (also how `parallax run` runs the benches of an experiment).
fn dispatch(command: Command, quiet: bool) -> anyhow::Result<()> {
    match command {
        Command::Render(a) => commands::render::run(&a, quiet),
        Command::Scenes => commands::info::scenes(),
        Command::Info(a) => commands::info::run(&a),
        Command::Capture(a) => commands::capture::run(&a, quiet),
        Command::Demo(a) => commands::demo::run(&a, quiet, &SHELL),
        Command::Vr(a) => commands::vr::run(&a, quiet),
        Command::Warp(a) => commands::warp::run(&a, quiet),
        Command::Upsample(a) => commands::upsample::run(&a, quiet),
        Command::Path(a) => commands::path::run(&a, quiet),
        Command::Secondary(a) => commands::secondary::run(&a, quiet),
        Command::Dof(a) => commands::dof::run(&a, quiet),
        Command::Reflect(a) => commands::reflect::run(&a, quiet),
        Command::Lightfield(a) => commands::lightfield::run(&a, quiet),
        Command::Reproject(a) => commands::reproject::run_reproject(&a, quiet),
        Command::Bench(b) => commands::bench::run(&b, quiet),
        Command::Run(a) => commands::run::run(&a, quiet, &SHELL),
        Command::Report(a) => commands::report::run(&a, quiet),
        Command::Merge(a) => commands::merge::run(&a, quiet),
    }
}
