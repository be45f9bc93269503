//! Reading a glTF file's document and buffers: the GLB container (glTF 2.0 spec §4.4), the JSON
//! document (deserialised and validated by `gltf-json`), and buffers from the BIN chunk, data
//! URIs or files inside the scene folder ([`super::uri`]).

use std::path::Path;

use super::uri::{Resolved, resolve};
use crate::{Result, SceneError};

/// Deserialises and validates the JSON document.
///
/// gltf-json 1.4.1's validation hook for primitives indexes `accessors` with the POSITION
/// accessor index before checking it (a panic on a file whose index is out of range, found by
/// the corrupted-GLB property test), so that index is checked here first. Its validation of
/// animations checks the samplers but not the channel targets (whose node index and path the
/// `gltf` crate unwraps), so those are checked here too.
pub(crate) fn parse_document(json: &[u8]) -> std::result::Result<gltf::Document, String> {
    let root: gltf::json::Root =
        serde_json::from_slice(json).map_err(|e| format!("malformed glTF JSON: {e}"))?;
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            if let Some(a) = p
                .attributes
                .values()
                .find(|a| a.value() >= root.accessors.len())
            {
                return Err(format!(
                    "invalid glTF: meshes[{mi}].primitives[{pi}] uses accessor {} but there are {}",
                    a.value(),
                    root.accessors.len()
                ));
            }
        }
    }
    for (ai, a) in root.animations.iter().enumerate() {
        for (ci, c) in a.channels.iter().enumerate() {
            let node = c.target.node.value();
            if node >= root.nodes.len() {
                return Err(format!(
                    "invalid glTF: animations[{ai}].channels[{ci}] targets node {node} but there are {}",
                    root.nodes.len()
                ));
            }
            if !matches!(c.target.path, gltf::json::validation::Checked::Valid(_)) {
                return Err(format!(
                    "invalid glTF: animations[{ai}].channels[{ci}] has an unknown target path"
                ));
            }
        }
    }
    gltf::Document::from_json(root).map_err(|e| e.to_string())
}

/// Splits a binary glTF (spec §4.4 "GLB file format") into its JSON chunk and optional BIN
/// chunk, checking every declared length against the bytes present.
pub(crate) fn split_glb(bytes: &[u8]) -> std::result::Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |o: usize| {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    let truncated = || format!("truncated GLB: only {} bytes", bytes.len());
    let version = u32_at(4).ok_or_else(truncated)?;
    if version != 2 {
        return Err(format!("unsupported GLB version {version} (expected 2)"));
    }
    let length = u32_at(8).ok_or_else(truncated)?;
    if length > bytes.len() {
        return Err(format!(
            "truncated GLB: the header declares {length} bytes but the file has {}",
            bytes.len()
        ));
    }
    let bytes = &bytes[..length];
    let mut chunks = Vec::new();
    let mut o = 12;
    while o < bytes.len() {
        let (len, ty) = match (u32_at(o), bytes.get(o + 4..o + 8)) {
            (Some(l), Some(t)) => (l, t),
            _ => {
                return Err(format!(
                    "truncated GLB: incomplete chunk header at byte {o}"
                ));
            }
        };
        let data = o
            .checked_add(8 + len)
            .and_then(|end| bytes.get(o + 8..end))
            .ok_or_else(|| format!("truncated GLB: chunk at byte {o} declares {len} bytes"))?;
        chunks.push((ty, data));
        o += 8 + len.next_multiple_of(4);
    }
    match chunks.as_slice() {
        [(b"JSON", json), rest @ ..] => {
            let bin = rest.first().filter(|(t, _)| t == b"BIN\0").map(|c| c.1);
            Ok((json, bin))
        }
        _ => Err("GLB does not start with a JSON chunk".into()),
    }
}

/// Reads every buffer: the GLB BIN chunk, data URIs, or files inside the scene folder.
pub(crate) fn load_buffers(
    doc: &gltf::Document,
    blob: Option<&[u8]>,
    path: &Path,
) -> Result<Vec<Vec<u8>>> {
    let mut out = Vec::with_capacity(doc.buffers().len());
    for buf in doc.buffers() {
        let data = match buf.source() {
            gltf::buffer::Source::Bin => blob
                .ok_or_else(|| SceneError::Parse {
                    path: path.to_path_buf(),
                    message: format!("buffer {} refers to a missing GLB BIN chunk", buf.index()),
                })?
                .to_vec(),
            gltf::buffer::Source::Uri(uri) => match resolve(path, uri)? {
                Resolved::Data(d) => d,
                Resolved::File(f) => std::fs::read(&f).map_err(|source| SceneError::Io {
                    path: f.clone(),
                    source,
                })?,
            },
        };
        if data.len() < buf.length() {
            return Err(SceneError::Parse {
                path: path.to_path_buf(),
                message: format!(
                    "buffer {} has {} bytes but declares byteLength {}",
                    buf.index(),
                    data.len(),
                    buf.length()
                ),
            });
        }
        out.push(data);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_chunk_lengths_are_checked() {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(28u32.to_le_bytes());
        glb.extend(8u32.to_le_bytes());
        glb.extend(b"JSON{}      ");
        assert_eq!(split_glb(&glb).unwrap().0, b"{}      ");
        glb[12] = 9; // JSON chunk longer than the file
        assert!(split_glb(&glb).unwrap_err().contains("truncated"));
        assert!(split_glb(&glb[..10]).unwrap_err().contains("truncated"));
    }
}
