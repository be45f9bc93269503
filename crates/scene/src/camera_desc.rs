//! Camera poses: the look-at description every camera model is built from, and the named
//! cameras of a scene.

use glam::Vec3;

use crate::{Result, SceneError};

/// A look-at camera pose with a vertical field of view: what `--eye --target --up --fov-y`
/// and the named cameras of a scene describe. Camera models are built from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees (pinhole-like models).
    pub fov_y_deg: f32,
}

impl CameraDesc {
    pub fn new(eye: Vec3, target: Vec3, up: Vec3, fov_y_deg: f32) -> Self {
        Self {
            eye,
            target,
            up,
            fov_y_deg,
        }
    }

    /// Checks the pose: finite, target distinct from eye, up not parallel to the view direction,
    /// field of view in (0, 180).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(SceneError::Camera(m.to_string()));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("eye, target and up must be finite");
        }
        let f = self.target - self.eye;
        if f.length_squared() <= 1e-20 {
            return bad("target must differ from eye");
        }
        if f.normalize()
            .cross(self.up.normalize_or_zero())
            .length_squared()
            < 1e-10
        {
            return bad("up must not be parallel to the view direction");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return bad("fov-y must be in (0, 180) degrees");
        }
        Ok(())
    }
}

/// A camera the scene file or built-in scene names.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedCamera {
    pub name: String,
    pub desc: CameraDesc,
}
