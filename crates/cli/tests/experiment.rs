//! `parallax run | report | merge` end to end: bad experiment files fail before any work with
//! the file, line and key; a run's rows equal the bench's own; sharded runs (`run` sweeps and
//! `upsample`) merged equal one unsharded run byte for byte; the report opens in headless
//! Chromium with every image and plot (skipped, with the reason, without a browser).

#[allow(dead_code)]
mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use common::{out_dir, stderr, tree};

/// Scheduler variables that would shard a run by themselves.
const SHARD_ENV: [&str; 4] = [
    "SLURM_ARRAY_TASK_ID",
    "SLURM_ARRAY_TASK_MIN",
    "SLURM_ARRAY_TASK_COUNT",
    "JOB_COMPLETION_INDEX",
];

fn parallax_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_parallax"));
    c.args(args);
    for k in SHARD_ENV {
        c.env_remove(k);
    }
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().expect("binary runs")
}

fn parallax(args: &[&str]) -> Output {
    parallax_env(args, &[])
}

fn ok(o: &Output) {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        stderr(o)
    );
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

const TINY: &str = r#"title = "tiny warp"
bench = "warp"
[args]
scene = "cornell"
width = 48
height = 27
method = "quadtree,dda"
layers = [1, 2]
[sweep]
ipd = [0.065, 0.1, 0.13]
[images]
command = "warp"
method = "quadtree"
layers = 2
"#;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn assert_same_tree(a: &Path, b: &Path) {
    let (ta, tb) = (tree(a), tree(b));
    let names = |t: &[(PathBuf, Vec<u8>)]| t.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&ta), names(&tb), "same files");
    for ((n, x), (_, y)) in ta.iter().zip(&tb) {
        assert!(x == y, "{} differs", n.display());
    }
}

fn error_of(dir: &Path, name: &str, text: &str) -> String {
    let f = write(dir, name, text);
    let out = dir.join(format!("{name}.out"));
    let o = parallax(&["--quiet", "run", s(&f), "--out", s(&out)]);
    assert!(!o.status.success(), "{name} should fail");
    assert!(!out.exists(), "{name}: no work before the error");
    stderr(&o)
}

#[test]
fn bad_experiment_files_fail_before_any_work() {
    let d = out_dir("experiment", "bad");
    let m = error_of(&d, "tech.toml", "bench = \"warpp\"\n");
    assert!(
        m.contains("tech.toml:1")
            && m.contains("unknown bench \"warpp\"")
            && m.contains("upsample"),
        "{m}"
    );
    let m = error_of(&d, "empty.toml", "bench = \"warp\"\n[sweep]\nipd = []\n");
    assert!(
        m.contains("empty.toml:3") && m.contains("empty sweep"),
        "{m}"
    );
    let big: Vec<String> = (0..1000).map(|i| i.to_string()).collect();
    let big = big.join(",");
    let m = error_of(
        &d,
        "big.toml",
        &format!("bench = \"warp\"\n[sweep]\na = [{big}]\nb = [{big}]\nc = [{big}]\n"),
    );
    assert!(m.contains("1000000000 points"), "{m}");
    let m = error_of(
        &d,
        "scene.toml",
        "bench = \"warp\"\n[args]\nwidth = 8\nscene = \"no/such/scene.glb\"\n",
    );
    assert!(
        m.contains("scene.toml:4") && m.contains("no/such/scene.glb") && m.contains("atrium"),
        "{m}"
    );
    let m = error_of(&d, "key.toml", "bench = \"warp\"\n[args]\nwidht = 8\n");
    assert!(
        m.contains("key.toml:3") && m.contains("unknown key") && m.contains("width"),
        "{m}"
    );
    let m = error_of(
        &d,
        "type.toml",
        "bench = \"warp\"\n[args]\nwidth = \"wide\"\n",
    );
    assert!(
        m.contains("type.toml:3") && m.contains("`width`") && m.contains("<WIDTH>"),
        "{m}"
    );
    let m = error_of(&d, "bool.toml", "bench = \"vr\"\n[args]\nssaa = 1\n");
    assert!(
        m.contains("bool.toml:3") && m.contains("expected a boolean"),
        "{m}"
    );
    let m = error_of(
        &d,
        "img.toml",
        "bench = \"warp\"\n[images]\ncommand = \"run\"\n",
    );
    assert!(
        m.contains("img.toml:3") && m.contains("unknown image command"),
        "{m}"
    );
    // The last point's line is checked too, before the first runs.
    let m = error_of(
        &d,
        "late.toml",
        "bench = \"warp\"\n[args]\nwidth = 8\nheight = 8\nscene = \"cornell\"\n[sweep]\nlayers = [1, 99]\n",
    );
    assert!(m.contains("late.toml:7") && m.contains("layers"), "{m}");
}

#[test]
fn run_rows_equal_the_bench_and_shards_merge_byte_for_byte() {
    let d = out_dir("experiment", "run");
    let exp = write(&d, "tiny.toml", TINY);
    let whole = d.join("whole");
    ok(&parallax(&[
        "--quiet",
        "run",
        s(&exp),
        "--out",
        s(&whole),
        "--mask-timings",
    ]));
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("results.json")).unwrap())
            .unwrap();
    let points = results["points"].as_array().unwrap();
    assert_eq!(points.len(), 3);
    // Point 1's rows are `parallax bench warp`'s, field by field but the timings.
    let bench_json = d.join("bench.json");
    ok(&parallax(&[
        "--quiet",
        "bench",
        "warp",
        "--scene=cornell",
        "--width=48",
        "--height=27",
        "--method=quadtree,dda",
        "--layers=1,2",
        "--ipd=0.1",
        "--json",
        s(&bench_json),
    ]));
    let mut bench: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&bench_json).unwrap()).unwrap();
    parallax_experiment::results::mask_timings(&mut bench);
    assert_eq!(points[1]["rows"], bench);
    assert_eq!(points[1]["rows"].as_array().unwrap().len(), 4);
    let imgs: Vec<&str> = points[1]["images"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(
        imgs.contains(&"points/p0001/left.png") && imgs.contains(&"points/p0001/left.bvh.png"),
        "{imgs:?}"
    );
    assert!(whole.join("index.html").exists());

    // Shard 0 by flag, shard 1 by the Slurm variables, merged.
    let s0 = d.join("s0");
    let s1 = d.join("s1");
    ok(&parallax(&[
        "--quiet",
        "run",
        s(&exp),
        "--out",
        s(&s0),
        "--mask-timings",
        "--shard",
        "0/2",
    ]));
    ok(&parallax_env(
        &["--quiet", "run", s(&exp), "--out", s(&s1), "--mask-timings"],
        &[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
    ));
    assert!(s0.join("points/p0002").exists() && !s0.join("points/p0001").exists());
    let merged = d.join("merged");
    let o = parallax(&["--quiet", "merge", s(&s0), "--out", s(&merged)]);
    assert!(
        !o.status.success() && stderr(&o).contains("missing"),
        "{}",
        stderr(&o)
    );
    let merged = d.join("merged2");
    ok(&parallax(&[
        "--quiet",
        "merge",
        s(&s0),
        s(&s1),
        "--out",
        s(&merged),
    ]));
    assert_same_tree(&whole, &merged);
}

#[test]
fn upsample_shards_merge_byte_for_byte() {
    let d = out_dir("experiment", "upsample");
    let base = [
        "--quiet", "upsample", "--scene", "cornell", "--width", "40", "--height", "24", "--frames",
        "10", "--truth",
    ];
    let whole = d.join("whole");
    let mut args = base.to_vec();
    args.extend(["--out", s(&whole)]);
    ok(&parallax(&args));
    let parts: Vec<PathBuf> = (0..3).map(|i| d.join(format!("s{i}"))).collect();
    let run = |i: usize, extra: &[&str], env: &[(&str, &str)]| {
        let mut a = base.to_vec();
        a.extend(["--out", s(&parts[i])]);
        a.extend(extra);
        ok(&parallax_env(&a, env));
    };
    run(0, &["--shard", "0/3"], &[]);
    run(
        1,
        &[],
        &[
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ],
    );
    run(2, &["--shard-count", "3"], &[("JOB_COMPLETION_INDEX", "2")]);
    assert!(parts[2].join("frame_0009.png").exists() && !parts[2].join("frame_0000.png").exists());
    let merged = d.join("merged");
    ok(&parallax(&[
        "--quiet",
        "merge",
        s(&parts[0]),
        s(&parts[1]),
        s(&parts[2]),
        "--out",
        s(&merged),
    ]));
    assert_eq!(tree(&whole).len(), 10 + 7 + 7, "frames, hit maps, truths");
    assert_same_tree(&whole, &merged);
}

/// The first browser on PATH.
fn browser() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for name in ["chromium", "chromium-browser", "google-chrome"] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Opens `page` headless; returns the dumped DOM's self-check attributes and writes a
/// screenshot.
fn check_in_browser(chrome: &Path, page: &Path, shot: &Path) -> String {
    let url = format!("file://{}", page.canonicalize().unwrap().display());
    let common = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--no-first-run",
        "--disable-extensions",
        "--virtual-time-budget=10000",
    ];
    let o = Command::new(chrome)
        .args(common)
        .arg("--dump-dom")
        .arg(&url)
        .output()
        .expect("browser runs");
    let dom = String::from_utf8_lossy(&o.stdout).into_owned();
    let o2 = Command::new(chrome)
        .args(common)
        .args(["--hide-scrollbars", "--window-size=1280,2000"])
        .arg(format!("--screenshot={}", shot.display()))
        .arg(&url)
        .output()
        .expect("browser runs");
    assert!(o2.status.success(), "screenshot: {}", stderr(&o2));
    let png = image::open(shot).expect("a screenshot").to_rgb8();
    let first = png.get_pixel(0, 0);
    assert!(
        png.pixels().any(|p| p != first),
        "the screenshot is not blank"
    );
    let at = dom
        .find("id=\"selfcheck\"")
        .unwrap_or_else(|| panic!("no self-check in the DOM: {}", stderr(&o)));
    dom[at..].split('>').next().unwrap().to_string()
}

fn attr(tag: &str, name: &str) -> String {
    let key = format!("{name}=\"");
    let at = tag.find(&key).unwrap_or_else(|| panic!("{name} in {tag}")) + key.len();
    tag[at..].split('"').next().unwrap().to_string()
}

#[test]
fn report_opens_in_headless_chromium() {
    let Some(chrome) = browser() else {
        println!(
            "skipped: no chromium, chromium-browser or google-chrome on PATH (.ci/run installs Debian's chromium)"
        );
        return;
    };
    let d = out_dir("experiment", "browser");
    let exp = write(
        &d,
        "tiny.toml",
        &TINY.replace("ipd = [0.065, 0.1, 0.13]", "ipd = [0.065, 0.13]"),
    );
    let out = d.join("run");
    ok(&parallax(&["--quiet", "run", s(&exp), "--out", s(&out)]));
    let tag = check_in_browser(&chrome, &out.join("index.html"), &d.join("report.png"));
    assert_eq!(attr(&tag, "data-status"), "ok", "{tag}");
    assert_eq!(attr(&tag, "data-broken"), "0", "{tag}");
    assert!(
        attr(&tag, "data-images").parse::<u32>().unwrap() >= 20,
        "{tag}"
    );
    assert!(
        attr(&tag, "data-plots").parse::<u32>().unwrap() >= 2,
        "{tag}"
    );
    // The inlined page of the same results, and the gallery of an image folder.
    let inline = d.join("inline.html");
    ok(&parallax(&[
        "--quiet",
        "report",
        s(&out),
        "--out",
        s(&inline),
        "--inline",
    ]));
    let tag = check_in_browser(&chrome, &inline, &d.join("inline.png"));
    assert_eq!(attr(&tag, "data-status"), "ok", "{tag}");
    let warp = d.join("warp");
    ok(&parallax(&[
        "--quiet",
        "warp",
        "--scene",
        "cornell",
        "--width",
        "48",
        "--height",
        "27",
        "--out",
        s(&warp),
    ]));
    ok(&parallax(&["--quiet", "report", s(&warp)]));
    let tag = check_in_browser(&chrome, &warp.join("index.html"), &d.join("gallery.png"));
    assert_eq!(attr(&tag, "data-status"), "ok", "{tag}");
    // A broken image is caught (the check can fail).
    let html = std::fs::read_to_string(warp.join("index.html")).unwrap();
    std::fs::write(
        warp.join("broken.html"),
        html.replacen("src=\"left.png\"", "src=\"missing.png\"", 1),
    )
    .unwrap();
    let tag = check_in_browser(&chrome, &warp.join("broken.html"), &d.join("broken.png"));
    assert_eq!(attr(&tag, "data-status"), "fail", "{tag}");
    assert_eq!(attr(&tag, "data-broken"), "1", "{tag}");
}

#[test]
fn memory_budget_refuses_before_allocating() {
    let o = parallax(&[
        "--quiet",
        "warp",
        "--scene",
        "cornell",
        "--width",
        "16384",
        "--height",
        "16384",
        "--layers",
        "8",
        "--no-score",
    ]);
    let m = stderr(&o);
    assert!(
        !o.status.success() && m.contains("GiB") && m.contains("--memory-budget-gib 16"),
        "{m}"
    );
    let o = parallax(&[
        "--quiet",
        "bench",
        "upsample",
        "--width",
        "4000",
        "--height",
        "4000",
        "--layers",
        "1,8",
        "--memory-budget-gib",
        "1",
    ]);
    assert!(
        !o.status.success() && stderr(&o).contains("8 layer(s)"),
        "{}",
        stderr(&o)
    );
}

/// Every example experiment still parses against the benches' flags (a renamed flag or a
/// removed scene fails here, not in a user's run); from the repository root, where the files'
/// `../shared/scenes` paths resolve.
#[test]
fn every_example_experiment_checks_in_a_dry_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("experiments"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 9, "{files:?}");
    let scenes = root.join("../shared/scenes");
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        if text.contains("../shared/scenes") && !scenes.is_dir() {
            eprintln!(
                "{}: skipped, ../shared/scenes is not beside the repository",
                f.display()
            );
            continue;
        }
        let mut c = Command::new(env!("CARGO_BIN_EXE_parallax"));
        c.current_dir(&root).args(["run", "--dry-run", s(&f)]);
        for k in SHARD_ENV {
            c.env_remove(k);
        }
        let o = c.output().expect("binary runs");
        ok(&o);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(out.contains("point(s) checked"), "{}: {out}", f.display());
    }
}
