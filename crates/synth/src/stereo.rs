//! Stereo warping (Widmer et al. 2015, §5.1, Table 2): a cyclopean reference view is rendered
//! with `N` layers and warped to the left and right eye, each `ipd / 2` along the reference's
//! right axis with parallel optical axes ([`parallax_scene::camera::StereoRig`]).

use std::time::Instant;

use parallax_scene::CameraDesc;
use parallax_scene::camera::{Eye, Pinhole, StereoRig};

use crate::SynthError;
use crate::layers::Reference;
use crate::method::{Method, MethodOptions, Synthesizer};
use crate::warp::WarpedView;

/// The two eyes of `desc` (left, right), each `width x height`.
pub fn stereo_eyes(
    desc: &CameraDesc,
    width: u32,
    height: u32,
    ipd: f32,
) -> Result<[Pinhole; 2], SynthError> {
    let rig = StereoRig::new(desc, width, height, ipd)?;
    Ok([rig.eye(Eye::Left).clone(), rig.eye(Eye::Right).clone()])
}

/// A synthesised stereo pair.
#[derive(Clone, Debug)]
pub struct StereoViews {
    /// Left, right.
    pub eyes: [Pinhole; 2],
    pub views: [WarpedView; 2],
}

impl StereoViews {
    /// `T_eye`: mean synthesis milliseconds of one eye.
    pub fn ms_eye(&self) -> f64 {
        (self.views[0].ms + self.views[1].ms) * 0.5
    }
}

/// Fits `reference`'s cube with `opts.cube_near` ([`Reference::fit_cube`], not timed), builds
/// `method` over it (its time goes to `reference.times.build_ms`) and warps the reference to
/// both eyes of the pose `desc` (the reference's own pose).
pub fn warp_stereo(
    reference: &mut Reference,
    desc: &CameraDesc,
    ipd: f32,
    method: Method,
    opts: &MethodOptions,
) -> Result<StereoViews, SynthError> {
    let eyes = stereo_eyes(desc, reference.width(), reference.height(), ipd)?;
    reference.fit_cube(opts.cube_near)?;
    let t = Instant::now();
    let synth = Synthesizer::build(method, reference, opts)?;
    reference.times.build_ms = t.elapsed().as_secs_f64() * 1e3;
    let left = synth.view(reference, &eyes[0])?;
    let right = synth.view(reference, &eyes[1])?;
    Ok(StereoViews {
        eyes,
        views: [left, right],
    })
}
