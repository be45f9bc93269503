//! `parallax-fuzz`: the long fuzz run (`cargo run --release -p parallax-fuzz -- --cases
//! 1000000`); see `parallax_fuzz` for what it does. Flags: `--cases N`, `--seed S`,
//! `--budget-mib M` (peak heap of one input), `--timeout S`, `--out DIR` (findings),
//! `--targets gltf,glb,obj,ply,png,exr,toml` (`--help` for all). Exit status 1 when anything was
//! found.

use clap::Parser;
use parallax_fuzz::targets::Target;
use parallax_fuzz::{FuzzOptions, alloc};

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

/// The long fuzz run over the loaders, image inputs and experiment files.
#[derive(Parser, Debug)]
#[command(name = "parallax-fuzz", version)]
struct Args {
    /// Inputs to run (round robin over the targets)
    #[arg(long, default_value_t = FuzzOptions::default().cases)]
    cases: u64,
    /// Seed of the mutations
    #[arg(long, default_value_t = FuzzOptions::default().seed)]
    seed: u64,
    /// Largest peak heap of one input before it counts as a finding (MiB)
    #[arg(long, default_value_t = FuzzOptions::default().budget_bytes >> 20)]
    budget_mib: usize,
    /// Wall-clock seconds one input may take before it counts as a hang
    #[arg(long, default_value_t = FuzzOptions::default().timeout_s)]
    timeout: u64,
    /// Folder of the findings (and the current input, under work/)
    #[arg(long, default_value = "out/fuzz")]
    out: std::path::PathBuf,
    /// Targets (comma list)
    #[arg(long, value_delimiter = ',', value_parser = parse_target,
          default_value = "gltf,glb,obj,ply,png,exr,toml")]
    targets: Vec<Target>,
}

fn parse_target(s: &str) -> Result<Target, String> {
    Target::of_ext(s).ok_or_else(|| {
        let names: Vec<&str> = Target::ALL.iter().map(|t| t.ext()).collect();
        format!("unknown target {s:?}; expected one of {}", names.join(", "))
    })
}

fn main() -> std::process::ExitCode {
    let a = Args::parse();
    let o = FuzzOptions {
        cases: a.cases,
        seed: a.seed,
        budget_bytes: a.budget_mib << 20,
        timeout_s: a.timeout,
        crash_dir: a.out,
        targets: a.targets,
    };
    // Above 4x the budget an allocation fails (abort) instead of swapping the machine.
    alloc::set_hard_cap(o.budget_bytes.saturating_mul(4).max(1 << 30));
    let r = match parallax_fuzz::run(&o) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("parallax-fuzz: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    let per: Vec<String> = r
        .per_target
        .iter()
        .map(|(t, n)| format!("{t} {n}"))
        .collect();
    println!(
        "{} inputs in {:.1} s ({}), seed {}, largest peak heap of one input {:.1} MiB (budget {} MiB), {} finding(s)",
        r.cases,
        r.seconds,
        per.join(", "),
        o.seed,
        r.max_peak_bytes as f64 / (1 << 20) as f64,
        o.budget_bytes >> 20,
        r.findings.len()
    );
    for f in &r.findings {
        println!(
            "{} {:?}: {} ({})",
            f.kind,
            f.target,
            f.file.display(),
            f.message.lines().next().unwrap_or("")
        );
    }
    if r.findings.is_empty() {
        std::process::ExitCode::SUCCESS
    } else {
        std::process::ExitCode::FAILURE
    }
}
