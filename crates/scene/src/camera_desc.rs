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

    /// The pose turned by `deg` degrees about its up axis, around the eye (positive: to the
    /// left, as a head turning; the eye, up and field of view unchanged).
    pub fn turned(&self, deg: f32) -> Self {
        let q = glam::Quat::from_axis_angle(self.up.normalize_or_zero(), deg.to_radians());
        Self {
            target: self.eye + q * (self.target - self.eye),
            ..*self
        }
    }
}

#[cfg(test)]
mod turn_tests {
    use super::*;

    /// Turning keeps the eye and the target distance, turns to the left for positive angles,
    /// and a full turn comes back.
    #[test]
    fn turned_rotates_the_view_about_up() {
        let d = CameraDesc::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::Y,
            60.0,
        );
        let t = d.turned(90.0);
        assert_eq!(t.eye, d.eye);
        // Looking along -z, a quarter turn to the left looks along -x.
        assert!(
            (t.target - Vec3::new(-1.0, 2.0, 3.0)).length() < 1e-5,
            "{}",
            t.target
        );
        assert!((d.turned(360.0).target - d.target).length() < 1e-5);
        assert_eq!(d.turned(0.0), d);
    }
}

/// A camera the scene file or built-in scene names.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedCamera {
    pub name: String,
    pub desc: CameraDesc,
}
