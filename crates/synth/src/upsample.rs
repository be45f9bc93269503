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

use crate::SynthError;
use crate::layers::{Reference, capture_reference};
use crate::method::{Method, MethodOptions, Synthesizer};
use crate::warp::WarpedView;
use parallax_render::score::Shading;

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
    let methods = [(opts.method, opts.method_opts)];
    upsample_interleaved(
        scene,
        bvh,
        path,
        width,
        height,
        opts,
        &methods,
        &mut |_, f| on_frame(f),
    )
    .pop()
    .expect("one result per method")
}

/// [`upsample`] of several `(method, options)` at once (`opts.method` and
/// `opts.method_opts` are ignored), interleaved: every reference is captured once and every
/// method is built over it (its cube fitted with the method's `cube_near`), then each
/// synthesised frame is run by every method in turn, so a disturbance of the machine hits all
/// methods alike. `on_frame(k, frame)` is called for method `k` and every frame, in frame
/// order. Returns per method its timings (`T_ref` = the shared capture and shading + its
/// own build) or its first error (a capture error fails every method); a failed method is
/// not run further. Each method's views equal those of [`upsample`] alone. The frames'
/// `reference.times.build_ms` is 0 (references are shared; each method's build time is in
/// its `ms_ref`).
#[allow(clippy::too_many_arguments)]
pub fn upsample_interleaved(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    width: u32,
    height: u32,
    opts: &UpsampleOptions,
    methods: &[(Method, MethodOptions)],
    on_frame: &mut dyn FnMut(usize, &UpsampleFrame) -> Result<(), SynthError>,
) -> Vec<Result<Vec<FrameTimes>, SynthError>> {
    let all = 0..opts.frames;
    upsample_range(
        scene, bvh, path, width, height, opts, methods, all, on_frame,
    )
}

/// [`upsample_interleaved`] over the output frames `frames` of the `opts.frames` of the
/// sequence only (a shard of a long sequence): `frames.start` must be a multiple of
/// `opts.period` (a reference frame), so every frame sees the reference it has in the whole
/// sequence and its image is bit-identical to the whole run's.
#[allow(clippy::too_many_arguments)]
pub fn upsample_range(
    scene: &Scene,
    bvh: &Bvh,
    path: &CameraPath,
    width: u32,
    height: u32,
    opts: &UpsampleOptions,
    methods: &[(Method, MethodOptions)],
    frames: std::ops::Range<u32>,
    on_frame: &mut dyn FnMut(usize, &UpsampleFrame) -> Result<(), SynthError>,
) -> Vec<Result<Vec<FrameTimes>, SynthError>> {
    let bad_range = opts.period == 0
        || !frames.start.is_multiple_of(opts.period)
        || frames.end > opts.frames
        || frames.start > frames.end;
    if opts.frames == 0 || bad_range || !(opts.fps > 0.0) {
        let msg = format!(
            "need frames >= 1, period >= 1, fps > 0 and a frame range inside the sequence starting at a reference (got {}, {}, {}, {:?})",
            opts.frames, opts.period, opts.fps, frames
        );
        return methods
            .iter()
            .map(|_| Err(SynthError::Invalid(msg.clone())))
            .collect();
    }
    let t0 = path.keys[0].time;
    let mut out: Vec<Result<Vec<FrameTimes>, SynthError>> = methods
        .iter()
        .map(|_| Ok(Vec::with_capacity(frames.len())))
        .collect();
    // Per method: the index of its fitted reference and its structure.
    let mut current: Vec<Option<(usize, Synthesizer)>> = methods.iter().map(|_| None).collect();
    let mut refs: Vec<Reference> = Vec::new();
    for i in frames {
        if out.iter().all(Result::is_err) {
            break;
        }
        let desc = path.at(t0 + i as f32 / opts.fps);
        let camera = match Pinhole::new(&desc, width, height) {
            Ok(c) => c,
            Err(e) => {
                fail_all(&mut out, e.into());
                break;
            }
        };
        let is_reference = i % opts.period == 0;
        if is_reference {
            refs.clear();
            let r = match capture_reference(
                scene,
                bvh,
                &camera,
                opts.layers,
                opts.shading,
                opts.seed,
            ) {
                Ok(r) => r,
                Err(e) => {
                    fail_all(&mut out, e);
                    break;
                }
            };
            for (k, (method, mo)) in methods.iter().enumerate() {
                current[k] = None;
                if out[k].is_err() {
                    continue;
                }
                let built = (|| {
                    let j = match refs.iter().position(|f| f.cube_near == mo.cube_near) {
                        Some(j) => j,
                        None => {
                            let mut f = r.clone();
                            f.fit_cube(mo.cube_near)?;
                            refs.push(f);
                            refs.len() - 1
                        }
                    };
                    let t = Instant::now();
                    let s = Synthesizer::build(*method, &refs[j], mo)?;
                    Ok::<_, SynthError>((j, s, t.elapsed().as_secs_f64() * 1e3))
                })();
                match built {
                    Ok((j, s, build_ms)) => {
                        current[k] = Some((j, s));
                        let mut t = refs[j].times;
                        t.build_ms = build_ms;
                        let ft = FrameTimes {
                            index: i,
                            is_reference,
                            ms_ref: t.total_ms(),
                            ms_syn: 0.0,
                        };
                        let frame = UpsampleFrame {
                            index: i,
                            camera: camera.clone(),
                            reference: &refs[j],
                            is_reference,
                            view: None,
                        };
                        push_or_fail(&mut out[k], ft, on_frame(k, &frame));
                    }
                    Err(e) => out[k] = Err(e),
                }
            }
            continue;
        }
        for (k, cur) in current.iter().enumerate() {
            let (Some((j, synth)), true) = (cur, out[k].is_ok()) else {
                continue;
            };
            let reference = &refs[*j];
            let v = match synth.view(reference, &camera) {
                Ok(v) => v,
                Err(e) => {
                    out[k] = Err(e);
                    continue;
                }
            };
            let ft = FrameTimes {
                index: i,
                is_reference,
                ms_ref: 0.0,
                ms_syn: v.ms,
            };
            let frame = UpsampleFrame {
                index: i,
                camera: camera.clone(),
                reference,
                is_reference,
                view: Some(v),
            };
            push_or_fail(&mut out[k], ft, on_frame(k, &frame));
        }
    }
    out
}

/// Records a frame's times, or the callback's error.
fn push_or_fail(
    out: &mut Result<Vec<FrameTimes>, SynthError>,
    ft: FrameTimes,
    done: Result<(), SynthError>,
) {
    match (done, &mut *out) {
        (Ok(()), Ok(v)) => v.push(ft),
        (Err(e), _) => *out = Err(e),
        _ => {}
    }
}

/// Fails every method still running: the first with `e`, the others with its message.
fn fail_all(out: &mut [Result<Vec<FrameTimes>, SynthError>], e: SynthError) {
    let msg = e.to_string();
    let mut first = Some(e);
    for o in out.iter_mut().filter(|o| o.is_ok()) {
        *o = Err(first
            .take()
            .unwrap_or_else(|| SynthError::Invalid(msg.clone())));
    }
}
