//! End-to-end runs of `parallax warp`, `parallax upsample` and `parallax bench warp |
//! upsample | compression` at tiny sizes with the brute-force tracer: files, printed scores,
//! JSON rows, unavailable methods as rows, and clean errors on bad input.

mod common;

use common::{parallax, stderr};

fn out_dir(name: &str) -> common::TestDir {
    common::out_dir("warp", name)
}

fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn psnr_of(out: &str) -> f64 {
    out.split("PSNR ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no PSNR in {out}"))
}

const TINY: [&str; 4] = ["--width", "40", "--height", "30"];

#[test]
fn warp_writes_eyes_and_scores() {
    let d = out_dir("eyes");
    let mut args = vec!["warp", "--method", "brute", "--layers", "2", "--ipd", "0.2"];
    args.extend(TINY);
    args.extend(["--out", d.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "reference.png",
        "left.png",
        "right.png",
        "left.hits.png",
        "right.heat.png",
        "left.bvh.png",
    ] {
        assert!(d.join(f).is_file(), "{f} missing");
    }
    let psnr = psnr_of(&stdout(&o));
    assert!(psnr > 12.0 && psnr < 60.0, "{psnr}");
}

#[test]
fn zero_ipd_is_allowed_and_exact() {
    let d = out_dir("zero");
    let mut args = vec!["warp", "--method", "brute", "--layers", "1", "--ipd", "0"];
    args.extend(TINY);
    args.extend(["--out", d.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    // The reference's layer 0 is rasterized, the truth ray traced: equal up to float noise.
    assert!(psnr_of(&stdout(&o)) > 60.0, "{}", stdout(&o));
}

#[test]
fn color_depth_input_warps() {
    let d = out_dir("input");
    let exr = d.join("frame.exr");
    let mut args = vec![
        "render",
        "--quiet",
        "--aov",
        "depth",
        "--out",
        exr.to_str().unwrap(),
    ];
    args.extend(TINY);
    assert!(parallax(&args).status.success());
    let e = exr.to_str().unwrap();
    let w = d.join("w");
    let o = parallax(&[
        "warp",
        "--method",
        "brute",
        "--color",
        e,
        "--depth",
        e,
        "--focal-px",
        "30",
        "--out",
        w.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(w.join("left.png").is_file() && !w.join("left.bvh.png").exists());
    // Missing depth file, colour without depth.
    let o = parallax(&[
        "warp",
        "--method",
        "brute",
        "--color",
        e,
        "--depth",
        "/nonexistent/d.exr",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("d.exr"), "{}", stderr(&o));
    let o = parallax(&["warp", "--method", "brute", "--color", e]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--depth"), "{}", stderr(&o));
}

#[test]
fn bad_arguments_fail_cleanly() {
    let cases: [(&[&str], &str); 6] = [
        (&["warp", "--method", "raytrace"], "unknown method"),
        (&["warp", "--method", "brute", "--ipd=-0.1"], "--ipd"),
        (&["warp", "--method", "brute", "--layers", "0"], "--layers"),
        (
            &[
                "warp", "--method", "dda", "--layers", "3", "--width", "16", "--height", "12",
            ],
            "1 or 2 layers",
        ),
        (
            &["upsample", "--method", "brute", "--frames", "-3"],
            "--frames",
        ),
        (
            &["bench", "warp", "--method", "brute,nope"],
            "unknown method",
        ),
    ];
    for (args, want) in cases {
        let o = parallax(args);
        assert!(!o.status.success(), "{args:?} succeeded");
        let e = stderr(&o);
        assert!(e.contains(want), "{args:?}: {e}");
        assert!(!e.contains("panicked"), "{args:?}: {e}");
    }
}

#[test]
fn upsample_writes_frames() {
    let d = out_dir("up");
    let mut args = vec![
        "upsample", "--method", "brute", "--frames", "6", "--layers", "2",
    ];
    args.extend(TINY);
    args.extend(["--out", d.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    for i in 0..6 {
        assert!(d.join(format!("frame_{i:04}.png")).is_file());
    }
    assert!(d.join("frame_0001.hits.png").is_file() && !d.join("frame_0004.hits.png").exists());
    assert!(stdout(&o).contains("2 references"), "{}", stdout(&o));
    assert!(stdout(&o).contains("mean PSNR"));
}

fn json_rows(path: &std::path::Path) -> Vec<serde_json::Value> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    v.as_array().unwrap().clone()
}

#[test]
fn bench_warp_rows() {
    let d = out_dir("bw");
    let j = d.join("rows.json");
    let mut args = vec![
        "bench",
        "warp",
        "--method",
        "quadtree,mesh,brute",
        "--layers",
        "1,2",
    ];
    args.extend(TINY);
    args.extend(["--json", j.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = json_rows(&j);
    // quadtree x2, mesh once, brute x2.
    assert_eq!(rows.len(), 5, "{rows:?}");
    for r in &rows {
        let m = r["method"].as_str().unwrap();
        if m == "quadtree" {
            // Either an error row (not in this build) or numbers.
            assert!(r.get("error").is_some() || r["psnr"].as_f64().is_some());
        } else {
            assert!(r.get("error").is_none(), "{r}");
            assert!(r["psnr"].as_f64().unwrap() > 10.0, "{r}");
            assert!(r["ms_ref"].as_f64().unwrap() > 0.0);
        }
    }
    let deep = rows
        .iter()
        .find(|r| r["method"] == "brute" && r["layers"] == 2)
        .unwrap();
    assert!(deep["pct_layer2"].as_f64().unwrap() >= 0.0);
    assert!(stdout(&o).contains("| brute | 2 |"));
}

#[test]
fn bench_upsample_and_compression_rows() {
    let d = out_dir("bu");
    let j = d.join("up.json");
    let mut args = vec![
        "bench", "upsample", "--method", "brute", "--layers", "1", "--frames", "5",
    ];
    args.extend(TINY);
    args.extend(["--json", j.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = json_rows(&j);
    assert_eq!(rows.len(), 1);
    assert_eq!(rows[0]["frames"], 5);
    assert!(rows[0]["psnr"].as_f64().unwrap() > 10.0);
    let j = d.join("comp.json");
    let mut args = vec!["bench", "compression", "--method", "brute", "--no-score"];
    args.extend(TINY);
    args.extend(["--json", j.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows = json_rows(&j);
    assert_eq!(rows.len(), 21);
    assert!(rows.iter().any(|r| r["adaptive"] == true));
}

#[test]
fn near_plane_trace_pass_and_dda_sweep() {
    let d = out_dir("near");
    let j = d.join("rows.json");
    let mut args = vec![
        "bench",
        "warp",
        "--method",
        "dda,brute,mesh",
        "--layers",
        "1",
        "--near",
        "0.1",
        "--dda-sweep",
        "2,200",
        "--repeats",
        "2",
    ];
    args.extend(TINY);
    args.extend(["--json", j.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("cube near: camera 0.1 m"), "{out}");
    assert!(out.contains("minimal max steps"), "{out}");
    let rows = json_rows(&j);
    // dda x2 (the sweep), brute, mesh.
    assert_eq!(rows.len(), 4, "{rows:?}");
    for r in &rows {
        assert_eq!(r["cube_near"], "camera 0.1 m", "{r}");
        assert!((r["near_m"].as_f64().unwrap() - 0.1).abs() < 1e-6, "{r}");
        assert_eq!(r["repeats"], 2);
        if r["method"] == "mesh" {
            assert!(r["trace_mrays_per_s"].is_null(), "{r}"); // NaN: no tracer
        } else {
            assert!(r["trace_mrays_per_s"].as_f64().unwrap() > 0.0, "{r}");
            assert!(r["ms_trace"].as_f64().unwrap() > 0.0, "{r}");
            assert!(r["ms_raygen"].as_f64().unwrap() >= 0.0, "{r}");
        }
    }
    let steps: Vec<_> = rows
        .iter()
        .filter(|r| r["method"] == "dda")
        .map(|r| r["dda_max_steps"].as_u64().unwrap())
        .collect();
    assert_eq!(steps, [2, 200]);
    // Two steps from a 0.1 m near plane cannot reach the surfaces: more misses / occlusion
    // volumes than with 200.
    let lost = |k: usize| {
        let r = &rows[k];
        r["pct_miss"].as_f64().unwrap() + r["pct_occlusion"].as_f64().unwrap()
    };
    assert!(lost(0) > lost(1) + 1.0, "{rows:?}");

    // The other commands take the flag too and record it.
    let j = d.join("up.json");
    let mut args = vec![
        "bench",
        "upsample",
        "--method",
        "brute",
        "--layers",
        "1",
        "--frames",
        "2",
        "--near",
        "0.2",
        "--no-score",
    ];
    args.extend(TINY);
    args.extend(["--json", j.to_str().unwrap()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json_rows(&j)[0]["cube_near"], "camera 0.2 m");
    let mut args = vec![
        "warp",
        "--method",
        "brute",
        "--layers",
        "1",
        "--near",
        "0.1",
        "--no-score",
    ];
    args.extend(TINY);
    args.extend(["--out", d.join("w").to_str().unwrap().to_owned().leak()]);
    let o = parallax(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("cube near camera 0.1 m"),
        "{}",
        stdout(&o)
    );
    for bad in ["0", "-1", "near"] {
        let flag = format!("--near={bad}");
        let o = parallax(&["warp", "--method", "brute", &flag]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains("near"), "{}", stderr(&o));
    }
}
