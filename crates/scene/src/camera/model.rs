//! What every camera model shares: the [`CameraModel`] interface, the ray it generates
//! ([`CameraRay`]), the look-at frame, the closed set of model kinds ([`ModelKind`]) and the
//! options the models are built from ([`CameraOptions`]).

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
    /// The ray of [`Self::generate_ray`] alone, without its differential and depth axis (what
    /// a ray caster needs), equal to `generate_ray(film, lens, channel).map(|r| r.ray)` bit for
    /// bit. Models whose differential costs more than the ray override it.
    #[inline]
    fn ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<Ray> {
        self.generate_ray(film, lens, channel).map(|r| r.ray)
    }
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
    /// `r_u = r_d (1 + k1 r_d^2 + k2 r_d^4)` (display radius `r_d` -> undistorted tangent-space
    /// radius `r_u`, both in units of the half-height; see [`super::distortion`]). Default: a
    /// pre-distortion for an HMD-like pincushion lens.
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

/// An angular field of view for `model`: `fov_deg` (degrees) or `default`, checked against
/// `(0, max.x] x (0, max.y]`, returned in radians.
pub(crate) fn angular_fov(
    model: &str,
    fov_deg: Option<Vec2>,
    default: Vec2,
    max: Vec2,
) -> Result<Vec2> {
    let fov = fov_deg.unwrap_or(default);
    if !(fov.x > 0.0 && fov.x <= max.x && fov.y > 0.0 && fov.y <= max.y) {
        return Err(camera_error(format!(
            "{model} fov must be in (0, {}] x (0, {}] degrees, got {} x {}",
            max.x, max.y, fov.x, fov.y
        )));
    }
    Ok(Vec2::new(fov.x.to_radians(), fov.y.to_radians()))
}

impl CameraOptions {
    /// Checks the options every model shares a meaning of (model-specific ranges such as the
    /// field of view are checked by the model that uses them).
    pub fn validate(&self) -> Result<()> {
        if !(self.aperture_radius.is_finite() && self.aperture_radius >= 0.0) {
            return Err(camera_error(format!(
                "aperture radius must be finite and >= 0, got {}",
                self.aperture_radius
            )));
        }
        if let Some(f) = self.focus_distance
            && !(f.is_finite() && f > 0.0)
        {
            return Err(camera_error(format!(
                "focus distance must be finite and > 0, got {f}"
            )));
        }
        if !(self.ipd.is_finite() && self.ipd >= 0.0) {
            return Err(camera_error(format!(
                "ipd (eye separation) must be finite and >= 0, got {}",
                self.ipd
            )));
        }
        if let Some(h) = self.ortho_height
            && !(h.is_finite() && h > 0.0)
        {
            return Err(camera_error(format!(
                "ortho height must be finite and > 0, got {h}"
            )));
        }
        if let Some(f) = self.fov_deg
            && !f.is_finite()
        {
            return Err(camera_error(format!("fov must be finite, got {f}")));
        }
        if self.distortion.iter().flatten().any(|k| !k.is_finite()) {
            return Err(camera_error(format!(
                "distortion coefficients must be finite, got {:?}",
                self.distortion
            )));
        }
        Ok(())
    }
}

/// A [`SceneError::Camera`] with `message`.
pub(crate) fn camera_error(message: impl Into<String>) -> SceneError {
    SceneError::Camera(message.into())
}

/// Checks a film size given in u64 (composite films multiply the per-view size).
pub(crate) fn check_film(width: u64, height: u64) -> Result<(u32, u32)> {
    let w = u32::try_from(width)
        .map_err(|_| camera_error(format!("film width {width} does not fit in 32 bits")))?;
    let h = u32::try_from(height)
        .map_err(|_| camera_error(format!("film height {height} does not fit in 32 bits")))?;
    parallax_core::image::check_size(w, h).map_err(|e| camera_error(format!("film: {e}")))?;
    Ok((w, h))
}

/// The derivative of `n = d / |d|` given `dd` (the derivative of `d`), with `len = |d|`:
/// `dn = (I - n n^T) dd / |d|` (Igehy 1999, eq. 8 for normalised directions).
#[inline]
pub(crate) fn normalized_derivative(n: Vec3, len: f32, dd: Vec3) -> Vec3 {
    (dd - n * n.dot(dd)) / len
}
