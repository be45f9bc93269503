//! End-to-end runs of `parallax capture` on the Cornell box at tiny sizes: files, EXR
//! channels and sizes, layer ordering, `--stats` JSON, and clean errors on bad input.

use std::path::Path;

use parallax_core::image::exr::{ExrImage, read_exr};

mod common;

use common::{parallax, stderr};

fn out_dir(name: &str) -> common::TestDir {
    common::out_dir("capture", name)
}

/// Runs a capture of cornell at `w x h` into `dir`, with `--stats dir/stats.json`.
fn capture(dir: &Path, view: &str, extra: &[&str]) -> serde_json::Value {
    let stats = dir.join("stats.json");
    let mut args = vec![
        "capture",
        "--quiet",
        "--scene",
        "cornell",
        "--view",
        view,
        "--width",
        "32",
        "--height",
        "24",
        "--out",
        dir.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = parallax(&args);
    assert!(o.status.success(), "{view}: {}", stderr(&o));
    assert!(o.stdout.is_empty(), "--quiet prints nothing");
    serde_json::from_str(&std::fs::read_to_string(stats).unwrap()).unwrap()
}

const LAYER_CHANNELS: [&str; 8] = [
    "R", "G", "B", "depth", "normal.X", "normal.Y", "normal.Z", "id",
];

/// Reads `dir/layer{k}.exr` for `k < layers`, checks channels, size, previews and
/// per-pixel consistency; returns the layers.
fn check_layers(dir: &Path, layers: usize, w: u32, h: u32) -> Vec<ExrImage> {
    let imgs: Vec<ExrImage> = (0..layers)
        .map(|k| {
            for png in [format!("layer{k}.png"), format!("layer{k}.depth.png")] {
                assert!(dir.join(&png).is_file(), "{}: {png}", dir.display());
            }
            read_exr(dir.join(format!("layer{k}.exr"))).unwrap()
        })
        .collect();
    assert!(!dir.join(format!("layer{layers}.exr")).exists());
    for img in &imgs {
        assert_eq!((img.width, img.height), (w, h));
        let mut names: Vec<&str> = img.names().collect();
        names.sort_unstable();
        let mut want = LAYER_CHANNELS.to_vec();
        want.sort_unstable();
        assert_eq!(names, want);
        let (depth, id) = (img.channel("depth").unwrap(), img.channel("id").unwrap());
        let nx = img.channel("normal.X").unwrap();
        let ny = img.channel("normal.Y").unwrap();
        let nz = img.channel("normal.Z").unwrap();
        for i in 0..depth.len() {
            // A hit has a finite positive depth, an id and a unit normal; a miss has id -1.
            assert_eq!(depth[i].is_finite(), id[i] >= 0.0, "pixel {i}");
            if depth[i].is_finite() {
                assert!(depth[i] > 0.0);
                let len = (nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt();
                assert!((len - 1.0).abs() < 1e-3, "normal length {len}");
            }
        }
    }
    // Layer k + 1 is behind layer k wherever both hold a surface.
    for k in 1..layers {
        let (a, b) = (
            imgs[k - 1].channel("depth").unwrap(),
            imgs[k].channel("depth").unwrap(),
        );
        let mut both = 0;
        for (da, db) in a.iter().zip(b) {
            if da.is_finite() && db.is_finite() {
                both += 1;
                assert!(db >= da, "layer {k}: {db} < {da}");
            }
            // No layer k + 1 surface without a layer k one.
            assert!(da.is_finite() || !db.is_finite());
        }
        assert!(both > 0, "layer {k} is empty");
    }
    imgs
}

#[test]
fn pinhole_two_layers() {
    let d = out_dir("pinhole");
    let s = capture(&d, "pinhole", &["--layers", "2"]);
    let imgs = check_layers(&d, 2, 32, 24);
    let hits0 = imgs[0]
        .channel("depth")
        .unwrap()
        .iter()
        .filter(|d| d.is_finite())
        .count();
    assert!(
        hits0 > 32 * 24 / 2,
        "cornell fills most of the view: {hits0}"
    );
    assert_eq!(s["triangles"], 2294);
    assert_eq!(s["layers"], 2);
    assert!(s["fragments"].as_u64().unwrap() >= hits0 as u64);
    // 2 layers of 32 x 24 G-buffer samples, 56 bytes each.
    assert_eq!(s["bytes"], 2 * 32 * 24 * 56);
    for stage in ["load", "setup", "bin", "raster", "resolve", "write"] {
        assert!(
            s["ms"][stage].as_f64().unwrap() >= 0.0,
            "stage {stage}: {s}"
        );
    }
}

#[test]
fn stereo_writes_both_eyes() {
    let d = out_dir("stereo");
    let s = capture(&d, "stereo", &["--layers", "2"]);
    let left = check_layers(&d.join("left"), 2, 32, 24);
    let right = check_layers(&d.join("right"), 2, 32, 24);
    // The eyes are apart: their depth images differ.
    assert_ne!(left[0].channel("depth"), right[0].channel("depth"));
    assert_eq!(s["views"].as_array().unwrap().len(), 2);
    assert_eq!(s["bytes"], 2 * 2 * 32 * 24 * 56);
}

#[test]
fn cube_writes_six_square_faces() {
    let d = out_dir("cube");
    let s = capture(&d, "cube", &["--camera", "corner"]);
    let mut hits = 0;
    for face in ["px", "nx", "py", "ny", "pz", "nz"] {
        let imgs = check_layers(&d.join(face), 1, 32, 32);
        hits += imgs[0]
            .channel("depth")
            .unwrap()
            .iter()
            .filter(|d| d.is_finite())
            .count();
    }
    // The corner camera is inside the box (open at the front): most directions hit.
    assert!(hits > 6 * 32 * 32 / 2, "{hits}");
    assert_eq!(s["views"].as_array().unwrap().len(), 6);
    assert_eq!(s["height"], 32);
}

#[test]
fn dirt_bounds_and_heatmap() {
    let d = out_dir("dirt");
    let s = capture(&d, "dirt", &["--tile", "4", "--buckets", "4"]);
    let b = read_exr(d.join("bounds.exr")).unwrap();
    assert_eq!((b.width, b.height), (8, 6), "32x24 in 4x4 tiles");
    let (lo, hi) = (b.channel("zmin").unwrap(), b.channel("zmax").unwrap());
    let mut nonempty = 0;
    for (l, h) in lo.iter().zip(hi) {
        if l.is_finite() {
            nonempty += 1;
            assert!(*l > 0.0 && h >= l, "{l}..{h}");
        }
    }
    assert!(nonempty > 0);
    assert!(d.join("lengths.png").is_file() && d.join("bounds.depth.png").is_file());
    assert_eq!(s["views"][0]["dirt"]["tile_size"], 4);
    assert_eq!(s["views"][0]["dirt"]["buckets"], 4);
    assert_eq!(s["views"][0]["dirt"]["nonempty_cells"], nonempty);
    assert!(s["bytes"].as_u64().unwrap() > 0);
    assert!(s["ms"]["fill"].as_f64().is_some());
}

#[test]
fn ldc_writes_three_axis_images() {
    let d = out_dir("ldc");
    let s = capture(&d, "ldc", &[]);
    let mut total = 0.0;
    for axis in ["x", "y", "z"] {
        let img = read_exr(d.join(format!("ldi_{axis}.exr"))).unwrap();
        assert_eq!(
            img.width.max(img.height),
            32,
            "--width = pixels along the longest side"
        );
        let depth = img.channel("depth").unwrap();
        let k = img.channel("complexity").unwrap();
        for (z, n) in depth.iter().zip(k) {
            // A pixel has a first sample exactly when its depth complexity is positive.
            assert_eq!(z.is_finite(), *n > 0.0);
        }
        total += k.iter().sum::<f32>();
        assert!(d.join(format!("ldi_{axis}.complexity.png")).is_file());
    }
    // The Cornell box is closed on five sides: every axis sees surfaces.
    assert_eq!(total as u64, s["fragments"].as_u64().unwrap());
    assert!(s["bytes"].as_u64().unwrap() > 0);
}

fn fails_with(args: &[&str], needle: &str) {
    let o = parallax(args);
    let e = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(e.contains(needle), "{args:?}: {e}");
    assert!(!e.contains("panicked"), "{args:?}: {e}");
}

#[test]
fn bad_input_is_a_clear_error() {
    let d = out_dir("bad");
    let out = d.to_str().unwrap();
    let base = ["capture", "--quiet", "--scene", "cornell", "--out", out];
    fn with<'a>(base: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [base, extra].concat()
    }
    fails_with(
        &with(&base, &["--layers", "0"]),
        "--layers must be in 1..=64, got 0",
    );
    fails_with(
        &with(&base, &["--layers", "1000"]),
        "--layers must be in 1..=64, got 1000",
    );
    fails_with(
        &with(&base, &["--view", "sphere"]),
        "invalid value 'sphere' for '--view",
    );
    fails_with(
        &with(&base, &["--width", "0"]),
        "--width and --height must be > 0",
    );
    fails_with(
        &with(&base, &["--width", "100000", "--height", "100000"]),
        "samples, more than",
    );
    fails_with(&with(&base, &["--view", "dirt", "--tile", "0"]), "DIRT");
    fails_with(
        &[
            "capture",
            "--quiet",
            "--scene",
            "no-such-scene",
            "--out",
            out,
        ],
        "no-such-scene",
    );
}
