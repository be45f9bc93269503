//! End-to-end runs of `parallax vr` and `parallax bench vr` at tiny sizes, and their errors.

mod common;

use common::{parallax, stderr};

fn out_dir(name: &str) -> common::TestDir {
    common::out_dir("vr", name)
}

fn png_size(p: &std::path::Path) -> (u32, u32) {
    let img = parallax_core::image::png::read_image(p).unwrap();
    (img.width(), img.height())
}

#[test]
fn vr_writes_both_eyes_and_the_pattern_with_stats() {
    let d = out_dir("frame");
    let stats = d.join("s.json");
    let o = parallax(&[
        "vr",
        "--scene",
        "cornell",
        "--preset",
        "rift-cv1",
        "--msaa",
        "4",
        "--subpixel",
        "--width",
        "64",
        "--height",
        "48",
        "--time",
        "0.5",
        "--out",
        d.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["left.png", "right.png", "pattern.png"] {
        assert_eq!(png_size(&d.join(f)), (64, 48), "{f}");
    }
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("shades") && out.contains("refit"), "{out}");
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    // Subpixel: three samples per pixel per eye, four rays each.
    assert_eq!(json["samples"].as_u64().unwrap(), 2 * 64 * 48 * 3);
    assert_eq!(json["rays"].as_u64().unwrap(), 2 * 64 * 48 * 3 * 4);
    let spp = json["shades_per_nonempty_pixel"].as_f64().unwrap();
    assert!((1.0..=4.0).contains(&spp), "{spp}");
}

#[test]
fn vr_presets_dof_and_ssaa_run() {
    for extra in [
        &["--preset", "vive"][..],
        &["--preset", "wide-210x130", "--ssaa"],
        &["--preset", "custom", "--model", "pinhole", "--fov-y", "70"],
        &["--dof-aperture", "0.003", "--dof-focus", "0.5"],
        &["--foveated", "--gaze", "0.2,0.1", "--visibility", "beam"],
        &["--foveated", "--subpixel", "--visibility", "beam"],
    ] {
        let d = out_dir(&format!("p{}", extra.len()));
        let mut args = vec![
            "vr", "--quiet", "--scene", "cornell", "--msaa", "4", "--width", "40", "--height",
            "30", "--out",
        ];
        let ds = d.to_str().unwrap().to_string();
        args.push(&ds);
        args.extend_from_slice(extra);
        let o = parallax(&args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        assert_eq!(png_size(&d.join("left.png")), (40, 30), "{extra:?}");
    }
}

/// A turning head over three frames: the beam caster's hierarchy built for the first and
/// moved for the others. The first frame is the single-frame render; the exact beam caster
/// (`beam-exact`, bit-identical to per-ray traversal) gives per-ray's images on every frame,
/// so the moved hierarchies culled nothing they should not; the head does turn.
#[test]
fn vr_frames_of_a_turning_head_move_the_hierarchy() {
    let run = |name: &str, extra: &[&str]| {
        let d = out_dir(name);
        let stats = d.join("s.json");
        let mut a = vec![
            "vr", "--scene", "cornell", "--preset", "vive", "--msaa", "4", "--width", "40",
            "--height", "32", "--out",
        ];
        a.push(d.to_str().unwrap());
        a.extend_from_slice(&["--stats", stats.to_str().unwrap()]);
        a.extend_from_slice(extra);
        let o = parallax(&a);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
        (d, String::from_utf8_lossy(&o.stdout).into_owned(), json)
    };
    let seq = ["--frames", "3", "--turn", "8"];
    let (single, ..) = run("frames-single", &["--visibility", "beam-exact"]);
    let (exact, out, json) = run(
        "frames-exact",
        &[&seq[..], &["--visibility", "beam-exact"]].concat(),
    );
    let (per_ray, ..) = run(
        "frames-per-ray",
        &[&seq[..], &["--visibility", "per-ray"]].concat(),
    );
    assert!(out.contains("moved"), "{out}");
    let frames = json["frames"].as_array().unwrap();
    let turns: Vec<f64> = frames
        .iter()
        .map(|f| f["turn_deg"].as_f64().unwrap())
        .collect();
    assert_eq!(turns, [0.0, 4.0, 8.0]);
    let read = |d: &common::TestDir, f: &str| std::fs::read(d.join(f)).unwrap();
    assert_eq!(read(&single, "left.png"), read(&exact, "left_000.png"));
    for f in 0..3 {
        for eye in ["left", "right"] {
            let file = format!("{eye}_{f:03}.png");
            assert!(
                read(&exact, &file) == read(&per_ray, &file),
                "{file} differs from per-ray"
            );
        }
    }
    assert!(
        read(&exact, "left_000.png") != read(&exact, "left_002.png"),
        "the head did not turn"
    );
}

#[test]
fn vr_rejects_bad_flags_clearly() {
    let d = out_dir("bad");
    let ds = d.to_str().unwrap();
    for (args, needle) in [
        (&["--msaa", "3"][..], "1, 4, 8, 16, 32"),
        (&["--foveated", "--gaze", "1.5,0"], "[-1, 1]"),
        (&["--dof-aperture", "-0.1"], "aperture"),
        (&["--visibility", "magic"], "per-ray or beam"),
        (&["--preset", "quest"], "rift-cv1"),
        (&["--preset", "wide-210x130", "--subpixel"], "distorted"),
        (&["--frames", "0"], "--frames"),
        (&["--frames", "2", "--turn", "nan"], "--turn"),
        (&["--frames", "2", "--turn", "400"], "360"),
    ] {
        let mut a = vec![
            "vr", "--scene", "cornell", "--width", "8", "--height", "8", "--out", ds,
        ];
        a.extend_from_slice(args);
        let o = parallax(&a);
        assert!(!o.status.success(), "{args:?} should fail");
        let e = stderr(&o);
        assert!(e.contains(needle), "{args:?}: {e}");
    }
}

#[test]
fn bench_vr_rows_for_both_visibility_methods() {
    let d = out_dir("bench");
    let json = d.join("b.json");
    let o = parallax(&[
        "bench",
        "vr",
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "24",
        "--msaa",
        "4",
        "--schemes",
        "normal,post-distort,foveated",
        "--ssaa",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let u = &v["update"];
    assert!(u["moving_vertices"].as_u64().unwrap() > 0, "{u}");
    assert!(u["refit_ms"].as_f64().unwrap() >= 0.0);
    let rows = v["rows"].as_array().unwrap();
    // 3 schemes x 2 methods x 2 shading modes.
    assert_eq!(rows.len(), 12);
    for r in rows {
        assert!(r["available"].as_bool().unwrap(), "{r}");
        assert!(r["mrays_per_s"].as_f64().unwrap() > 0.0);
        assert!(r["shades_per_nonempty_pixel"].as_f64().unwrap() >= 1.0);
        if r["visibility"] == "beam" {
            // The beam caster reports its stages and the per-ray rate of the same rays.
            assert!(r["ms_intersect"].as_f64().is_some(), "{r}");
            assert!(r["baseline_mrays_per_s"].as_f64().unwrap() > 0.0, "{r}");
        }
    }
    // The foveated pattern casts fewer rays than the grid of the same eyes.
    let rays = |scheme: &str| {
        rows.iter().find(|r| r["scheme"] == scheme).unwrap()["rays"]
            .as_u64()
            .unwrap()
    };
    assert!(
        rays("foveated") < rays("normal"),
        "{} vs {}",
        rays("foveated"),
        rays("normal")
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("| scheme |"), "{stdout}");
}
