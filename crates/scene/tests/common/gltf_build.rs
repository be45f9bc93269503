//! Builds small glTF files in memory for tests: a binary buffer grown accessor by accessor and
//! embedded as a base64 data URI. Shared by the scene and BVH tests (`#[path]`-included).
#![allow(dead_code)]

use serde_json::{Value, json};

/// Accessors and buffer views over one growing buffer.
#[derive(Default)]
pub struct GltfBuf {
    pub bin: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl GltfBuf {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// A float accessor of `ty` ("SCALAR", "VEC3", "VEC4", "MAT4"); min/max are written for
    /// SCALAR and VEC3 (animation inputs and positions need them).
    pub fn floats(&mut self, data: &[f32], ty: &str) -> usize {
        let n = match ty {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            _ => panic!("{ty}"),
        };
        let bytes: Vec<u8> = data.iter().flat_map(|f| f.to_le_bytes()).collect();
        let v = self.view(&bytes);
        let mut acc =
            json!({"bufferView": v, "componentType": 5126, "count": data.len() / n, "type": ty});
        if n <= 3 {
            let mut mn = vec![f32::INFINITY; n];
            let mut mx = vec![f32::NEG_INFINITY; n];
            for e in data.chunks(n) {
                for c in 0..n {
                    mn[c] = mn[c].min(e[c]);
                    mx[c] = mx[c].max(e[c]);
                }
            }
            if data.iter().all(|f| f.is_finite()) && !data.is_empty() {
                acc["min"] = json!(mn);
                acc["max"] = json!(mx);
            }
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// An integer accessor: `component` 5121 (u8) or 5123 (u16), `count` elements of `ty`.
    pub fn ints(&mut self, data: &[u32], component: u32, ty: &str, normalized: bool) -> usize {
        let n = if ty == "SCALAR" { 1 } else { 4 };
        let bytes: Vec<u8> = match component {
            5121 => data.iter().map(|&v| v as u8).collect(),
            5123 => data
                .iter()
                .flat_map(|&v| (v as u16).to_le_bytes())
                .collect(),
            _ => data.iter().flat_map(|&v| v.to_le_bytes()).collect(),
        };
        let v = self.view(&bytes);
        let mut acc = json!({"bufferView": v, "componentType": component, "count": data.len() / n, "type": ty});
        if normalized {
            acc["normalized"] = json!(true);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Completes `doc` (nodes, meshes, animations, ...) with the buffer, views and accessors.
    pub fn finish(&self, mut doc: Value) -> String {
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{
            "byteLength": self.bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(&self.bin))
        }]);
        doc["bufferViews"] = json!(self.views);
        doc["accessors"] = json!(self.accessors);
        doc.to_string()
    }
}

pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let v = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= c.len() {
                s.push(A[(v >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A fresh temporary folder for one test, removed when dropped.
pub fn tmp_dir(name: &str) -> tempfile::TempDir {
    tempfile::Builder::new()
        .prefix(&format!("parallax-gltf-anim-{name}-"))
        .tempdir()
        .unwrap()
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &std::path::Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}
