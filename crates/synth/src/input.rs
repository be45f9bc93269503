//! A colour + depth image pair as a single-layer reference, so any image with depth (a game
//! frame, a photo with a depth map) goes through the same warp path as a rendered reference.
//!
//! **Colour:** an EXR with channels `R`, `G`, `B` (linear), or a PNG / JPEG (sRGB, decoded to
//! linear). **Depth:** an EXR holding per-pixel **view depth** (positive distance along the
//! view axis, metres, not the distance to the eye) in the first present channel of `Z`,
//! `depth` (what `parallax render --aov depth` writes), `Y`, `R`. A non-finite or non-positive
//! depth means "no surface": background at infinity, whose colour misses take by direction
//! ([`crate::environment`]); `background` is used only when the input has no such pixel. **Camera:** a pinhole with the vertical
//! field of view in degrees or the focal length in pixels (`tan(fov_y / 2) = (H / 2) / f`),
//! at a pose (`eye`, `target`, `up`) or the identity pose (eye at the origin looking down -Z,
//! +Y up). Normals are reconstructed from depth (Widmer's input; the G-buffer normal channel is
//! filled with them, so either [`parallax_screen::NormalSource`] works).

use std::path::Path;
use std::sync::Arc;

use glam::{Vec2, Vec3};
use parallax_core::image::png::read_image;
use parallax_core::image::{GBuffer, read_exr};
use parallax_core::{Image, Rgb};
use parallax_raster::normals::{DEFAULT_MAX_REL_ERROR, normals_from_depth};
use parallax_scene::CameraDesc;
use parallax_scene::camera::Pinhole;
use parallax_screen::{CubeNear, UnitCube};

use crate::SynthError;
use crate::environment::Environment;
use crate::layers::{Reference, ReferenceTimes};

/// Depth channel names tried in order.
pub const DEPTH_CHANNELS: [&str; 4] = ["Z", "depth", "Y", "R"];

/// The pinhole intrinsics of the input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Intrinsics {
    FovYDeg(f32),
    FocalPx(f32),
}

/// Reads a linear colour image (EXR `R,G,B` or PNG / JPEG).
pub fn read_color(path: &Path) -> Result<Image<Rgb>, SynthError> {
    let is_exr = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        return Ok(read_image(path)?);
    }
    let e = read_exr(path)?;
    let ch = |n: &str| {
        e.channel(n).ok_or_else(|| {
            SynthError::Invalid(format!("{}: no channel {n} (need R, G, B)", path.display()))
        })
    };
    let (r, g, b) = (ch("R")?, ch("G")?, ch("B")?);
    let data = (0..r.len()).map(|i| Vec3::new(r[i], g[i], b[i])).collect();
    Ok(Image::from_vec(e.width, e.height, data)?)
}

/// Reads the view depth of an EXR (first of [`DEPTH_CHANNELS`]).
pub fn read_depth(path: &Path) -> Result<Image<f32>, SynthError> {
    let e = read_exr(path)?;
    let data = DEPTH_CHANNELS
        .iter()
        .find_map(|n| e.channel(n))
        .ok_or_else(|| {
            SynthError::Invalid(format!(
                "{}: no depth channel (tried Z, depth, Y, R)",
                path.display()
            ))
        })?;
    Ok(Image::from_vec(e.width, e.height, data.to_vec())?)
}

/// The pose + intrinsics as a camera description (`pose = None`: identity pose).
pub fn input_desc(
    intrinsics: Intrinsics,
    height: u32,
    pose: Option<(Vec3, Vec3, Vec3)>,
) -> Result<CameraDesc, SynthError> {
    let fov = match intrinsics {
        Intrinsics::FovYDeg(f) => f,
        Intrinsics::FocalPx(f) => {
            if !(f.is_finite() && f > 0.0) {
                return Err(SynthError::Invalid(format!(
                    "focal length must be > 0 px, got {f}"
                )));
            }
            2.0 * (0.5 * height as f32 / f).atan().to_degrees()
        }
    };
    let (eye, target, up) = pose.unwrap_or((Vec3::ZERO, Vec3::NEG_Z, Vec3::Y));
    let desc = CameraDesc::new(eye, target, up, fov);
    desc.validate()?;
    Ok(desc)
}

/// A single-layer reference from a colour image and its view depth seen by `desc`'s pinhole
/// (unit cube: [`CubeNear::Fitted`]; [`Reference::fit_cube`] picks another near plane, and
/// [`crate::stereo::warp_stereo`] applies [`crate::MethodOptions::cube_near`]).
pub fn reference_from_images(
    color: Image<Rgb>,
    depth: &Image<f32>,
    desc: &CameraDesc,
    background: Rgb,
) -> Result<Reference, SynthError> {
    let (w, h) = (color.width(), color.height());
    if (depth.width(), depth.height()) != (w, h) {
        return Err(SynthError::Invalid(format!(
            "colour is {w}x{h} but depth is {}x{}",
            depth.width(),
            depth.height()
        )));
    }
    let camera = Pinhole::new(desc, w, h)?;
    let clean = depth.map(|&d| {
        if d.is_finite() && d > 0.0 {
            d
        } else {
            f32::INFINITY
        }
    });
    let normals = normals_from_depth(&clean, &camera, DEFAULT_MAX_REL_ERROR)?;
    let mut g = GBuffer::new(w, h)?;
    for y in 0..h {
        for x in 0..w {
            let d = *clean.get(x, y);
            if !d.is_finite() {
                continue;
            }
            let i = g.index(x, y);
            let dir = camera.camera_dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            g.depth[i] = d;
            g.position[i] = camera.frame.position + camera.frame.dir_to_world(dir * d);
            g.normal[i] = *normals.normals.get(x, y);
            g.albedo[i] = *color.get(x, y);
            g.material_id[i] = 0;
            g.primitive_id[i] = i as u32;
        }
    }
    let cube = UnitCube::fit_depths(&camera, [&g.depth[..]])?;
    // Pixels without depth are background at infinity: they keep their colour, and rays
    // that miss every surface take it by direction (`crate::environment`).
    let sky: Vec<bool> = clean.data().iter().map(|d| !d.is_finite()).collect();
    let environment = Environment::from_sky(&camera, &color, &sky).map(Arc::new);
    Ok(Reference {
        camera,
        layers: vec![g],
        colors: vec![color],
        cube,
        cube_near: CubeNear::Fitted,
        background,
        environment,
        times: ReferenceTimes::default(),
    })
}
