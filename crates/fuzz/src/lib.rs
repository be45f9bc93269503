//! parallax-fuzz: a mutation fuzzer on stable Rust over every input a user hands parallax:
//! scene files (glTF, GLB, OBJ, PLY), colour / depth images (PNG, EXR) and experiment files
//! (TOML). Each case mutates a seed ([`mutate`]), runs it ([`targets`]) under
//! `catch_unwind`, and records a finding when it panics, allocates more than the budget at
//! its peak (with the counting allocator of [`alloc`] installed) or runs longer than the
//! timeout (a watchdog saves the input and ends the process). Findings go to the crash folder
//! as `<kind>-<target>-<hash>.<ext>` (+ `.txt` with the message); copy one into
//! `crates/fuzz/regressions/` to make it a regression test (`tests/regressions.rs` loads
//! every file there).
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `cases` | u64 | 10 000 | inputs to run (round robin over the targets) |
//! | `seed` | u64 | 1 | the mutation stream |
//! | `budget_bytes` | usize | 2 GiB | peak heap of one input above which it is a finding (the largest legal image, 2^28 f32 samples = 1 GiB, plus a decoder copy) |
//! | `timeout_s` | u64 | 120 | one input's wall-clock limit (generous: the machine may be shared) |
//! | `crash_dir` | path | `out/fuzz` | where findings and the scratch files go |

pub mod alloc;
pub mod mutate;
pub mod targets;

use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use mutate::Rng;
use targets::Target;

/// Options of a run (see the module docs).
#[derive(Clone, Debug)]
pub struct FuzzOptions {
    pub cases: u64,
    pub seed: u64,
    pub budget_bytes: usize,
    pub timeout_s: u64,
    pub crash_dir: PathBuf,
    pub targets: Vec<Target>,
}

impl Default for FuzzOptions {
    fn default() -> Self {
        FuzzOptions {
            cases: 10_000,
            seed: 1,
            budget_bytes: 2 << 30,
            timeout_s: 120,
            crash_dir: PathBuf::from("out/fuzz"),
            targets: Target::ALL.to_vec(),
        }
    }
}

/// One finding.
#[derive(Clone, Debug)]
pub struct Finding {
    pub kind: &'static str,
    pub target: Target,
    pub message: String,
    pub file: PathBuf,
}

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct FuzzReport {
    pub cases: u64,
    pub per_target: Vec<(String, u64)>,
    pub findings: Vec<Finding>,
    /// The largest peak heap of one input (0 without the counting allocator).
    pub max_peak_bytes: usize,
    pub seconds: f64,
}

fn fnv(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x100_0000_01b3)
    })
}

fn save(
    dir: &std::path::Path,
    kind: &'static str,
    t: Target,
    data: &[u8],
    message: &str,
) -> PathBuf {
    let name = format!("{kind}-{}-{:016x}.{}", t.ext(), fnv(data), t.ext());
    let p = dir.join(name);
    let _ = std::fs::write(&p, data);
    let _ = std::fs::write(p.with_extension(format!("{}.txt", t.ext())), message);
    p
}

/// One mutated input of `seed`'s format.
fn mutated(t: Target, seed: &[u8], other: &[u8], rng: &mut Rng) -> Vec<u8> {
    match t {
        Target::Gltf if rng.chance(2) => {
            mutate::mutate_json(seed, rng).unwrap_or_else(|| mutate::havoc(seed, other, rng))
        }
        Target::Glb if rng.chance(2) => match mutate::glb_chunks(seed) {
            Some((json, bin)) => match mutate::mutate_json(&json, rng) {
                Some(j) => mutate::glb(&j, &bin),
                None => mutate::havoc(seed, other, rng),
            },
            None => mutate::havoc(seed, other, rng),
        },
        Target::Toml if rng.chance(2) => mutate::mutate_toml(seed, rng),
        _ => mutate::havoc(seed, other, rng),
    }
}

/// Runs the fuzzer (see the module docs).
pub fn run(opts: &FuzzOptions) -> std::io::Result<FuzzReport> {
    std::fs::create_dir_all(&opts.crash_dir)?;
    let work = opts.crash_dir.join("work");
    std::fs::create_dir_all(&work)?;
    let seeds = targets::seeds(&work);
    let by_target: Vec<(Target, Vec<&Vec<u8>>)> = opts
        .targets
        .iter()
        .map(|&t| {
            (
                t,
                seeds
                    .iter()
                    .filter(|s| s.0 == t)
                    .map(|s| &s.1)
                    .collect::<Vec<_>>(),
            )
        })
        .filter(|(_, s)| !s.is_empty())
        .collect();
    let mut report = FuzzReport::default();
    if by_target.is_empty() {
        return Ok(report);
    }
    // Panic messages of the current case (the default hook would print each one).
    let last_panic = Arc::new(Mutex::new(String::new()));
    let hook_msg = last_panic.clone();
    let old_hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        if let Ok(mut m) = hook_msg.lock() {
            *m = info.to_string();
        }
    }));
    // Watchdog: the start of the running case in ms since `t0` (u64::MAX between cases).
    let t0 = Instant::now();
    let started = Arc::new(AtomicU64::new(u64::MAX));
    let done = Arc::new(AtomicU64::new(0));
    let running = Arc::new(AtomicU64::new(0));
    let (st, dn, rt) = (started.clone(), done.clone(), running.clone());
    let (timeout, dir) = (opts.timeout_s.max(1) * 1000, opts.crash_dir.clone());
    let names: Vec<Target> = by_target.iter().map(|t| t.0).collect();
    let watchdog = std::thread::spawn(move || {
        while dn.load(Ordering::Relaxed) == 0 {
            std::thread::sleep(Duration::from_millis(200));
            let s = st.load(Ordering::Relaxed);
            let now = t0.elapsed().as_millis() as u64;
            if s != u64::MAX && now.saturating_sub(s) > timeout {
                let t = names[rt.load(Ordering::Relaxed) as usize];
                let cur = dir.join("work").join(format!("current.{}", t.ext()));
                let data = std::fs::read(cur).unwrap_or_default();
                let msg = format!("ran over {} s (wall clock)", timeout / 1000);
                let f = save(&dir, "hang", t, &data, &msg);
                eprintln!("fuzz: a {t:?} input {msg}: {}", f.display());
                std::process::exit(3);
            }
        }
    });
    let mut rng = Rng::new(opts.seed);
    let mut counts = vec![0u64; by_target.len()];
    for case in 0..opts.cases {
        let k = (case % by_target.len() as u64) as usize;
        let (t, list) = &by_target[k];
        let seed = list[rng.below(list.len())];
        let other = list[rng.below(list.len())];
        let mut data = mutated(*t, seed, other, &mut rng);
        if rng.chance(4) {
            data = mutated(*t, &data, other, &mut rng);
        }
        let file = work.join(format!("current.{}", t.ext()));
        running.store(k as u64, Ordering::Relaxed);
        let base = alloc::reset_peak();
        started.store(t0.elapsed().as_millis() as u64, Ordering::Relaxed);
        let r = std::panic::catch_unwind(AssertUnwindSafe(|| t.run(&data, &file)));
        if let Ok(Err(e)) = r {
            done.store(1, Ordering::Relaxed);
            return Err(std::io::Error::other(format!(
                "writing {}: {e}",
                file.display()
            )));
        }
        started.store(u64::MAX, Ordering::Relaxed);
        let peak = alloc::peak().saturating_sub(base);
        report.max_peak_bytes = report.max_peak_bytes.max(peak);
        counts[k] += 1;
        if (case + 1) % 100_000 == 0 {
            eprintln!(
                "fuzz: {} inputs, {:.0} s, {} finding(s), largest peak heap {} MiB",
                case + 1,
                t0.elapsed().as_secs_f64(),
                report.findings.len(),
                report.max_peak_bytes >> 20
            );
        }
        let finding = if r.is_err() {
            Some((
                "panic",
                last_panic.lock().map(|m| m.clone()).unwrap_or_default(),
            ))
        } else if peak > opts.budget_bytes {
            Some((
                "budget",
                format!("peak heap {peak} bytes > budget {}", opts.budget_bytes),
            ))
        } else {
            None
        };
        if let Some((kind, message)) = finding {
            let file = save(&opts.crash_dir, kind, *t, &data, &message);
            report.findings.push(Finding {
                kind,
                target: *t,
                message,
                file,
            });
        }
    }
    done.store(1, Ordering::Relaxed);
    let _ = watchdog.join();
    std::panic::set_hook(old_hook);
    report.cases = opts.cases;
    report.per_target = by_target
        .iter()
        .zip(&counts)
        .map(|((t, _), &c)| (t.ext().to_string(), c))
        .collect();
    report.seconds = t0.elapsed().as_secs_f64();
    Ok(report)
}
