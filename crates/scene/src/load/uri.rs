//! References from a scene file to other files: data URIs (base64) and relative paths that must
//! stay inside the scene's folder.
//!
//! **Invariant:** a loader never reads a file outside the folder of the scene file it was given.
//! A reference that is absolute, uses a scheme other than `data:`, or climbs out of the folder
//! with `..` (lexically, or through a symbolic link) is a [`SceneError::BadReference`].

use std::path::{Component, Path, PathBuf};

use crate::{Result, SceneError};

/// Where a reference points to.
pub(crate) enum Resolved {
    /// Inline bytes of a `data:...;base64,` URI.
    Data(Vec<u8>),
    /// A file inside the scene folder (it exists: it was canonicalised).
    File(PathBuf),
}

/// Resolves `uri` (as written in the scene file `scene`) against the scene's folder.
pub(crate) fn resolve(scene: &Path, uri: &str) -> Result<Resolved> {
    let bad = |message: String| SceneError::BadReference {
        path: scene.to_path_buf(),
        uri: uri.to_string(),
        message,
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or_else(|| bad("only base64 data URIs are supported".into()))?;
        return decode_base64(payload)
            .map(Resolved::Data)
            .map_err(|e| bad(format!("bad base64 data: {e}")));
    }
    let decoded = percent_decode(uri).map_err(bad)?;
    resolve_relative(scene, &decoded)
        .map_err(|e| bad(e.to_string()))
        .map(Resolved::File)
}

/// Why a relative reference cannot be followed.
#[derive(Debug)]
pub(crate) enum RefError {
    /// Absolute, another scheme, or outside the scene folder.
    Forbidden(String),
    /// Inside the folder but not an existing file.
    Missing(String),
}

impl std::fmt::Display for RefError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefError::Forbidden(m) | RefError::Missing(m) => f.write_str(m),
        }
    }
}

/// Resolves a relative file reference (already percent-decoded) against the folder of `scene`.
pub(crate) fn resolve_relative(scene: &Path, rel: &str) -> std::result::Result<PathBuf, RefError> {
    check_relative(rel).map_err(RefError::Forbidden)?;
    let inside = lexical_inside(rel).map_err(RefError::Forbidden)?;
    let dir = scene.parent().unwrap_or(Path::new(""));
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let full = dir.join(&inside);
    let canon = full
        .canonicalize()
        .map_err(|e| RefError::Missing(format!("cannot open {}: {e}", full.display())))?;
    let canon_dir = dir
        .canonicalize()
        .map_err(|e| RefError::Missing(format!("cannot open folder {}: {e}", dir.display())))?;
    if !canon.starts_with(&canon_dir) {
        return Err(RefError::Forbidden(format!(
            "{} resolves (through a link) outside the scene folder",
            full.display()
        )));
    }
    if !canon.is_file() {
        return Err(RefError::Missing(format!(
            "{} is not a file",
            full.display()
        )));
    }
    Ok(canon)
}

/// Rejects empty, absolute and scheme-carrying references.
fn check_relative(rel: &str) -> std::result::Result<(), String> {
    if rel.is_empty() {
        return Err("empty file reference".into());
    }
    // A scheme ("http:", "file:") or a drive letter ("C:") before the first slash.
    let head = rel.split(['/', '\\']).next().unwrap_or("");
    if head.contains(':') {
        return Err("absolute paths and URI schemes other than data: are not allowed".into());
    }
    if rel.starts_with('/') || rel.starts_with('\\') {
        return Err(
            "absolute paths are not allowed: references must stay in the scene folder".into(),
        );
    }
    Ok(())
}

/// The reference as a path below the scene folder, `..` resolved lexically; an error if it
/// climbs above the folder.
fn lexical_inside(rel: &str) -> std::result::Result<PathBuf, String> {
    let mut inside = PathBuf::new();
    for part in rel.split(['/', '\\']) {
        match Path::new(part).components().next() {
            None | Some(Component::CurDir) => {}
            Some(Component::ParentDir) => {
                if !inside.pop() {
                    return Err("the reference climbs out of the scene folder".into());
                }
            }
            Some(Component::Normal(p)) => inside.push(p),
            Some(Component::RootDir | Component::Prefix(_)) => {
                return Err("absolute paths are not allowed".into());
            }
        }
    }
    Ok(inside)
}

/// Decodes `%XX` escapes of a URI reference.
fn percent_decode(s: &str) -> std::result::Result<String, String> {
    if !s.contains('%') {
        return Ok(s.to_string());
    }
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or("bad %-escape")?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| "%-escapes do not form UTF-8".to_string())
}

/// Decodes standard base64 (RFC 4648 §4; padding optional).
pub(crate) fn decode_base64(s: &str) -> std::result::Result<Vec<u8>, String> {
    fn val(c: u8) -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    }
    let s = s.trim_end_matches('=').as_bytes();
    if s.len() % 4 == 1 {
        return Err("length is not a valid base64 length".into());
    }
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 2);
    for chunk in s.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            let v = val(c).ok_or_else(|| format!("invalid character {:?}", c as char))?;
            acc |= v << (18 - 6 * k);
        }
        let bytes = [(acc >> 16) as u8, (acc >> 8) as u8, acc as u8];
        out.extend_from_slice(&bytes[..chunk.len() - 1]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_vectors() {
        // RFC 4648 §10 test vectors.
        for (plain, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(decode_base64(enc).unwrap(), plain.as_bytes());
        }
        assert!(decode_base64("Zm9v!").is_err());
        assert!(decode_base64("Z").is_err());
    }

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert!(percent_decode("a%2").is_err());
    }

    #[test]
    fn escaping_references_are_rejected() {
        let scene = Path::new("/nonexistent/dir/scene.gltf");
        for uri in [
            "../x.bin",
            "a/../../x.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "C:x",
        ] {
            let e = resolve_relative(scene, uri).unwrap_err();
            assert!(matches!(e, RefError::Forbidden(_)), "{uri}: {e}");
            let e = e.to_string();
            assert!(
                e.contains("scene folder") || e.contains("absolute"),
                "{uri}: {e}"
            );
        }
    }
}

/// The scene name of a scene file: its file name without the extension.
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}
