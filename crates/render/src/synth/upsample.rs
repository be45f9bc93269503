//! Temporal upsampling, 15 -> 60 Hz (Widmer et al. 2015, §5.1, Table 3): along a camera path
//! sampled at 60 Hz, every `period`-th frame (default 4) is rendered as a reference with `N`
//! layers; the `period - 1` frames after it are synthesised by tracing their own camera's rays
//! against that **previous** reference. The paper does not spell out which reference a frame
//! uses; its discussion ("moving away from the reference frame increases the reprojection
//! magnitude", growing variance of `T_syn`) matches extrapolation from the last reference, which
//! is also what a renderer can do without waiting for the next reference (no added latency).
//!
//! A scene without a camera path gets [`default_path`]: a 1 s dolly towards the target with a
//! slight sideways drift from its default camera.

use std::time::Instant;

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::{Image, Rgb};
use parallax_scene::camera::{CameraFrame, Pinhole};
use parallax_scene::path::{CameraKey, CameraPath};
use parallax_scene::{CameraDesc, Scene};
use serde::Serialize;

use super::SynthError;
use super::layers::{Reference, Shading, capture_reference};
use super::method::{Method, MethodOptions, Synthesizer};
use super::warp::WarpedView;

/// Options of the upsampling run.
#[derive(Clone, Copy, Debug)]
pub struct UpsampleOptions {
    /// Output frames (at `fps`), >= 1.
    pub frames: u32,
    /// Output frame rate (60).
    pub fps: f32,
    /// A reference every `period` frames (4: 15 -> 60 Hz), >= 1.
    pub period: u32,
    pub layers: usize,
    pub method: Method,
    pub method_opts: MethodOptions,
    pub shading: Shading,
    pub seed: u64,
}

/// One output frame.
pub struct UpsampleFrame<'a> {
    pub index: u32,
    pub camera: Pinhole,
    /// The reference in effect (this frame's own when `is_reference`).
    pub reference: &'a Reference,
    pub is_reference: bool,
    /// The synthesised view (`None` for reference frames, whose image is layer 0's colour).
    pub view: Option<WarpedView>,
}

impl UpsampleFrame<'_> {
    /// The frame's image.
    pub fn image(&self) -> &Image<Rgb> {
        match &self.view {
            Some(v) => &v.image,
            None => &self.reference.colors[0],
        }
    }
}

/// Per-frame timings, returned for every frame.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FrameTimes {
    pub index: u32,
    pub is_reference: bool,
    /// `T_ref` of a reference frame (capture + shade + build), 0 otherwise.
    pub ms_ref: f64,
    /// `T_syn` of a synthesised frame, 0 otherwise.
    pub ms_syn: f64,
}

/// A short path for scenes without one: 1 s from the default camera, dollying 15% of the way
/// to the target and drifting sideways by 5% of that distance.
pub fn default_path(desc: &CameraDesc) -> Result<CameraPath, SynthError> {
    let frame = CameraFrame::look_at(desc)?;
    let dist = (desc.target - desc.eye).length();
    let end = desc.eye + (desc.target - desc.eye) * 0.15 + frame.right() * (0.05 * dist);
    let key = |time: f32, eye: Vec3| CameraKey {
        time,
        camera: CameraDesc { eye, ..*desc },
    };
    Ok(CameraPath::new(
        vec![key(0.0, desc.eye), key(1.0, end)],
        60.0,
        60,
    ))
}

/// The scene's path, or [`default_path`] around its default camera.
pub fn scene_path(scene: &Scene) -> Result<CameraPath, SynthError> {
    match &scene.camera_path {
        Some(p) => Ok(p.clone()),
        None => default_path(&scene.camera(None)?),
    }
}

/// Runs the sequence (each reference's cube fitted with `opts.method_opts.cube_near`), calling `on_frame` for every frame in order; returns the timings.
pub fn upsample(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    width: u32,
    height: u32,
    opts: &UpsampleOptions,
    on_frame: &mut dyn FnMut(&UpsampleFrame) -> Result<(), SynthError>,
) -> Result<Vec<FrameTimes>, SynthError> {
    if opts.frames == 0 || opts.period == 0 || !(opts.fps > 0.0) {
        return Err(SynthError::Invalid(format!(
            "need frames >= 1, period >= 1, fps > 0 (got {}, {}, {})",
            opts.frames, opts.period, opts.fps
        )));
    }
    let t0 = path.keys[0].time;
    let mut times = Vec::with_capacity(opts.frames as usize);
    let mut current: Option<(Reference, Synthesizer)> = None;
    for i in 0..opts.frames {
        let desc = path.at(t0 + i as f32 / opts.fps);
        let camera = Pinhole::new(&desc, width, height)?;
        let is_reference = i % opts.period == 0;
        let mut ft = FrameTimes {
            index: i,
            is_reference,
            ms_ref: 0.0,
            ms_syn: 0.0,
        };
        if is_reference {
            let mut r =
                capture_reference(scene, bvh, &camera, opts.layers, opts.shading, opts.seed)?;
            r.fit_cube(opts.method_opts.cube_near)?;
            let t = Instant::now();
            let s = Synthesizer::build(opts.method, &r, &opts.method_opts)?;
            r.times.build_ms = t.elapsed().as_secs_f64() * 1e3;
            ft.ms_ref = r.times.total_ms();
            current = Some((r, s));
        }
        let (reference, synth) = current.as_ref().expect("frame 0 is a reference");
        let view = if is_reference {
            None
        } else {
            let v = synth.view(reference, &camera)?;
            ft.ms_syn = v.ms;
            Some(v)
        };
        on_frame(&UpsampleFrame {
            index: i,
            camera,
            reference,
            is_reference,
            view,
        })?;
        times.push(ft);
    }
    Ok(times)
}
