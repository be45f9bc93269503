//! Every pipeline gives bit-identical files at 1 and 2 threads: the quad-tree build and stereo
//! warp (and the DDA), temporal upsampling, the HVVR beam caster's frame, the LDC and BVH
//! secondary-ray renders, depth of field, and the path tracer through DIRT, each run twice by
//! the binary with `--threads 1` / `--threads 2` on small images, all output files compared.

#[allow(dead_code)]
mod common;

use common::{out_dir, parallax, stderr, tree};

/// Runs `args` (with `{out}` replaced by an output folder) at 1 and 2 threads and compares.
fn same_at_one_and_two_threads(name: &str, args: &[&str]) {
    let base = out_dir("determinism", name);
    let mut trees = Vec::new();
    for t in ["1", "2"] {
        let dir = base.join(format!("t{t}"));
        std::fs::create_dir_all(&dir).unwrap();
        let d = dir.to_str().unwrap().to_string();
        let mut a = vec!["--quiet".to_string(), "--threads".into(), t.into()];
        a.extend(args.iter().map(|s| s.replace("{out}", &d)));
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let o = parallax(&refs);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        trees.push(tree(&dir));
    }
    assert!(!trees[0].is_empty(), "{name} wrote files");
    let names =
        |t: &[(std::path::PathBuf, Vec<u8>)]| t.iter().map(|x| x.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&trees[0]), names(&trees[1]), "{name}");
    for ((n, a), (_, b)) in trees[0].iter().zip(&trees[1]) {
        assert!(
            a == b,
            "{name}: {} differs between 1 and 2 threads",
            n.display()
        );
    }
    let _ = std::fs::remove_dir_all(base);
}

#[test]
fn quadtree_warp_and_dda() {
    let size = [
        "--scene", "atrium", "--width", "64", "--height", "36", "--layers", "2", "--out", "{out}",
    ];
    let mut a = vec!["warp", "--method", "quadtree"];
    a.extend(size);
    same_at_one_and_two_threads("warp-quadtree", &a);
    let mut a = vec!["warp", "--method", "dda"];
    a.extend(size);
    same_at_one_and_two_threads("warp-dda", &a);
}

#[test]
fn upsample() {
    same_at_one_and_two_threads(
        "upsample",
        &[
            "upsample", "--scene", "atrium", "--width", "48", "--height", "27", "--frames", "6",
            "--truth", "--out", "{out}",
        ],
    );
}

#[test]
fn vr_beam_caster() {
    same_at_one_and_two_threads(
        "vr",
        &[
            "vr",
            "--scene",
            "cornell",
            "--preset",
            "custom",
            "--width",
            "96",
            "--height",
            "48",
            "--msaa",
            "4",
            "--foveated",
            "--visibility",
            "beam",
            "--out",
            "{out}",
        ],
    );
}

#[test]
fn secondary_ldc_and_bvh() {
    same_at_one_and_two_threads(
        "secondary",
        &[
            "secondary",
            "--scene",
            "cornell",
            "--width",
            "40",
            "--height",
            "30",
            "--out",
            "{out}/sec.png",
        ],
    );
}

#[test]
fn path_through_dirt() {
    same_at_one_and_two_threads(
        "path-dirt",
        &[
            "path",
            "--scene",
            "cornell",
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "2",
            "--tracer",
            "dirt",
            "--out",
            "{out}/p.png",
        ],
    );
}

#[test]
fn depth_of_field() {
    same_at_one_and_two_threads(
        "dof",
        &[
            "dof",
            "--scene",
            "cornell",
            "--width",
            "40",
            "--height",
            "24",
            "--truth-spp",
            "4",
            "--out",
            "{out}",
        ],
    );
}
