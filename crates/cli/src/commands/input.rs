//! A user's colour + depth image pair as a single-layer reference, shared by every command
//! that takes one (`warp`, `dof`, `lightfield`): the colour (EXR linear or PNG / JPEG sRGB),
//! its view depth (EXR), the intrinsics (`--focal-px`, else `--fov-y`, default 60 degrees)
//! and the pose (`--eye/--target/--up`, else the identity pose).
//!
//! **Output encoding.** Renders of a scene are written through the display transform of the
//! scores (ACES filmic, [`SCORE_TONEMAP`]); a user's content keeps its encoding: PNGs made
//! from colour + depth input are plain sRGB of the linear values ([`USER_TONEMAP`]: no tone
//! curve, so an identity warp of an sRGB PNG returns its bytes), and `--exr` (where offered)
//! writes the linear values as EXR.

use std::path::Path;

use anyhow::{Context, Result};
use parallax_core::Rgb;
use parallax_core::image::png::ToneMapping;
use parallax_render::score::SCORE_TONEMAP;
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

/// PNG encoding of a user's content: sRGB of the clamped linear values, no tone curve
/// (module docs).
pub const USER_TONEMAP: ToneMapping = ToneMapping {
    exposure: 0.0,
    tonemap: parallax_core::image::png::Tonemap::Clamp,
};

/// The PNG encoding of a command's outputs: [`USER_TONEMAP`] for colour + depth input,
/// else the scores' display transform.
pub fn output_tonemap(user_input: bool) -> ToneMapping {
    if user_input {
        USER_TONEMAP
    } else {
        SCORE_TONEMAP
    }
}
