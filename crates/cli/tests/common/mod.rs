//! Helpers shared by the CLI's end-to-end tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the `parallax` binary with `args`.
pub fn parallax(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_parallax"))
        .args(args)
        .output()
        .expect("binary runs")
}

/// A fresh, empty temporary folder of one test, removed when the test passes.
///
/// It dereferences to its [`Path`]. When dropped during a panic (a failing test) the folder
/// is kept and its path printed, so the outputs that made the test fail can be looked at.
pub struct TestDir(Option<tempfile::TempDir>);

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.as_ref().expect("held until drop").path()
    }
}

impl AsRef<Path> for TestDir {
    fn as_ref(&self) -> &Path {
        self
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        if std::thread::panicking()
            && let Some(d) = self.0.take()
        {
            eprintln!("test outputs kept in {}", d.keep().display());
        }
    }
}

/// A fresh, empty temporary folder for test `name` of suite `suite`.
pub fn out_dir(suite: &str, name: &str) -> TestDir {
    let d = tempfile::Builder::new()
        .prefix(&format!("parallax-{suite}-{name}-"))
        .tempdir()
        .expect("temporary folder");
    TestDir(Some(d))
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
