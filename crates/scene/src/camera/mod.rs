//! Camera models: one interface, each model in its own file (pbrt-style closed set).
//!
//! Every model answers two questions:
//! - [`CameraModel::generate_ray`]: the ray (with ray differentials = pixel footprint) for a
//!   continuous film position, a lens sample and a colour channel;
//! - [`CameraModel::project`]: the film position a world point maps to (the inverse).
//!
//! Film coordinates are continuous pixels: pixel `(x, y)` covers `[x, x+1) x [y, y+1)` and has its
//! centre at `(x + 0.5, y + 0.5)`; `y` grows downward. Models whose image is made of several views
//! (stereo rig, cube map) lay the views side by side on one film; see each model.
//!
//! | model | file | film | depth axis | differentials |
//! |---|---|---|---|---|
//! | `pinhole` | [`pinhole`] | `w x h` | forward | analytic |
//! | `ortho` | [`orthographic`] | `w x h` | forward | analytic (origin only) |
//! | `thinlens` | [`thin_lens`] | `w x h` | forward | analytic (per lens sample) |
//! | `stereo` | [`stereo`] | `2w x h` (w per eye) | forward | analytic (per eye) |
//! | `cube` | [`cube`] | `6w x w` (w per face) | face axis | analytic (per face) |
//! | `equirect` | [`equirect`] | `w x h` | ray direction | analytic |
//! | `fisheye` | [`fisheye`] | `w x h` | ray direction | analytic |
//! | `distorted` | [`distortion`] | `w x h` | forward | analytic (per channel) |
//!
//! Every model validates its parameters when built and returns [`crate::SceneError::Camera`] with a
//! message naming the parameter and the allowed range.

pub mod cube;
pub mod distortion;
pub mod equirect;
pub mod fisheye;
pub mod orthographic;
pub mod pinhole;
pub mod stereo;
pub mod thin_lens;

pub use cube::CubeMap;
pub use distortion::Distorted;
pub use equirect::Equirect;
pub use fisheye::Fisheye;
pub use orthographic::Orthographic;
pub use pinhole::Pinhole;
pub use stereo::{Eye, StereoRig, eye_camera};
pub use thin_lens::ThinLens;

mod model;

pub use model::{CameraFrame, CameraModel, CameraOptions, CameraRay, ModelKind};
pub(crate) use model::{angular_fov, camera_error, check_film, normalized_derivative};

use glam::{Vec2, Vec3};

use crate::{CameraDesc, Result};

/// The closed set of camera models.
#[derive(Clone, Debug, PartialEq)]
pub enum Camera {
    Pinhole(Pinhole),
    Orthographic(Orthographic),
    ThinLens(ThinLens),
    Stereo(StereoRig),
    Cube(CubeMap),
    Equirect(Equirect),
    Fisheye(Fisheye),
    Distorted(Distorted),
}

impl Camera {
    /// Builds a model from a pose, a film size and options. Errors on an invalid pose, a zero or
    /// absurd film size, or invalid options.
    ///
    /// `width x height` is the film of single-view models. Composite models take the size of
    /// one view: the stereo rig's film is `2 * width x height` (left eye left), the cube map's
    /// is `6 * width x width` (faces of `width x width`; `height` must still be valid but is
    /// otherwise unused). The shared options are checked whatever the model
    /// ([`CameraOptions::validate`]: a negative aperture is an error even for a pinhole); the
    /// model-specific ranges (fov, distortion monotonicity) by the model that uses them.
    pub fn new(
        kind: ModelKind,
        desc: &CameraDesc,
        width: u32,
        height: u32,
        opts: &CameraOptions,
    ) -> Result<Self> {
        check_film(width as u64, height as u64)?;
        opts.validate()?;
        let (w, h) = (width, height);
        Ok(match kind {
            ModelKind::Pinhole => Camera::Pinhole(Pinhole::new(desc, w, h)?),
            ModelKind::Orthographic => {
                Camera::Orthographic(Orthographic::new(desc, w, h, opts.ortho_height)?)
            }
            ModelKind::ThinLens => Camera::ThinLens(ThinLens::new(
                desc,
                w,
                h,
                opts.aperture_radius,
                opts.focus_distance,
            )?),
            ModelKind::Stereo => Camera::Stereo(StereoRig::new(desc, w, h, opts.ipd)?),
            ModelKind::Cube => Camera::Cube(CubeMap::new(desc, w)?),
            ModelKind::Equirect => Camera::Equirect(Equirect::new(desc, w, h, opts.fov_deg)?),
            ModelKind::Fisheye => Camera::Fisheye(Fisheye::new(desc, w, h, opts.fov_deg)?),
            ModelKind::Distorted => Camera::Distorted(Distorted::new(desc, w, h, opts.distortion)?),
        })
    }

    /// Which model this is.
    pub fn kind(&self) -> ModelKind {
        match self {
            Camera::Pinhole(_) => ModelKind::Pinhole,
            Camera::Orthographic(_) => ModelKind::Orthographic,
            Camera::ThinLens(_) => ModelKind::ThinLens,
            Camera::Stereo(_) => ModelKind::Stereo,
            Camera::Cube(_) => ModelKind::Cube,
            Camera::Equirect(_) => ModelKind::Equirect,
            Camera::Fisheye(_) => ModelKind::Fisheye,
            Camera::Distorted(_) => ModelKind::Distorted,
        }
    }

    /// How many colour channels need their own rays: 3 for per-channel lens distortion
    /// (subpixel rendering), 1 for every other model (channel argument ignored).
    pub fn channel_count(&self) -> usize {
        if matches!(self, Camera::Distorted(_)) {
            3
        } else {
            1
        }
    }

    fn inner(&self) -> &dyn CameraModel {
        match self {
            Camera::Pinhole(c) => c,
            Camera::Orthographic(c) => c,
            Camera::ThinLens(c) => c,
            Camera::Stereo(c) => c,
            Camera::Cube(c) => c,
            Camera::Equirect(c) => c,
            Camera::Fisheye(c) => c,
            Camera::Distorted(c) => c,
        }
    }
}

impl CameraModel for Camera {
    fn width(&self) -> u32 {
        self.inner().width()
    }
    fn height(&self) -> u32 {
        self.inner().height()
    }
    fn generate_ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<CameraRay> {
        self.inner().generate_ray(film, lens, channel)
    }
    fn ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<parallax_core::Ray> {
        self.inner().ray(film, lens, channel)
    }
    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2> {
        self.inner().project(p, channel)
    }
}
