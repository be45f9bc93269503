//! A user's colour + depth image pair as a single-layer reference, shared by every command
//! that takes one (`warp`, `dof`, `lightfield`): the colour (EXR linear or PNG / JPEG sRGB),
//! its view depth (EXR), the intrinsics (`--focal-px`, else `--fov-y`, default 60 degrees)
//! and the pose (`--eye/--target/--up`, else the identity pose).

use std::path::Path;

use anyhow::{Context, Result};
use parallax_core::Rgb;
use parallax_scene::CameraDesc;
use parallax_synth::Reference;
use parallax_synth::input::{
    Intrinsics, input_desc, read_color, read_depth, reference_from_images,
};

use crate::args::ViewArgs;

/// Reads `color` and `depth` into a reference posed by `view` (module docs).
pub fn load_color_depth(
    view: &ViewArgs,
    color: &Path,
    depth: &Path,
    focal_px: Option<f32>,
) -> Result<(Reference, CameraDesc)> {
    let c = read_color(color).with_context(|| format!("reading {}", color.display()))?;
    let d = read_depth(depth).with_context(|| format!("reading {}", depth.display()))?;
    let intr = match focal_px {
        Some(f) => Intrinsics::FocalPx(f),
        None => Intrinsics::FovYDeg(view.fov_y.unwrap_or(60.0)),
    };
    let pose = match (&view.eye, &view.target) {
        (Some(_), Some(_)) => {
            let scene = parallax_scene::Scene::default();
            let d = view.camera_desc(&scene)?;
            Some((d.eye, d.target, d.up))
        }
        _ => None,
    };
    let desc = input_desc(intr, c.height(), pose)?;
    let r = reference_from_images(c, &d, &desc, Rgb::ZERO)?;
    Ok((r, desc))
}
