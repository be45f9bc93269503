//! The results folder of `parallax run` and the merge of shard folders.
//!
//! An unsharded run writes `results.json` ([`RunResults`]: the experiment's header and one
//! [`PointResult`] per sweep point, rows as the bench wrote them) and each point's images in
//! `points/pNNNN/`. A shard writes its points the same way and, instead of `results.json`, a
//! `shard.json` ([`ShardManifest`]: which items of how many it ran, and its partial results).
//! Commands whose output is plain files (e.g. `parallax upsample --shard`) write a manifest
//! without results. [`merge`] checks that the shards are one job, disjoint and complete, copies
//! every file but the manifests, and writes `results.json` with the same serializer as an
//! unsharded run, so merged shards equal one run byte for byte (with `--mask-timings`: two
//! runs never measure the same milliseconds).
//!
//! Invariants: points are sorted by index; a file written by two shards must be identical.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::ExperimentError;
use crate::shard::Shard;
use crate::sweep::Param;

/// File name of a complete run's results.
pub const RESULTS_FILE: &str = "results.json";
/// File name of a shard's manifest.
pub const MANIFEST_FILE: &str = "shard.json";

/// The results of a run (or of the points a shard ran).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResults {
    pub title: String,
    pub bench: String,
    /// The experiment file as given on the command line.
    pub experiment: String,
    pub points: Vec<PointResult>,
}

/// One sweep point: its parameters, the command lines it ran, the bench's rows and images.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointResult {
    pub index: usize,
    pub params: Vec<Param>,
    /// `parallax bench ...` arguments of the rows.
    pub bench_args: Vec<String>,
    /// Arguments of the image subcommand (empty without `[images]`).
    #[serde(default)]
    pub image_args: Vec<String>,
    /// The bench's JSON rows (an array).
    pub rows: serde_json::Value,
    /// Other fields of the bench's JSON (e.g. `bench vr`'s `update` row).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub extra: BTreeMap<String, serde_json::Value>,
    /// Image files relative to the results folder, sorted.
    #[serde(default)]
    pub images: Vec<String>,
}

/// `shard.json`: what one shard of a job ran.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardManifest {
    /// `run` (sweep points) or the command whose items are files (`upsample`: frame groups).
    pub kind: String,
    pub shard: Shard,
    /// Items of the whole job and the ones this shard ran.
    pub total: usize,
    pub items: Vec<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub results: Option<RunResults>,
}

/// Pretty JSON with a final newline: the one serializer of results files.
pub fn to_json_text<T: Serialize>(v: &T) -> String {
    let mut s = serde_json::to_string_pretty(v).expect("results serialize");
    s.push('\n');
    s
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ExperimentError + '_ {
    move |source| ExperimentError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `v` as [`to_json_text`] to `path`.
pub fn write_json<T: Serialize>(path: &Path, v: &T) -> Result<(), ExperimentError> {
    std::fs::write(path, to_json_text(v)).map_err(io(path))
}

/// Reads a JSON file into `T`.
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, ExperimentError> {
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    serde_json::from_str(&text).map_err(|e| ExperimentError::Json {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Whether a row field is a measured time or rate (differs between any two runs).
pub fn is_timing_key(k: &str) -> bool {
    k.starts_with("ms_")
        || k.ends_with("_ms")
        || k.contains("_ms_")
        || k == "ms"
        || k.ends_with("per_s")
        || k.contains("per_cpu_s")
        || k.ends_with("seconds")
        || k.ends_with("_secs")
        || k.starts_with("time")
        || k.contains("speedup")
        || k.starts_with("vs_")
        || k.starts_with("ratio")
}

/// Replaces every timing field (see [`is_timing_key`]) of `v`, at any depth, by `null`.
pub fn mask_timings(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m.iter_mut() {
                if is_timing_key(k) && (x.is_number() || x.is_null()) {
                    *x = serde_json::Value::Null;
                } else {
                    mask_timings(x);
                }
            }
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(mask_timings),
        _ => {}
    }
}

/// Every file under `dir`, relative to it, sorted.
pub fn files_under(dir: &Path) -> Result<Vec<PathBuf>, ExperimentError> {
    let mut out = Vec::new();
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let abs = dir.join(&rel);
        for e in std::fs::read_dir(&abs).map_err(io(&abs))? {
            let e = e.map_err(io(&abs))?;
            let r = rel.join(e.file_name());
            if e.file_type().map_err(io(&abs))?.is_dir() {
                stack.push(r);
            } else {
                out.push(r);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// What [`merge`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct MergeSummary {
    pub kind: String,
    pub shards: usize,
    pub items: usize,
    pub files: usize,
}

/// Merges shard folders into `out` (see the module docs).
pub fn merge(shard_dirs: &[PathBuf], out: &Path) -> Result<MergeSummary, ExperimentError> {
    let bad = |m: String| ExperimentError::Merge(m);
    if shard_dirs.is_empty() {
        return Err(bad("no shard folders given".into()));
    }
    let mut manifests = Vec::new();
    for d in shard_dirs {
        let m: ShardManifest = read_json(&d.join(MANIFEST_FILE))?;
        manifests.push(m);
    }
    let first = &manifests[0];
    let mut owner: Vec<Option<usize>> = vec![None; first.total];
    for (k, m) in manifests.iter().enumerate() {
        let dir = shard_dirs[k].display();
        if m.kind != first.kind || m.total != first.total || m.shard.count != first.shard.count {
            return Err(bad(format!(
                "{dir} is shard {}/{} of a {} job over {} items, {} is {}/{} of a {} job over {}",
                m.shard.index,
                m.shard.count,
                m.kind,
                m.total,
                shard_dirs[0].display(),
                first.shard.index,
                first.shard.count,
                first.kind,
                first.total
            )));
        }
        for &i in &m.items {
            let slot = owner
                .get_mut(i)
                .ok_or_else(|| bad(format!("{dir}: item {i} out of range 0..{}", m.total)))?;
            if let Some(o) = slot.replace(k) {
                return Err(bad(format!(
                    "item {i} is in both {} and {dir}",
                    shard_dirs[o].display()
                )));
            }
        }
    }
    let missing: Vec<usize> = (0..first.total).filter(|&i| owner[i].is_none()).collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(10).map(|i| i.to_string()).collect();
        return Err(bad(format!(
            "{} of {} items missing (e.g. {}): not every shard is given",
            missing.len(),
            first.total,
            shown.join(", ")
        )));
    }
    std::fs::create_dir_all(out).map_err(io(out))?;
    let mut copied: BTreeMap<PathBuf, usize> = BTreeMap::new();
    for (k, d) in shard_dirs.iter().enumerate() {
        for rel in files_under(d)? {
            if rel == Path::new(MANIFEST_FILE) {
                continue;
            }
            let src = d.join(&rel);
            let dst = out.join(&rel);
            if let Some(&o) = copied.get(&rel) {
                let a = std::fs::read(&src).map_err(io(&src))?;
                let b = std::fs::read(&dst).map_err(io(&dst))?;
                if a != b {
                    return Err(bad(format!(
                        "{} differs between {} and {}",
                        rel.display(),
                        shard_dirs[o].display(),
                        d.display()
                    )));
                }
                continue;
            }
            if let Some(p) = dst.parent() {
                std::fs::create_dir_all(p).map_err(io(p))?;
            }
            std::fs::copy(&src, &dst).map_err(io(&src))?;
            copied.insert(rel, k);
        }
    }
    if first.kind == "run" {
        let mut merged: Option<RunResults> = None;
        for (k, m) in manifests.iter().enumerate() {
            let r = m.results.as_ref().ok_or_else(|| {
                bad(format!(
                    "{}: run shard without results",
                    shard_dirs[k].display()
                ))
            })?;
            match &mut merged {
                None => merged = Some(r.clone()),
                Some(all) => {
                    if (&all.title, &all.bench, &all.experiment)
                        != (&r.title, &r.bench, &r.experiment)
                    {
                        return Err(bad(format!(
                            "{} ran {} ({}), not {} ({})",
                            shard_dirs[k].display(),
                            r.experiment,
                            r.bench,
                            all.experiment,
                            all.bench
                        )));
                    }
                    all.points.extend(r.points.iter().cloned());
                }
            }
        }
        let mut all = merged.expect("at least one shard");
        all.points.sort_by_key(|p| p.index);
        write_json(&out.join(RESULTS_FILE), &all)?;
    }
    Ok(MergeSummary {
        kind: first.kind.clone(),
        shards: shard_dirs.len(),
        items: first.total,
        files: copied.len(),
    })
}
