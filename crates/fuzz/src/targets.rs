//! What the fuzzer feeds: the scene loaders (glTF, GLB, OBJ, PLY), the colour / depth inputs
//! of `warp --color --depth` (PNG, EXR) and experiment files (TOML); their seeds (valid files:
//! `../shared/scenes/box_textured`, `experiments/*.toml` and small built-in ones) and how one
//! input is run. A target's `Result` is ignored: only panics, hangs and allocations over the
//! budget are findings.

use std::path::{Path, PathBuf};

/// One input format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    Gltf,
    Glb,
    Obj,
    Ply,
    Png,
    Exr,
    Toml,
}

impl Target {
    pub const ALL: [Target; 7] = [
        Target::Gltf,
        Target::Glb,
        Target::Obj,
        Target::Ply,
        Target::Png,
        Target::Exr,
        Target::Toml,
    ];

    pub fn ext(self) -> &'static str {
        match self {
            Target::Gltf => "gltf",
            Target::Glb => "glb",
            Target::Obj => "obj",
            Target::Ply => "ply",
            Target::Png => "png",
            Target::Exr => "exr",
            Target::Toml => "toml",
        }
    }

    /// The target of a file name's extension.
    pub fn of_ext(ext: &str) -> Option<Target> {
        Target::ALL
            .into_iter()
            .find(|t| t.ext().eq_ignore_ascii_case(ext))
    }

    /// Runs one input, written to `file` first (an error only when it cannot be written:
    /// a case that was not written tested nothing).
    pub fn run(self, data: &[u8], file: &Path) -> std::io::Result<()> {
        std::fs::write(file, data)?;
        match self {
            Target::Gltf | Target::Glb | Target::Obj | Target::Ply => {
                let _ = parallax_scene::Scene::load(&file.to_string_lossy());
            }
            Target::Png => {
                let _ = parallax_synth::input::read_color(file);
            }
            Target::Exr => {
                let _ = parallax_synth::input::read_color(file);
                let _ = parallax_synth::input::read_depth(file);
            }
            Target::Toml => {
                let text = String::from_utf8_lossy(data);
                if let Ok(e) = parallax_experiment::Experiment::parse(&text, file)
                    && let Ok(n) = e.point_count()
                {
                    if n <= 1000 {
                        let _ = e.points();
                    } else {
                        let _ = e.point(n - 1);
                    }
                }
            }
        }
        Ok(())
    }
}

const TRIANGLE_OBJ: &str = "# a unit cube corner\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvt 0 0\nf 1 2 3\nf 1/1/1 3/1/1 4/1/1\nf -1 -2 -3\nusemtl x\no part\nf 2 3 4\n";
const TRIANGLE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n4 0 1 2 3\n";
const SMALL_TOML: &str = "title = \"t\"\nbench = \"warp\"\nmax_points = 100\n[args]\nscene = \"cornell\"\nwidth = 8\nlayers = [1, 2]\n[sweep]\nipd = [0.1, 0.2]\nnear = [\"fitted\", \"0.1\"]\n[images]\ncommand = \"warp\"\nlayers = 2\n";

/// A triangle as glTF JSON with its buffer as a data URI.
fn triangle_gltf() -> String {
    let mut bin = Vec::new();
    for v in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let b64 = base64_encode(&bin);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"translation":[0,0,-2]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.5,1],"metallicFactor":0}}}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":1.0,"znear":0.01}}}}]}}"#,
        bin.len()
    )
}

/// Standard base64 (for the built-in seed only).
fn base64_encode(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// The repository's root (this crate is `crates/fuzz`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The seeds of every target; `work` is a scratch folder for the image seeds.
pub fn seeds(work: &Path) -> Vec<(Target, Vec<u8>)> {
    let mut out = vec![
        (Target::Gltf, triangle_gltf().into_bytes()),
        (Target::Obj, TRIANGLE_OBJ.as_bytes().to_vec()),
        (Target::Ply, TRIANGLE_PLY.as_bytes().to_vec()),
        (Target::Toml, SMALL_TOML.as_bytes().to_vec()),
    ];
    let gltf = triangle_gltf();
    out.push((Target::Glb, crate::mutate::glb(gltf.as_bytes(), &[])));
    // Binary PLY of the same triangle.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n".to_vec();
    for v in [0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        ply.extend_from_slice(&v.to_le_bytes());
    }
    ply.push(3);
    for i in [0i32, 1, 2] {
        ply.extend_from_slice(&i.to_le_bytes());
    }
    out.push((Target::Ply, ply));
    let scenes = repo_root().join("../shared/scenes/box_textured");
    for (f, t) in [
        ("BoxTextured.gltf", Target::Gltf),
        ("BoxTextured.glb", Target::Glb),
    ] {
        if let Ok(b) = std::fs::read(scenes.join(f)) {
            out.push((t, b));
        }
    }
    if let Ok(rd) = std::fs::read_dir(repo_root().join("experiments")) {
        let mut files: Vec<PathBuf> = rd
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "toml"))
            .collect();
        files.sort();
        for f in files {
            if let Ok(b) = std::fs::read(f) {
                out.push((Target::Toml, b));
            }
        }
    }
    let _ = std::fs::create_dir_all(work);
    if let Ok(img) = parallax_core::Image::from_fn(6, 4, |x, y| {
        parallax_core::Rgb::new(x as f32 / 6.0, y as f32 / 4.0, 0.5)
    }) {
        let p = work.join("seed.png");
        if parallax_core::image::png::write_png_linear_clamped(&p, &img).is_ok()
            && let Ok(b) = std::fs::read(&p)
        {
            out.push((Target::Png, b));
        }
        let e = work.join("seed.exr");
        let ch: Vec<f32> = (0..24).map(|i| 1.0 + i as f32).collect();
        if parallax_core::image::exr::write_exr(
            &e,
            6,
            4,
            &[("R", &ch), ("G", &ch), ("B", &ch), ("Z", &ch)],
        )
        .is_ok()
            && let Ok(b) = std::fs::read(&e)
        {
            out.push((Target::Exr, b));
        }
    }
    out
}
