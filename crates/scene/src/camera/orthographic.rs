//! The orthographic camera: parallel rays along the view direction, their origins on the plane
//! through the eye perpendicular to it (pbrt-v4 §5.2.1, "Orthographic Camera").
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `ortho_height` | f32 (m) | `2 * |target - eye| * tan(fov_y / 2)` | height of the view; the width follows the film aspect |
//!
//! The default frames the target plane exactly as a pinhole of the pose's field of view would.
//! Ray `(x, y)` starts at `eye + right * X + up * Y` with `X = (2x/w - 1) * half_width` and
//! `Y = (1 - 2y/h) * half_height`, direction `forward`. Differentials are analytic: the origin
//! moves by `right * 2 half_width / w` per pixel in x and by `-up * 2 half_height / h` in y, the
//! direction does not move. `project` returns `None` for points behind the eye plane (negative
//! view depth) and film positions outside the film for points beside the view volume.

use glam::{Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraFrame, CameraModel, CameraRay, camera_error};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Orthographic {
    pub frame: CameraFrame,
    pub width: u32,
    pub height: u32,
    /// Half the view height in metres.
    pub half_height: f32,
}

impl Orthographic {
    /// `ortho_height = None` frames the target at the pose's field of view.
    pub fn new(
        desc: &CameraDesc,
        width: u32,
        height: u32,
        ortho_height: Option<f32>,
    ) -> Result<Self> {
        let frame = CameraFrame::look_at(desc)?;
        let h = match ortho_height {
            Some(h) => h,
            None => {
                2.0 * (desc.target - desc.eye).length() * (desc.fov_y_deg.to_radians() * 0.5).tan()
            }
        };
        if !(h.is_finite() && h > 0.0) {
            return Err(camera_error(format!(
                "ortho height must be finite and > 0, got {h}"
            )));
        }
        Ok(Self {
            frame,
            width,
            height,
            half_height: 0.5 * h,
        })
    }

    /// Half the view width in metres.
    #[inline]
    pub fn half_width(&self) -> f32 {
        self.half_height * self.width as f32 / self.height as f32
    }
}

impl CameraModel for Orthographic {
    fn width(&self) -> u32 {
        self.width
    }
    fn height(&self) -> u32 {
        self.height
    }

    fn generate_ray(&self, film: Vec2, _lens: Vec2, _channel: usize) -> Option<CameraRay> {
        let x = (2.0 * film.x / self.width as f32 - 1.0) * self.half_width();
        let y = (1.0 - 2.0 * film.y / self.height as f32) * self.half_height;
        let origin = self.frame.position + self.frame.right() * x + self.frame.up() * y;
        Some(CameraRay {
            ray: Ray::new(origin, self.frame.forward()),
            differential: RayDifferential {
                d_origin_dx: self.frame.right() * (2.0 * self.half_width() / self.width as f32),
                d_origin_dy: self.frame.up() * (-2.0 * self.half_height / self.height as f32),
                d_dir_dx: Vec3::ZERO,
                d_dir_dy: Vec3::ZERO,
            },
            depth_axis: self.frame.forward(),
        })
    }

    fn project(&self, p: Vec3, _channel: usize) -> Option<Vec2> {
        let q = self.frame.to_camera(p);
        // Camera space looks down -z: view depth is -q.z.
        if q.z.is_nan() || q.z > 0.0 {
            return None;
        }
        Some(Vec2::new(
            (q.x / self.half_width() + 1.0) * 0.5 * self.width as f32,
            (1.0 - q.y / self.half_height) * 0.5 * self.height as f32,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_height_frames_target_like_the_pinhole() {
        let desc = CameraDesc::new(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 90.0);
        let cam = Orthographic::new(&desc, 40, 20, None).unwrap();
        // 2 * 4 * tan(45 deg) = 8 m tall, 16 m wide.
        assert!((cam.half_height - 4.0).abs() < 1e-5);
        let top = cam
            .generate_ray(Vec2::new(20.0, 0.0), Vec2::ZERO, 0)
            .unwrap();
        let left = cam
            .generate_ray(Vec2::new(0.0, 10.0), Vec2::ZERO, 0)
            .unwrap();
        assert!((top.ray.origin - Vec3::new(0.0, 4.0, 4.0)).length() < 1e-5);
        assert!((left.ray.origin - Vec3::new(-8.0, 0.0, 4.0)).length() < 1e-5);
        assert_eq!(top.ray.dir, Vec3::NEG_Z);
        assert!(cam.project(Vec3::new(0.0, 0.0, 5.0), 0).is_none());
    }

    #[test]
    fn rejects_bad_height() {
        let desc = CameraDesc::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 60.0);
        for h in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(Orthographic::new(&desc, 4, 4, Some(h)).is_err(), "{h}");
        }
    }
}
