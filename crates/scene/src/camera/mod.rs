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

mod pinhole;

pub use pinhole::Pinhole;

use glam::{Mat3, Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use crate::{CameraDesc, Result, SceneError};

/// A camera ray: the ray, its differentials, and the axis along which "view depth" is
/// measured for this pixel (the camera's forward axis for planar models, the face axis for cube
/// maps, the ray direction itself for spherical models).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraRay {
    pub ray: Ray,
    pub differential: RayDifferential,
    pub depth_axis: Vec3,
}

impl CameraRay {
    /// The view depth of the point at parameter `t` on this ray (positive in front).
    #[inline]
    pub fn view_depth(&self, t: f32) -> f32 {
        (self.ray.dir * t).dot(self.depth_axis)
    }
}

/// The interface every camera model implements.
pub trait CameraModel {
    /// Film width in pixels.
    fn width(&self) -> u32;
    /// Film height in pixels.
    fn height(&self) -> u32;
    /// The ray through film position `film` with lens sample `lens` in [0,1)^2 (ignored by
    /// models without an aperture) for colour `channel` 0, 1, 2 = R, G, B (ignored by models
    /// without per-channel distortion). `None` where the film position maps to no ray (outside
    /// a fisheye's circle, off the film).
    fn generate_ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<CameraRay>;
    /// The film position of world point `p` (for the centre of the lens / channel `channel`),
    /// or `None` if it is behind the camera or outside the model's field of view.
    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2>;
}

/// The camera's orientation: a right-handed frame, looking down -z (DESIGN.md conventions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    pub position: Vec3,
    /// Columns: right (+x), up (+y), backward (+z); the camera looks along `-z`.
    pub basis: Mat3,
}

impl CameraFrame {
    /// From a validated look-at description.
    pub fn look_at(desc: &CameraDesc) -> Result<Self> {
        desc.validate()?;
        let forward = (desc.target - desc.eye).normalize();
        let right = forward.cross(desc.up).normalize();
        let up = right.cross(forward);
        Ok(Self {
            position: desc.eye,
            basis: Mat3::from_cols(right, up, -forward),
        })
    }
    #[inline]
    pub fn right(&self) -> Vec3 {
        self.basis.x_axis
    }
    #[inline]
    pub fn up(&self) -> Vec3 {
        self.basis.y_axis
    }
    #[inline]
    pub fn forward(&self) -> Vec3 {
        -self.basis.z_axis
    }
    /// World point -> camera space.
    #[inline]
    pub fn to_camera(&self, p: Vec3) -> Vec3 {
        self.basis.transpose() * (p - self.position)
    }
    /// Camera-space direction -> world.
    #[inline]
    pub fn dir_to_world(&self, d: Vec3) -> Vec3 {
        self.basis * d
    }
}

/// Which camera model to build (the CLI's `--model`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModelKind {
    Pinhole,
    Orthographic,
    ThinLens,
    Stereo,
    Cube,
    Equirect,
    Fisheye,
    Distorted,
}

impl ModelKind {
    pub const ALL: [ModelKind; 8] = [
        ModelKind::Pinhole,
        ModelKind::Orthographic,
        ModelKind::ThinLens,
        ModelKind::Stereo,
        ModelKind::Cube,
        ModelKind::Equirect,
        ModelKind::Fisheye,
        ModelKind::Distorted,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Pinhole => "pinhole",
            ModelKind::Orthographic => "ortho",
            ModelKind::ThinLens => "thinlens",
            ModelKind::Stereo => "stereo",
            ModelKind::Cube => "cube",
            ModelKind::Equirect => "equirect",
            ModelKind::Fisheye => "fisheye",
            ModelKind::Distorted => "distorted",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|m| m.name()).collect();
                SceneError::Camera(format!(
                    "unknown camera model {s:?}; expected one of {}",
                    names.join(", ")
                ))
            })
    }
}

/// Parameters of the models beyond the pose and film size, with their defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraOptions {
    /// Thin lens: aperture radius (m). Default 0.05.
    pub aperture_radius: f32,
    /// Thin lens: focus distance (m); `None` = distance from eye to target.
    pub focus_distance: Option<f32>,
    /// Stereo: interpupillary distance (m). Default 0.065.
    pub ipd: f32,
    /// Orthographic: height of the view in metres; `None` = frame the target at the pinhole's
    /// field of view.
    pub ortho_height: Option<f32>,
    /// Fisheye / equirect: horizontal and vertical field of view in degrees. Default 210 x 130
    /// for the fisheye and 360 x 180 for the equirect.
    pub fov_deg: Option<Vec2>,
    /// Radial distortion: per-channel (R, G, B) coefficients `(k1, k2)` of
    /// `r_d = r (1 + k1 r^2 + k2 r^4)`. Default: an HMD-like pincushion.
    pub distortion: [[f32; 2]; 3],
}

impl Default for CameraOptions {
    fn default() -> Self {
        Self {
            aperture_radius: 0.05,
            focus_distance: None,
            ipd: 0.065,
            ortho_height: None,
            fov_deg: None,
            distortion: [[0.22, 0.24], [0.24, 0.26], [0.26, 0.28]],
        }
    }
}

/// The closed set of camera models.
#[derive(Clone, Debug, PartialEq)]
pub enum Camera {
    Pinhole(Pinhole),
}

impl Camera {
    /// Builds a model from a pose, a film size and options. Errors on an invalid pose, a zero or
    /// absurd film size, or invalid options.
    pub fn new(
        kind: ModelKind,
        desc: &CameraDesc,
        width: u32,
        height: u32,
        opts: &CameraOptions,
    ) -> Result<Self> {
        parallax_core::image::check_size(width, height)
            .map_err(|e| SceneError::Camera(e.to_string()))?;
        let _ = opts;
        match kind {
            ModelKind::Pinhole => Ok(Camera::Pinhole(Pinhole::new(desc, width, height)?)),
            other => Err(SceneError::Camera(format!(
                "camera model {} is not implemented yet",
                other.name()
            ))),
        }
    }

    fn inner(&self) -> &dyn CameraModel {
        match self {
            Camera::Pinhole(c) => c,
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
    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2> {
        self.inner().project(p, channel)
    }
}
