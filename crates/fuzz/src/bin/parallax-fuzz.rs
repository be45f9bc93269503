//! `parallax-fuzz`: the long fuzz run (`cargo run --release -p parallax-fuzz -- --cases
//! 1000000`); see `parallax_fuzz` for what it does. Flags: `--cases N`, `--seed S`,
//! `--budget-mib M` (peak heap of one input), `--timeout S`, `--out DIR` (findings),
//! `--targets gltf,glb,obj,ply,png,exr,toml`. Exit status 1 when anything was found.

use parallax_fuzz::targets::Target;
use parallax_fuzz::{FuzzOptions, alloc};

#[global_allocator]
static ALLOC: alloc::Counting = alloc::Counting;

fn main() -> std::process::ExitCode {
    let mut o = FuzzOptions::default();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().cloned().unwrap_or_default();
        let parsed = match a.as_str() {
            "--cases" => val().parse().map(|v| o.cases = v).is_ok(),
            "--seed" => val().parse().map(|v| o.seed = v).is_ok(),
            "--budget-mib" => val()
                .parse::<usize>()
                .map(|v| o.budget_bytes = v << 20)
                .is_ok(),
            "--timeout" => val().parse().map(|v| o.timeout_s = v).is_ok(),
            "--out" => {
                o.crash_dir = val().into();
                true
            }
            "--targets" => {
                let list: Option<Vec<Target>> = val().split(',').map(Target::of_ext).collect();
                list.map(|l| o.targets = l).is_some()
            }
            _ => false,
        };
        if !parsed {
            eprintln!(
                "parallax-fuzz: bad flag {a:?}; flags: --cases N --seed S --budget-mib M --timeout S --out DIR --targets gltf,glb,obj,ply,png,exr,toml"
            );
            return std::process::ExitCode::FAILURE;
        }
    }
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
