//! `parallax secondary` and `parallax bench ldc` end to end on the built-in Cornell box, and
//! their error messages.

mod common;

use common::{parallax, stderr};

#[test]
fn secondary_renders_both_tracers_and_writes_rows() {
    let d = common::out_dir("secondary", "run");
    let out = d.join("s.png");
    let json = d.join("s.json");
    let o = parallax(&[
        "secondary",
        "--scene",
        "cornell",
        "--width",
        "48",
        "--height",
        "36",
        "--tracer",
        "bvh,ldc",
        "--ldc-res",
        "128",
        "--bounces",
        "3",
        "--out",
        out.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["s.bvh.png", "s.ldc.png", "s.ldc_vs_bvh.png"] {
        assert!(d.join(f).exists(), "missing {f}");
    }
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let tracers = v["tracers"].as_array().unwrap();
    assert_eq!(tracers.len(), 2);
    assert!(
        tracers[1]["psnr"].as_f64().unwrap() > 25.0,
        "{}",
        tracers[1]
    );
    let rows = v["rows"].as_array().unwrap();
    for effect in ["reflect", "refract", "shadow"] {
        for method in ["bvh", "ldc"] {
            let r = rows
                .iter()
                .find(|r| r["method"] == method && r["effect"] == effect && r["bounce"] == -1)
                .unwrap_or_else(|| panic!("no {method} {effect} row"));
            assert!(r["rays"].as_u64().unwrap() > 0);
            assert!(r["agreement"].as_f64().unwrap() > 0.9, "{r}");
        }
    }
    // One tracer: exactly the given file.
    let single = d.join("only.png");
    let o = parallax(&[
        "secondary",
        "--quiet",
        "--scene",
        "cornell",
        "--width",
        "16",
        "--height",
        "12",
        "--tracer",
        "ldc",
        "--ldc-res",
        "64",
        "--out",
        single.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(single.exists());
}

#[test]
fn bench_ldc_prints_table_1_and_writes_json() {
    let d = common::out_dir("secondary", "bench");
    let json = d.join("ldc.json");
    let o = parallax(&[
        "bench",
        "ldc",
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "24",
        "--resolutions",
        "64,128",
        "--synthetic-rays",
        "2000",
        "--repeats",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("build ms (A)") && s.contains("trace ms (B)"),
        "{s}"
    );
    let rows: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rows = rows.as_array().unwrap();
    for res in [64, 128] {
        let view = rows
            .iter()
            .find(|r| r["method"] == "ldc" && r["resolution"] == res && r["rays_set"] == "view")
            .unwrap();
        assert!(view["layers"].as_u64().unwrap() >= 2, "{view}");
        assert!(view["ms_build"].as_f64().unwrap() > 0.0);
        for k in [
            "ms_peel",
            "ms_assign",
            "ms_grid",
            "ms_trace",
            "mrays_per_s",
            "psnr",
            "ssim",
            "agreement",
            "bytes_per_layer",
        ] {
            assert!(view.get(k).is_some(), "row lacks {k}");
        }
    }
    // Every disagreement of the LDC is in exactly one class (the classifier's invariant).
    for r in rows.iter().filter(|r| r["method"] == "ldc") {
        let rays = r["rays"].as_f64().unwrap();
        let disagree = (rays * (1.0 - r["agreement"].as_f64().unwrap())).round() as u64;
        let classes: u64 = r["classes"]
            .as_object()
            .unwrap()
            .values()
            .map(|v| v.as_u64().unwrap())
            .sum();
        assert_eq!(classes, disagree, "{r}");
    }
    for set in ["reflect", "refract", "shadow", "axis", "random", "surface"] {
        assert!(
            rows.iter()
                .any(|r| r["method"] == "bvh" && r["rays_set"] == set),
            "no bvh {set} row"
        );
    }
}

#[test]
fn bad_ldc_input_gives_clear_errors() {
    let d = common::out_dir("secondary", "errors");
    let p = d.join("x.png");
    let p = p.to_str().unwrap();
    let base = [
        "secondary",
        "--scene",
        "cornell",
        "--width",
        "8",
        "--height",
        "8",
        "--out",
        p,
    ];
    let cases: &[(&[&str], &str)] = &[
        (&["--ldc-eps", "0"], "--ldc-eps"),
        (&["--ldc-eps", "-1"], "--ldc-eps"),
        (&["--ldc-res", "0"], "--ldc-res"),
        (&["--ldc-res", "100000"], "--ldc-res"),
        (&["--ldc-max-layers", "1"], "layers"),
        (&["--ldc-roi=5,5,5,6,6,6"], "region of interest"),
        (&["--ldc-roi=1,2,3"], "--ldc-roi"),
        (&["--ldc-roi", "everything"], "--ldc-roi"),
        (&["--ldc-roi-margin=-1"], "--ldc-roi-margin"),
        (&["--ldc-overlap", "2"], "overlap"),
        (&["--tracer", "octree"], "unknown tracer"),
        (&["--effects", "sparkle"], "unknown effect"),
        (&["--bounces", "99"], "bounces"),
        (&["--ldc-test", "box"], "sample test"),
        (&["--model", "fisheye"], "pinhole"),
    ];
    for (extra, needle) in cases {
        let args: Vec<&str> = base.iter().chain(extra.iter()).copied().collect();
        let o = parallax(&args);
        assert!(!o.status.success(), "{extra:?} should fail");
        let e = stderr(&o);
        assert!(
            e.contains(needle),
            "{extra:?}: expected {needle:?} in {e:?}"
        );
        assert!(!e.contains("panicked"), "{extra:?} panicked: {e}");
    }
}
