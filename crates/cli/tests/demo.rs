//! `parallax demo` (the README's first command) end to end at a small size: every technique's
//! piece is written, the page shows every image, and the image-space methods' pieces agree
//! with their BVH ground truth beside them.

#[allow(dead_code)]
mod common;

use std::path::Path;

use common::{out_dir, parallax, stderr};

/// PSNR (dB) of two 8-bit images of the same size.
fn psnr_png(a: &Path, b: &Path) -> f64 {
    let (x, y) = (
        image::open(a).unwrap().to_rgb8(),
        image::open(b).unwrap().to_rgb8(),
    );
    assert_eq!(x.dimensions(), y.dimensions(), "{}", a.display());
    let n = x.as_raw().len() as f64;
    let mse = x
        .as_raw()
        .iter()
        .zip(y.as_raw())
        .map(|(&p, &q)| (p as f64 - q as f64).powi(2))
        .sum::<f64>()
        / n;
    10.0 * (255.0f64 * 255.0 / mse.max(1e-12)).log10()
}

#[test]
fn demo_writes_every_piece_and_its_page() {
    let dir = out_dir("demo", "small");
    let o = parallax(&[
        "--threads",
        "2",
        "demo",
        "--width",
        "192",
        "--height",
        "108",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    let page = std::fs::read_to_string(dir.join("index.html")).expect("the demo's page");
    for piece in [
        "pinhole",
        "thinlens",
        "path_traced",
        "dirt_path_traced",
        "reflect_cubemap",
        "reflect_bvh",
        "dof_quadtree",
        "dof_bvh",
        "quilt",
        "quilt_bvh",
        "vr_rift_left",
        "stereo_warp_left",
        "secondary_ldc",
        "secondary_bvh",
        "reproject_compare",
    ] {
        let name = format!("{piece}.png");
        let img = image::open(dir.join(&name))
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .to_rgb8();
        let first = img.get_pixel(0, 0);
        assert!(img.pixels().any(|p| p != first), "{name} is blank");
        assert!(
            page.contains(&format!("src=\"{name}\"")),
            "{name} not on the page"
        );
    }
    for piece in ["dof_quadtree", "quilt", "reproject"] {
        assert!(
            table.contains(&format!("| {piece}")),
            "no {piece} row:\n{table}"
        );
    }
    // The page: a section per paper, each result with a ground truth behind a wipe slider,
    // and the stereo warp scored against the BVH's eye views.
    for section in [
        "Path tracing and DIRT",
        "Widmer et al. 2015",
        "HVVR",
        "Layered depth cubes",
        "Stereo and temporal reprojection",
        "Camera models",
    ] {
        assert!(
            page.contains(&format!("<h2>{section}")),
            "no section {section}"
        );
    }
    for truth in [
        "dirt_path_traced_bvh.png",
        "stereo_warp_left_bvh.png",
        "dof_bvh.png",
        "quilt_bvh.png",
        "reflect_bvh.png",
        "secondary_bvh.png",
    ] {
        let wipe = format!("<div class=\"wipe\"><img src=\"{truth}\"");
        assert!(page.contains(&wipe), "no wipe against {truth}");
    }
    let p = psnr_png(
        &dir.join("stereo_warp_left.png"),
        &dir.join("stereo_warp_left_bvh.png"),
    );
    println!("stereo_warp_left vs its BVH view: {p:.2} dB");
    assert!(p >= 18.0, "stereo warp left eye vs BVH: {p:.2} dB < 18");
    let p = psnr_png(&dir.join("dof_quadtree.png"), &dir.join("dof_bvh.png"));
    println!("dof_quadtree vs dof_bvh: {p:.2} dB");
    assert!(p >= 20.0, "dof_quadtree vs dof_bvh: {p:.2} dB < 20");
    // The quilt's views nearest the reference (its outer views see what the reference did
    // not: docs/notes/synth.md).
    let rows: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("synth/quilt/rows.json")).expect("quilt rows"),
    )
    .unwrap();
    let mut views: Vec<(f64, f64)> = rows
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["offset_m"].as_f64().unwrap().abs(),
                r["psnr"].as_f64().unwrap(),
            )
        })
        .collect();
    views.sort_by(|a, b| a.0.total_cmp(&b.0));
    println!("quilt views (|offset| m, dB): {views:?}");
    assert_eq!(views.len(), 8);
    for (off, db) in &views[..2] {
        assert!(*db >= 18.0, "quilt view at {off:.2} m: {db:.2} dB < 18");
    }
}
