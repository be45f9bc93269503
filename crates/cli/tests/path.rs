//! `parallax path` and `parallax bench path` end to end, and their error cases.

mod common;

use common::{parallax, stderr};

fn out_dir(name: &str) -> common::TestDir {
    common::out_dir("path", name)
}

#[test]
fn path_writes_exr_with_variance_and_sample_count_and_png() {
    let d = out_dir("exr");
    let exr = d.join("c.exr");
    let stats = d.join("c.json");
    let o = parallax(&[
        "--quiet",
        "path",
        "--scene",
        "cornell",
        "--width",
        "24",
        "--height",
        "16",
        "--spp",
        "3",
        "--out",
        exr.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let img = parallax_core::image::exr::read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (24, 16));
    for c in [
        "R",
        "G",
        "B",
        "variance.R",
        "variance.G",
        "variance.B",
        "samples",
    ] {
        assert!(img.channel(c).is_some(), "missing channel {c}");
    }
    assert!(img.channel("samples").unwrap().iter().all(|&n| n == 3.0));
    assert!(img.channel("R").unwrap().iter().any(|&v| v > 0.0));
    assert!(d.join("c.preview.png").exists());
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    for k in ["spp", "seconds", "paths_per_s", "mrays_per_s", "stats"] {
        assert!(json.get(k).is_some(), "stats lack {k}: {json}");
    }
    let png = d.join("c.png");
    let o = parallax(&[
        "--quiet",
        "path",
        "--scene",
        "atrium",
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "1",
        "--time-budget",
        "30",
        "--materials",
        "diffuse",
        "--env",
        "0.5",
        "--point=1,3,-2",
        "--point-intensity",
        "5",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(png.exists());
}

#[test]
fn an_unlit_scene_gets_the_default_sky_with_a_message() {
    let scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/scenes/box_textured/BoxTextured.glb"
    );
    if !std::path::Path::new(scene).exists() {
        return;
    }
    let d = out_dir("sky");
    let o = parallax(&[
        "path",
        "--scene",
        scene,
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--out",
        d.join("b.png").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("default sky"), "{}", stderr(&o));
}

#[test]
fn bad_path_input_gives_clear_errors() {
    let d = out_dir("bad");
    let out = d.join("x.png");
    let out = out.to_str().unwrap();
    let base = [
        "path", "--scene", "cornell", "--width", "8", "--height", "8", "--out", out,
    ];
    for (extra, expect) in [
        (&["--spp", "0"][..], "--spp"),
        (&["--time-budget", "0"][..], "--time-budget"),
        (&["--time-budget", "-3"][..], "--time-budget"),
        (&["--env", "-1"][..], "--env"),
        (&["--env", "1,nan,1"][..], "--env"),
        (
            &["--point=0,1,0", "--point-intensity", "-5"][..],
            "--point-intensity",
        ),
        (&["--point=0,1,0"][..], "--point-intensity"),
        (&["--point=0,1", "--point-intensity", "1"][..], "--point"),
        (&["--max-depth", "0"][..], "--max-depth"),
        (&["--tracer", "octree"][..], "octree"),
        (&["--materials", "shiny"][..], "--materials"),
    ] {
        let mut args: Vec<&str> = base.to_vec();
        args.extend_from_slice(extra);
        let o = parallax(&args);
        assert!(!o.status.success(), "{extra:?} should fail");
        let e = stderr(&o);
        assert!(
            e.contains(expect) && !e.contains("panicked"),
            "{extra:?}: {e}"
        );
    }
    // An explicit black environment on a scene without emitters leaves nothing lit.
    let o = parallax(&[
        "path", "--scene", "atrium", "--width", "8", "--height", "8", "--env", "0", "--out", out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("nothing emits light"), "{}", stderr(&o));
    // The Mitsuba export needs the diffuse material model.
    let o = parallax(&[
        "path",
        "--scene",
        "cornell",
        "--width",
        "8",
        "--height",
        "8",
        "--export-mitsuba",
        d.join("m").to_str().unwrap(),
        "--out",
        out,
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--materials diffuse"), "{}", stderr(&o));
}

#[test]
fn mitsuba_export_writes_meshes_and_scene_json() {
    let d = out_dir("export");
    let o = parallax(&[
        "--quiet",
        "path",
        "--scene",
        "cornell",
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "1",
        "--materials",
        "diffuse",
        "--export-mitsuba",
        d.join("m").to_str().unwrap(),
        "--out",
        d.join("x.exr").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("m/scene.json")).unwrap()).unwrap();
    let shapes = json["shapes"].as_array().unwrap();
    let tris: u64 = shapes
        .iter()
        .map(|s| s["triangles"].as_u64().unwrap())
        .sum();
    let scene = parallax_scene::Scene::load("cornell").unwrap();
    assert_eq!(tris as usize, scene.mesh.triangle_count());
    assert!(shapes.iter().any(|s| !s["emission"].is_null()));
    assert!(shapes.iter().any(|s| s["bsdf"]["type"] == "thindielectric"));
    for s in shapes {
        assert!(d.join("m").join(s["file"].as_str().unwrap()).exists());
    }
    assert_eq!(json["film"]["width"], 8);
    assert_eq!(json["camera"]["fov_y_deg"].as_f64().unwrap() as f32, 40.0);
}

#[test]
fn bench_path_prints_rows_and_writes_json() {
    let d = out_dir("bench");
    let json = d.join("b.json");
    let o = parallax(&[
        "--quiet",
        "bench",
        "path",
        "--scene",
        "cornell",
        "--width",
        "12",
        "--height",
        "8",
        "--spp",
        "2",
        "--reference-spp",
        "4",
        "--repeats",
        "1",
        "--json",
        json.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let rows: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let r = &rows[0];
    assert_eq!(r["method"], "bvh");
    for k in [
        "paths_per_s",
        "mrays_per_s",
        "rmse",
        "efficiency",
        "bounces",
        "budgets",
    ] {
        assert!(r.get(k).is_some(), "row lacks {k}: {r}");
    }
    assert!(r["rmse"].as_f64().unwrap() > 0.0);
    assert_eq!(r["budgets"].as_array().unwrap().len(), 4);
}
