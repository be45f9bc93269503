//! Experiment files: parsing, the errors of bad files (key, line, expected type), sweep order
//! and the point limit.

use std::path::Path;

use parallax_experiment::sweep::flag_args;
use parallax_experiment::{Experiment, ExperimentError};

fn parse(text: &str) -> Result<Experiment, ExperimentError> {
    Experiment::parse(text, Path::new("exp.toml"))
}

fn message(text: &str) -> String {
    parse(text)
        .and_then(|e| e.points().map(|_| e))
        .expect_err("an error")
        .to_string()
}

#[test]
fn parses_args_sweep_and_images() {
    let e = parse(
        "bench = \"warp\"\n[args]\nwidth = 64\nlayers = [1, 2]\nadaptive = true\n\
         [sweep]\nipd = [0.065, 0.13]\nscene = [\"atrium\", \"cornell\", \"foliage\"]\n\
         [images]\ncommand = \"warp\"\nlayers = 2\n",
    )
    .unwrap();
    assert_eq!(e.title, "exp");
    assert_eq!(e.out, Path::new("out/experiments/exp"));
    let flags: Vec<String> = e.args.iter().flat_map(flag_args).collect();
    assert_eq!(flags, ["--width=64", "--layers=1,2", "--adaptive"]);
    let pts = e.points().unwrap();
    assert_eq!(pts.len(), 6);
    // File order of axes, last axis fastest.
    let p4: Vec<String> = pts[4].params.iter().flat_map(flag_args).collect();
    assert_eq!(p4, ["--ipd=0.13", "--scene=cornell"]);
    assert_eq!(e.images.as_ref().unwrap().command, "warp");
    assert_eq!(e.images.as_ref().unwrap().args[0].line, 11);
}

#[test]
fn unknown_top_level_key_names_line() {
    let m = message("bench = \"warp\"\ntitel = \"x\"\n");
    assert!(m.contains("exp.toml:2") && m.contains("titel"), "{m}");
}

#[test]
fn wrong_types_name_key_line_and_type() {
    let m = message("bench = \"warp\"\n[args]\nwidth = { a = 1 }\n");
    assert!(
        m.contains("exp.toml:3") && m.contains("args.width") && m.contains("got table"),
        "{m}"
    );
    let m = message("bench = \"warp\"\n[sweep]\nwidth = 64\n");
    assert!(
        m.contains("sweep.width") && m.contains("expected an array") && m.contains("got integer"),
        "{m}"
    );
    let m = message("bench = 3\n");
    assert!(m.contains("exp.toml:1") && m.contains("string"), "{m}");
    let m = message("bench = \"warp\"\nmax_points = 0\n");
    assert!(m.contains("max_points") && m.contains(">= 1"), "{m}");
}

#[test]
fn empty_sweep_and_duplicate_key() {
    let m = message("bench = \"warp\"\n[sweep]\nipd = []\n");
    assert!(m.contains("exp.toml:3") && m.contains("empty sweep"), "{m}");
    let m = message("bench = \"warp\"\n[args]\nipd = 0.1\n[sweep]\nipd = [0.2]\n");
    assert!(
        m.contains("exp.toml:5") && m.contains("also set in [args] at line 3"),
        "{m}"
    );
}

#[test]
fn a_billion_points_is_refused_without_allocating() {
    let axis: Vec<String> = (0..1000).map(|i| i.to_string()).collect();
    let list = axis.join(", ");
    let text = format!("bench = \"warp\"\n[sweep]\na = [{list}]\nb = [{list}]\nc = [{list}]\n");
    let e = parse(&text).unwrap();
    let m = e.points().err().unwrap().to_string();
    assert!(
        m.contains("1000000000 points") && m.contains("max_points = 10000"),
        "{m}"
    );
    let ok = parse(&format!(
        "max_points = 1000000\nbench = \"warp\"\n[sweep]\na = [{list}]\nb = [{list}]\n"
    ))
    .unwrap();
    assert_eq!(ok.point_count().unwrap(), 1_000_000);
    assert_eq!(ok.point(999_999).params[0].value.as_integer(), Some(999));
}

#[test]
fn images_needs_a_command() {
    let m = message("bench = \"warp\"\n[images]\nlayers = 2\n");
    assert!(m.contains("images.command") && m.contains("missing"), "{m}");
}
