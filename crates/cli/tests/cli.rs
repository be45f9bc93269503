//! End-to-end runs of the `parallax` binary on built-in scenes, and its error cases.

mod common;

use common::{parallax, stderr};

fn out_dir(name: &str) -> common::TestDir {
    common::out_dir("cli", name)
}

#[test]
fn scenes_lists_the_builtins() {
    let o = parallax(&["scenes"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    for name in ["atrium", "cornell", "foliage"] {
        assert!(s.contains(name), "{s}");
    }
}

#[test]
fn info_prints_counts() {
    let o = parallax(&["info", "cornell"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("triangles") && s.contains("cameras"), "{s}");
}

#[test]
fn render_png_exr_with_aovs_and_stats() {
    let d = out_dir("render");
    let exr = d.join("a.exr");
    let stats = d.join("s.json");
    let o = parallax(&[
        "render",
        "--quiet",
        "--scene",
        "cornell",
        "--width",
        "40",
        "--height",
        "30",
        "--out",
        exr.to_str().unwrap(),
        "--aov",
        "depth,normal,albedo,id",
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = parallax_core::image::exr::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (40, 30));
    for c in [
        "R", "G", "B", "depth", "normal.X", "normal.Y", "normal.Z", "albedo.R", "albedo.G",
        "albedo.B", "id",
    ] {
        assert!(img.channel(c).is_some(), "missing channel {c}");
    }
    // The Cornell box's front camera sees the box everywhere: finite positive depths.
    let depth = img.channel("depth").unwrap();
    let hits = depth.iter().filter(|d| d.is_finite() && **d > 0.0).count();
    assert!(hits > depth.len() / 2, "{hits} of {}", depth.len());
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    for k in ["rays", "seconds", "mrays_per_s", "build_ms", "stages"] {
        assert!(json.get(k).is_some(), "stats lack {k}: {json}");
    }
    assert!(json["rays"].as_u64().unwrap() >= 1200);

    let png = d.join("b.png");
    let o = parallax(&[
        "render",
        "--quiet",
        "--scene",
        "atrium",
        "--model",
        "fisheye",
        "--width",
        "42",
        "--height",
        "26",
        "--out",
        png.to_str().unwrap(),
        "--aov",
        "depth",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.exists() && d.join("b.depth.png").exists());
}

#[test]
fn negative_coordinates_parse_in_both_spellings() {
    let d = out_dir("coords");
    for eye in [
        &["--eye", "-1.5", "0.8", "-0.2"][..],
        &["--eye=-1.5,0.8,-0.2"][..],
    ] {
        let p = d.join("c.png");
        let mut args = vec![
            "render", "--quiet", "--scene", "cornell", "--width", "8", "--height", "6",
        ];
        args.extend_from_slice(eye);
        args.extend_from_slice(&["--target", "0", "1", "0", "--out", p.to_str().unwrap()]);
        let o = parallax(&args);
        assert!(o.status.success(), "{eye:?}: {}", stderr(&o));
    }
}

#[test]
fn every_camera_model_renders() {
    let d = out_dir("models");
    for m in [
        "pinhole",
        "ortho",
        "thinlens",
        "stereo",
        "cube",
        "equirect",
        "fisheye",
        "distorted",
    ] {
        let p = d.join(format!("{m}.png"));
        let o = parallax(&[
            "render",
            "--quiet",
            "--scene",
            "cornell",
            "--model",
            m,
            "--width",
            "24",
            "--height",
            "16",
            "--out",
            p.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{m}: {}", stderr(&o));
        assert!(p.exists(), "{m}");
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let d = out_dir("errors");
    let p = d.join("x.png");
    let p = p.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (
            &["render", "--scene", "cornell", "--width", "0", "--out", p],
            "width and height must be at least 1",
        ),
        (
            &[
                "render", "--scene", "cornell", "--width", "100000", "--height", "100000", "--out",
                p,
            ],
            "2^28",
        ),
        (
            &["render", "--scene", "no-such-scene", "--out", p],
            "unknown scene",
        ),
        (
            &["render", "--scene", "/nonexistent/x.glb", "--out", p],
            "x.glb",
        ),
        (
            &["render", "--scene", "cornell", "--out", "x.jpg"],
            ".png or .exr",
        ),
        (
            &[
                "render", "--scene", "cornell", "--camera", "nope", "--out", p,
            ],
            "no camera \"nope\"",
        ),
        (
            &[
                "render", "--scene", "cornell", "--eye", "0,0,0", "--target", "0,0,0", "--out", p,
            ],
            "target must differ",
        ),
        (
            &[
                "render", "--scene", "cornell", "--model", "banana", "--out", p,
            ],
            "unknown camera model",
        ),
        (
            &["render", "--scene", "cornell", "--spp", "0", "--out", p],
            "--spp",
        ),
        (
            &[
                "reflect",
                "--scene",
                "mirrors-open",
                "--spp",
                "0",
                "--out",
                p,
            ],
            "rays per pixel must be a square",
        ),
        (
            &[
                "reflect",
                "--scene",
                "mirrors-open",
                "--spp",
                "1000",
                "--out",
                p,
            ],
            "rays per pixel must be a square",
        ),
        (
            &["bench", "reflect", "--scene", "mirrors", "--spp", "1,5"],
            "rays per pixel must be a square",
        ),
    ];
    for (args, needle) in cases {
        let o = parallax(args);
        assert!(!o.status.success(), "{args:?} should fail");
        let e = stderr(&o);
        assert!(e.contains(needle), "{args:?}: expected {needle:?} in {e:?}");
        assert!(!e.contains("panicked"), "{args:?} panicked: {e}");
    }
}

/// `bench rays` builds the SBVH by default; `--no-spatial-splits` the object-split tree; the
/// old `--spatial-splits` (now the default) is still accepted, but not with its opposite.
#[test]
fn bench_rays_spatial_split_flags() {
    let run = |extra: &[&str]| {
        let mut args = vec![
            "bench",
            "rays",
            "--scene",
            "cornell",
            "--width",
            "16",
            "--height",
            "12",
            "--repeats",
            "1",
            "--no-msaa",
            "--methods",
            "single",
        ];
        args.extend_from_slice(extra);
        parallax(&args)
    };
    for ok in [&[][..], &["--no-spatial-splits"], &["--spatial-splits"]] {
        let o = run(ok);
        assert!(o.status.success(), "{ok:?}: {}", stderr(&o));
    }
    let o = run(&["--spatial-splits", "--no-spatial-splits"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("cannot be used with"), "{}", stderr(&o));
}

#[test]
fn bench_rays_writes_json_rows() {
    let d = out_dir("bench");
    let j = d.join("rays.json");
    let o = parallax(&[
        "bench",
        "rays",
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "24",
        "--repeats",
        "1",
        "--json",
        j.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    // Without the `embree` feature the bench says how to get Embree's rows.
    assert_eq!(
        !parallax_embree::ENABLED,
        out.contains("--features embree"),
        "{out}"
    );
    let rows: serde_json::Value = serde_json::from_slice(&std::fs::read(&j).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    let has = |mode: &str, method: &str| {
        rows.iter()
            .any(|r| r["mode"] == mode && r["method"] == method)
    };
    assert!(has("build", "bvh"));
    for mode in ["primary", "msaa16", "random"] {
        for method in ["bvh single", "bvh packet16", "bvh4 single", "bvh4 packet16"] {
            assert!(has(mode, method), "no {mode} / {method} row");
        }
        assert_eq!(parallax_embree::ENABLED, has(mode, "embree rtcIntersect16"));
    }
    for r in rows.iter().filter(|r| r["mode"] != "build") {
        for k in [
            "mode",
            "method",
            "scene",
            "rays",
            "build_ms",
            "trace_ms",
            "mrays_per_s",
            "same_prim",
            "same_t",
            "hit_rate",
            "threads",
        ] {
            assert!(r.get(k).is_some(), "row lacks {k}: {r}");
        }
        assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0);
        // Every parallax method returns exactly the single-ray answers.
        if r["method"].as_str().unwrap().starts_with("bvh") {
            assert_eq!(r["same_prim"].as_f64(), Some(1.0), "{r}");
        }
    }
}
