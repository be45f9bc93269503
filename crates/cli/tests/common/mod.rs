//! Helpers shared by the CLI's end-to-end tests.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `parallax` binary with `args`.
pub fn parallax(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_parallax"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// A fresh, empty temporary folder for test `name` of suite `suite`.
pub fn out_dir(suite: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("parallax-{suite}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The process's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every file under `dir` (relative, sorted) with its bytes.
#[allow(dead_code)]
pub fn tree(dir: &std::path::Path) -> Vec<(PathBuf, Vec<u8>)> {
    parallax_experiment::results::files_under(dir)
        .unwrap()
        .into_iter()
        .map(|r| {
            let b = std::fs::read(dir.join(&r)).unwrap();
            (r, b)
        })
        .collect()
}
