//! Temporary folders and load helpers shared by the loader tests (`#[path]`-included).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use parallax_scene::load::load_file;
use parallax_scene::{Scene, SceneError};

pub fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes")
}

/// A fresh, empty temporary folder for one test, removed when dropped.
pub fn tmp(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("parallax-scene-loaders-{name}-"))
        .tempdir()
        .unwrap()
}

pub fn load(p: &Path) -> Scene {
    load_file(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

pub fn load_err(p: &Path) -> (SceneError, String) {
    match load_file(p) {
        Ok(_) => panic!("{} loaded but should fail", p.display()),
        Err(e) => {
            let msg = e.to_string();
            eprintln!("expected error: {msg}");
            (e, msg)
        }
    }
}

pub fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}
