//! References from a scene file to other files: data URIs (base64, decoded by the `base64`
//! crate) and relative paths (percent-decoded by `percent-encoding`) that must stay inside the
//! scene's folder.
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

/// Decodes `%XX` escapes of a URI reference (`percent-encoding`); a `%` not followed by two hex
/// digits, or escapes that do not form UTF-8, are an error.
fn percent_decode(s: &str) -> std::result::Result<String, String> {
    let b = s.as_bytes();
    let hex2 = |i: usize| {
        b.get(i + 1..i + 3)
            .is_some_and(|h| h.iter().all(u8::is_ascii_hexdigit))
    };
    if (0..b.len()).any(|i| b[i] == b'%' && !hex2(i)) {
        return Err("bad %-escape".into());
    }
    percent_encoding::percent_decode_str(s)
        .decode_utf8()
        .map(|c| c.into_owned())
        .map_err(|_| "%-escapes do not form UTF-8".to_string())
}

/// Decodes base64 (`base64` crate): the standard alphabet of RFC 4648 §4 as data URIs use it, or
/// the URL-safe one (§5); padding optional, trailing bits tolerated.
pub(crate) fn decode_base64(s: &str) -> std::result::Result<Vec<u8>, String> {
    use base64::Engine;
    use base64::alphabet::{STANDARD, URL_SAFE};
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    let config = GeneralPurposeConfig::new()
        .with_decode_padding_mode(DecodePaddingMode::Indifferent)
        .with_decode_allow_trailing_bits(true);
    let standard = GeneralPurpose::new(&STANDARD, config);
    match standard.decode(s) {
        Err(base64::DecodeError::InvalidByte(..)) if s.contains(['-', '_']) => {
            GeneralPurpose::new(&URL_SAFE, config).decode(s)
        }
        r => r,
    }
    .map_err(|e| e.to_string())
}

/// The scene name of a scene file: its file name without the extension.
pub(crate) fn file_stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
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
