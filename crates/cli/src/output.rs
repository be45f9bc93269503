//! Writing results: renders as PNG (tonemapped sRGB) or EXR (linear, with AOVs as named
//! channels), PNG previews through the display transform, and JSON rows.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use parallax_core::image::png::ToneMapping;
use parallax_core::image::{GBuffer, exr, png};
use parallax_core::{Image, Rgb};
use parallax_render::score::SCORE_TONEMAP;
use serde::Serialize;

/// The G-buffer channels `--aov` can ask for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Aov {
    Depth,
    Normal,
    Albedo,
    Id,
}

/// Shaded renders go through the display transform of the scores (ACES filmic, exposure 0:
/// highlights roll off instead of clipping), so a PNG shows what PSNR / SSIM compare.
const RENDER_TONEMAP: ToneMapping = SCORE_TONEMAP;

/// Writes a linear image as a PNG through the display transform; returns the path.
pub fn write_png(path: &Path, img: &Image<Rgb>) -> Result<PathBuf> {
    png::write_png(path, img, &RENDER_TONEMAP)?;
    Ok(path.to_path_buf())
}

/// Writes `rows` as pretty JSON to `path` (`--json FILE`, `--stats FILE`), if given.
pub fn write_json<T: Serialize>(path: Option<&Path>, rows: &T) -> Result<()> {
    if let Some(p) = path {
        std::fs::write(p, serde_json::to_string_pretty(rows)?)
            .with_context(|| format!("writing {}", p.display()))?;
    }
    Ok(())
}

fn ext(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Checks that `path` ends in .png or .exr before any work is done.
pub fn check_image_path(path: &Path) -> Result<()> {
    match ext(path).as_str() {
        "png" | "exr" => Ok(()),
        _ => bail!("{}: output must end in .png or .exr", path.display()),
    }
}

fn split3(v: &[glam::Vec3]) -> [Vec<f32>; 3] {
    [
        v.iter().map(|c| c.x).collect(),
        v.iter().map(|c| c.y).collect(),
        v.iter().map(|c| c.z).collect(),
    ]
}

/// `out.png` + ("depth") -> `out.depth.png`.
fn sibling(path: &Path, suffix: &str) -> PathBuf {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("out");
    path.with_file_name(format!("{stem}.{suffix}.png"))
}

/// Writes `image` (and the requested AOVs) to `path`. EXR: channels R,G,B plus `depth`,
/// `normal.X/Y/Z`, `albedo.R/G/B`, `id` (primitive id as f32, -1 for misses). PNG: the image,
/// and one preview PNG per AOV beside it.
pub fn write_render(
    path: &Path,
    image: &Image<Rgb>,
    g: Option<&GBuffer>,
    aovs: &[Aov],
) -> Result<Vec<PathBuf>> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let (w, h) = (image.width(), image.height());
    let mut written = vec![path.to_path_buf()];
    match ext(path).as_str() {
        "exr" => {
            let [r, gc, b] = split3(image.data());
            let mut owned: Vec<(String, Vec<f32>)> =
                vec![("R".into(), r), ("G".into(), gc), ("B".into(), b)];
            if let Some(g) = g {
                for aov in aovs {
                    match aov {
                        Aov::Depth => owned.push(("depth".into(), g.depth.clone())),
                        Aov::Normal => {
                            let [x, y, z] = split3(&g.normal);
                            owned.extend([
                                ("normal.X".into(), x),
                                ("normal.Y".into(), y),
                                ("normal.Z".into(), z),
                            ]);
                        }
                        Aov::Albedo => {
                            let [x, y, z] = split3(&g.albedo);
                            owned.extend([
                                ("albedo.R".into(), x),
                                ("albedo.G".into(), y),
                                ("albedo.B".into(), z),
                            ]);
                        }
                        Aov::Id => owned.push((
                            "id".into(),
                            g.primitive_id
                                .iter()
                                .map(|&i| if i == u32::MAX { -1.0 } else { i as f32 })
                                .collect(),
                        )),
                    }
                }
            }
            let channels: Vec<(&str, &[f32])> = owned
                .iter()
                .map(|(n, v)| (n.as_str(), v.as_slice()))
                .collect();
            exr::write_exr(path, w, h, &channels)?;
        }
        "png" => {
            png::write_png(path, image, &RENDER_TONEMAP)?;
            if let Some(g) = g {
                for aov in aovs {
                    let p = match aov {
                        Aov::Depth => {
                            let p = sibling(path, "depth");
                            png::write_depth_png(&p, &Image::from_vec(w, h, g.depth.clone())?)?;
                            p
                        }
                        Aov::Normal => {
                            let p = sibling(path, "normal");
                            let img = Image::from_vec(
                                w,
                                h,
                                g.normal.iter().map(|n| *n * 0.5 + 0.5).collect(),
                            )?;
                            png::write_png_linear_clamped(&p, &img)?;
                            p
                        }
                        Aov::Albedo => {
                            let p = sibling(path, "albedo");
                            png::write_png(
                                &p,
                                &Image::from_vec(w, h, g.albedo.clone())?,
                                &ToneMapping::default(),
                            )?;
                            p
                        }
                        Aov::Id => {
                            let p = sibling(path, "id");
                            png::write_id_png(&p, &Image::from_vec(w, h, g.primitive_id.clone())?)?;
                            p
                        }
                    };
                    written.push(p);
                }
            }
        }
        _ => check_image_path(path)?,
    }
    Ok(written)
}
