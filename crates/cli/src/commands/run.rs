//! `parallax run EXPERIMENT.toml`: runs an experiment file (`parallax_experiment::schema`):
//! every sweep point becomes a `parallax bench <name>` command line, parsed by the same clap
//! definitions and run by the same code as when typed by hand (`main.rs`'s `dispatch`, handed in
//! as a [`Shell`] so that this file does not import `main.rs`), its
//! `--json` rows collected into `OUT/results.json`; with `[images]` the point's image
//! subcommand (e.g. `parallax warp`) writes into `OUT/points/pNNNN/`. Then the HTML report
//! (`OUT/index.html`).
//!
//! Every point's command lines are built and checked before the first point runs: an
//! unknown bench or key, a value of the wrong type, a missing scene or a sweep over
//! `max_points` is an error naming the file, line and key. `--shard I/N` (or the Slurm /
//! Kubernetes array index, `parallax_experiment::shard`) runs the points `i % N == I` and
//! writes `OUT/shard.json` instead of `results.json`; `parallax merge` joins the shards.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use parallax_experiment::results::{
    self, MANIFEST_FILE, PointResult, RESULTS_FILE, RunResults, ShardManifest,
};
use parallax_experiment::sweep::{flag_args, flag_name};
use parallax_experiment::toml::Value;
use parallax_experiment::{Entry, Experiment, Shard};

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Experiment file (TOML; examples in experiments/).
    pub experiment: PathBuf,
    /// Output folder (default: the file's `out`, else `out/experiments/<file stem>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Run part I of N of the sweep points (0-based, points i with i % N == I). Without it,
    /// SLURM_ARRAY_TASK_ID / SLURM_ARRAY_TASK_COUNT or JOB_COMPLETION_INDEX (+ --shard-count).
    #[arg(long)]
    pub shard: Option<String>,
    /// Shard count for an environment index without its own count (Kubernetes Indexed Jobs).
    #[arg(long)]
    pub shard_count: Option<usize>,
    /// Replace measured times and rates in the rows by null (runs then compare byte for byte).
    #[arg(long)]
    pub mask_timings: bool,
    /// Check the file and print every point's command lines; run nothing.
    #[arg(long)]
    pub dry_run: bool,
    /// Do not write OUT/index.html after an unsharded run.
    #[arg(long)]
    pub no_report: bool,
}

/// A parsed command line, ready to run (`quiet` flag in).
pub type Job = Box<dyn FnOnce(bool) -> Result<()>>;

/// The binary's command-line interface as `parallax run` sees it (given by `main.rs`).
pub struct Shell {
    /// The clap definition of `parallax` (`Cli::command()`).
    pub command: fn() -> clap::Command,
    /// Parses a whole argument list (`parallax ...`) into a job that runs it.
    pub parse: fn(&[String]) -> std::result::Result<Job, clap::Error>,
}

/// A command line checked against the clap definitions of `parallax`.
pub struct CheckedLine {
    pub args: Vec<String>,
    pub job: Job,
}

/// Subcommands an experiment may not run as its image command.
const NOT_IMAGE_COMMANDS: [&str; 6] = ["run", "report", "merge", "bench", "demo", "scenes"];
/// Image subcommands whose `--out` is a file (the others take a folder).
const FILE_OUT_COMMANDS: [&str; 3] = ["render", "path", "secondary"];
/// Keys the runner sets itself.
const RESERVED_KEYS: [&str; 2] = ["json", "out"];

fn value_text(v: &Value) -> String {
    match v {
        Value::String(s) => format!("{s:?}"),
        other => other.to_string(),
    }
}

/// What a flag expects, for messages.
fn expected(arg: &clap::Arg) -> String {
    if !arg.get_action().takes_values() {
        return "a boolean (true adds the flag)".into();
    }
    let pv = arg.get_possible_values();
    let what = if !pv.is_empty() {
        let names: Vec<&str> = pv.iter().map(|p| p.get_name()).collect();
        format!("one of {}", names.join(", "))
    } else {
        let names = arg
            .get_value_names()
            .map(|n| n.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(" "))
            .unwrap_or_else(|| "VALUE".into());
        format!("<{names}>")
    };
    match arg.get_help() {
        Some(h) => format!("{what} ({})", h.to_string().lines().next().unwrap_or("")),
        None => what,
    }
}

/// The clap command of `parallax <path...>` (e.g. `["bench", "warp"]`).
fn subcommand(sh: &Shell, path: &[&str]) -> Option<clap::Command> {
    let mut c = (sh.command)();
    for p in path {
        c = c.find_subcommand(p)?.clone();
    }
    Some(c)
}

fn long_flag<'a>(cmd: &'a clap::Command, key: &str) -> Option<&'a clap::Arg> {
    let f = flag_name(key);
    cmd.get_arguments()
        .find(|a| a.get_long() == Some(f.as_str()) && !a.is_global_set())
}

/// Checks the keys of `entries` against `path`'s flags, then parses the line.
fn check_line(
    sh: &Shell,
    exp: &Experiment,
    path: &[&str],
    entries: &[&Entry],
    extra: &[String],
) -> Result<CheckedLine> {
    let name = format!("parallax {}", path.join(" "));
    let cmd = subcommand(sh, path).with_context(|| format!("no subcommand `{name}`"))?;
    let mut args: Vec<String> = path.iter().map(|s| s.to_string()).collect();
    for e in entries {
        if RESERVED_KEYS.contains(&e.key.as_str()) {
            bail!(exp.key_error(e.line, &e.key, "set by `parallax run` (use --out of run)"));
        }
        let Some(arg) = long_flag(&cmd, &e.key) else {
            let mut flags: Vec<String> = cmd
                .get_arguments()
                .filter_map(|a| a.get_long())
                .filter(|l| {
                    !RESERVED_KEYS.contains(l) && *l != "help" && *l != "quiet" && *l != "threads"
                })
                .map(|l| l.replace('-', "_"))
                .collect();
            flags.sort();
            bail!(exp.key_error(
                e.line,
                &e.key,
                format!(
                    "unknown key: `{name}` has no --{}; its keys: {}",
                    flag_name(&e.key),
                    flags.join(", ")
                )
            ));
        };
        let is_bool = matches!(e.value, Value::Boolean(_));
        if arg.get_action().takes_values() == is_bool {
            bail!(exp.key_error(
                e.line,
                &e.key,
                format!(
                    "expected {}, got {} {}",
                    expected(arg),
                    parallax_experiment::schema::type_name(&e.value),
                    value_text(&e.value)
                )
            ));
        }
        if e.key == "scene"
            && let Value::String(s) = &e.value
        {
            let file = parallax_scene::builtin::room::parse(s).map_or(s.as_str(), |r| r.1);
            if !parallax_scene::builtin::NAMES.contains(&file) && !Path::new(file).exists() {
                bail!(exp.key_error(
                        e.line,
                        "scene",
                        format!(
                            "{s:?} is neither a built-in scene ({}) nor an existing file (paths are relative to the working directory)",
                            parallax_scene::builtin::NAMES.join(", ")
                        )
                    ));
            }
        }
        args.extend(flag_args(e));
    }
    args.extend(extra.iter().cloned());
    let argv: Vec<String> = std::iter::once("parallax".to_string())
        .chain(args.iter().cloned())
        .collect();
    match (sh.parse)(&argv) {
        Ok(job) => Ok(CheckedLine { args, job }),
        Err(err) => {
            let invalid = err
                .get(clap::error::ContextKind::InvalidArg)
                .map(|v| v.to_string())
                .unwrap_or_default();
            let flag = invalid
                .split([' ', '='])
                .next()
                .unwrap_or("")
                .trim_start_matches('-');
            let msg = err.render().to_string();
            let msg = msg
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
                .to_string();
            match entries.iter().find(|e| flag_name(&e.key) == flag) {
                Some(e) => {
                    let exp_text = long_flag(&cmd, &e.key).map(expected).unwrap_or_default();
                    bail!(exp.key_error(
                        e.line,
                        &e.key,
                        format!("`{name}`: {msg} (expected {exp_text})")
                    ))
                }
                None => bail!(
                    "{}: `{name} {}`: {msg}",
                    exp.file.display(),
                    args[path.len()..].join(" ")
                ),
            }
        }
    }
}

/// The checked command lines of one point.
struct PointPlan {
    point: parallax_experiment::Point,
    bench: CheckedLine,
    images: Option<CheckedLine>,
}

/// Builds and checks every point's command lines (before any work).
fn plan(sh: &Shell, exp: &Experiment, out: &Path) -> Result<Vec<PointPlan>> {
    let Some(bench_cmd) = subcommand(sh, &["bench"]) else {
        bail!("no bench subcommand");
    };
    let names: Vec<String> = bench_cmd
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .filter(|n| n != "help")
        .collect();
    if !names.contains(&exp.bench) {
        bail!(exp.key_error(
            exp.bench_line,
            "bench",
            format!(
                "unknown bench {:?}; expected one of {}",
                exp.bench,
                names.join(", ")
            )
        ));
    }
    if let Some(img) = &exp.images {
        let ok = subcommand(sh, &[img.command.as_str()]).is_some()
            && !NOT_IMAGE_COMMANDS.contains(&img.command.as_str());
        if !ok {
            let all: Vec<String> = (sh.command)()
                .get_subcommands()
                .map(|c| c.get_name().to_string())
                .filter(|n| !NOT_IMAGE_COMMANDS.contains(&n.as_str()) && n != "help" && n != "info")
                .collect();
            bail!(exp.key_error(
                img.line,
                "images.command",
                format!(
                    "unknown image command {:?}; expected one of {}",
                    img.command,
                    all.join(", ")
                )
            ));
        }
    }
    let mut plans = Vec::new();
    for point in exp.points()? {
        let dir = point_dir(out, point.index);
        let json = dir.join("rows.json.tmp");
        let entries: Vec<&Entry> = exp.entries_of(&point).collect();
        let bench = check_line(
            sh,
            exp,
            &["bench", exp.bench.as_str()],
            &entries,
            &[format!("--json={}", json.display())],
        )?;
        let images = match &exp.images {
            None => None,
            Some(img) => {
                let cmd = subcommand(sh, &[img.command.as_str()]).expect("checked above");
                let mut list: Vec<&Entry> = entries
                    .iter()
                    .copied()
                    .filter(|e| long_flag(&cmd, &e.key).is_some())
                    .filter(|e| !img.args.iter().any(|i| i.key == e.key))
                    .collect();
                list.extend(img.args.iter());
                let target = if FILE_OUT_COMMANDS.contains(&img.command.as_str()) {
                    dir.join("image.png")
                } else {
                    dir.clone()
                };
                Some(check_line(
                    sh,
                    exp,
                    &[img.command.as_str()],
                    &list,
                    &[format!("--out={}", target.display())],
                )?)
            }
        };
        plans.push(PointPlan {
            point,
            bench,
            images,
        });
    }
    Ok(plans)
}

fn point_dir(out: &Path, index: usize) -> PathBuf {
    out.join("points").join(format!("p{index:04}"))
}

/// The bench's JSON as (rows, other fields).
fn split_rows(
    v: serde_json::Value,
) -> (
    serde_json::Value,
    std::collections::BTreeMap<String, serde_json::Value>,
) {
    match v {
        serde_json::Value::Array(_) => (v, Default::default()),
        serde_json::Value::Object(mut m) => match m.remove("rows") {
            Some(rows) => (rows, m.into_iter().collect()),
            None => (
                serde_json::Value::Array(vec![serde_json::Value::Object(m)]),
                Default::default(),
            ),
        },
        other => (serde_json::Value::Array(vec![other]), Default::default()),
    }
}

/// Runs one planned point; returns its results.
fn run_point(p: PointPlan, out: &Path, mask: bool, quiet: bool) -> Result<PointResult> {
    let dir = point_dir(out, p.point.index);
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    let json = dir.join("rows.json.tmp");
    (p.bench.job)(quiet).with_context(|| {
        format!(
            "point {}: parallax {}",
            p.point.index,
            p.bench.args.join(" ")
        )
    })?;
    let text =
        std::fs::read_to_string(&json).with_context(|| format!("reading {}", json.display()))?;
    std::fs::remove_file(&json).with_context(|| format!("removing {}", json.display()))?;
    let mut value: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", json.display()))?;
    if mask {
        results::mask_timings(&mut value);
    }
    let (rows, extra) = split_rows(value);
    let mut image_args = Vec::new();
    if let Some(img) = p.images {
        image_args = img.args.clone();
        (img.job)(true)
            .with_context(|| format!("point {}: parallax {}", p.point.index, img.args.join(" ")))?;
    }
    let mut images: Vec<String> = results::files_under(&dir)?
        .into_iter()
        .filter(|f| f.extension().is_some_and(|e| e == "png"))
        .map(|f| {
            Path::new("points")
                .join(format!("p{:04}", p.point.index))
                .join(f)
                .to_string_lossy()
                .replace('\\', "/")
        })
        .collect();
    images.sort();
    // Strip the machine-specific --json / --out paths: the rows do not depend on them.
    let keep = |a: &String| !a.starts_with("--json=") && !a.starts_with("--out=");
    Ok(PointResult {
        index: p.point.index,
        params: p.point.json_params(),
        bench_args: p
            .bench
            .args
            .iter()
            .skip(1)
            .filter(|a| keep(a))
            .cloned()
            .collect(),
        image_args: image_args.into_iter().filter(|a| keep(a)).collect(),
        rows,
        extra,
        images,
    })
}

pub fn run(a: &RunArgs, quiet: bool, sh: &Shell) -> Result<()> {
    let exp = Experiment::from_file(&a.experiment)?;
    let out = a.out.clone().unwrap_or_else(|| exp.out.clone());
    let plans = plan(sh, &exp, &out)?;
    let total = plans.len();
    let shard = Shard::from_flags(a.shard.as_deref(), a.shard_count)?;
    let selected: Vec<usize> = match shard {
        Some(s) => s.items(total),
        None => (0..total).collect(),
    };
    if a.dry_run {
        for p in plans.iter().filter(|p| selected.contains(&p.point.index)) {
            println!(
                "point {}: parallax {}",
                p.point.index,
                p.bench.args.join(" ")
            );
            if let Some(i) = &p.images {
                println!("point {}: parallax {}", p.point.index, i.args.join(" "));
            }
        }
        println!("{} of {total} point(s) checked", selected.len());
        return Ok(());
    }
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let mut points = Vec::new();
    for p in plans
        .into_iter()
        .filter(|p| selected.contains(&p.point.index))
    {
        if !quiet {
            let params: Vec<String> = p
                .point
                .params
                .iter()
                .map(|e| format!("{} = {}", e.key, e.value))
                .collect();
            println!(
                "\n## {} point {}/{total}{}\n",
                exp.title,
                p.point.index,
                if params.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", params.join(", "))
                }
            );
        }
        points.push(run_point(p, &out, a.mask_timings, quiet)?);
    }
    let results = RunResults {
        title: exp.title.clone(),
        bench: exp.bench.clone(),
        experiment: a.experiment.to_string_lossy().replace('\\', "/"),
        points,
    };
    match shard {
        Some(s) => {
            let m = ShardManifest {
                kind: "run".into(),
                shard: s,
                total,
                items: selected,
                results: Some(results),
            };
            results::write_json(&out.join(MANIFEST_FILE), &m)?;
            if !quiet {
                println!(
                    "shard {}/{} wrote {} point(s) to {}; join the shards with `parallax merge`",
                    s.index,
                    s.count,
                    m.items.len(),
                    out.display()
                );
            }
        }
        None => {
            results::write_json(&out.join(RESULTS_FILE), &results)?;
            if !a.no_report {
                let page = parallax_experiment::report::write_report(
                    std::slice::from_ref(&out),
                    None,
                    false,
                )?;
                if !quiet {
                    println!("report: {}", page.display());
                }
            }
            if !quiet {
                println!("results: {}", out.join(RESULTS_FILE).display());
            }
        }
    }
    Ok(())
}
