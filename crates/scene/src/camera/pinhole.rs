//! The pinhole camera: a perspective projection, any vertical FoV and aspect, optionally
//! off-axis (a shifted image window, as stereo displays need).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_y_deg` | f32 | from the pose | vertical field of view of the unshifted window |
//! | `shift` | Vec2 | (0, 0) | image-window offset in units of the half-extent (off-axis projection) |
//!
//! Ray differentials are analytic (Igehy 1999, §3: the derivative of the normalised direction
//! through the film); the origin is fixed, so its differentials are zero. `project` returns film
//! positions outside `[0, width] x [0, height]` for points outside the frustum (useful for
//! reprojection); it returns `None` only for points behind or on the eye plane.

use glam::{Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraFrame, CameraModel, CameraRay, normalized_derivative};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Pinhole {
    pub frame: CameraFrame,
    pub width: u32,
    pub height: u32,
    /// tan(fov_y / 2): half-height of the image window at distance 1.
    pub tan_half_y: f32,
    /// Window shift (x, y) in units of `tan_half_y` (y up).
    pub shift: Vec2,
}

impl Pinhole {
    pub fn new(desc: &CameraDesc, width: u32, height: u32) -> Result<Self> {
        let frame = CameraFrame::look_at(desc)?;
        Ok(Self {
            frame,
            width,
            height,
            tan_half_y: (desc.fov_y_deg.to_radians() * 0.5).tan(),
            shift: Vec2::ZERO,
        })
    }

    /// A pinhole with an explicit frame (any orthonormal basis, also a mirrored one as the cube
    /// map's faces use) and `tan(fov_y / 2)`.
    pub fn from_frame(frame: CameraFrame, width: u32, height: u32, tan_half_y: f32) -> Self {
        Self {
            frame,
            width,
            height,
            tan_half_y,
            shift: Vec2::ZERO,
        }
    }

    /// The same camera with an off-axis image window: `shift` in units of the half-width (x) and
    /// half-height (y), y up.
    pub fn with_shift(mut self, shift: Vec2) -> Self {
        self.shift = shift;
        self
    }

    /// Half-width of the image window at distance 1.
    #[inline]
    pub fn tan_half_x(&self) -> f32 {
        self.tan_half_y * self.width as f32 / self.height as f32
    }

    /// Camera-space direction (not normalised, z = -1) through film position `film`.
    #[inline]
    pub fn camera_dir(&self, film: Vec2) -> Vec3 {
        let ndc_x = 2.0 * film.x / self.width as f32 - 1.0;
        let ndc_y = 1.0 - 2.0 * film.y / self.height as f32;
        Vec3::new(
            (ndc_x + self.shift.x) * self.tan_half_x(),
            (ndc_y + self.shift.y) * self.tan_half_y,
            -1.0,
        )
    }

    /// World-space derivatives of the unnormalised direction `camera_dir(film)` with respect to
    /// film x and film y (constant over the film).
    #[inline]
    pub fn film_dir_derivatives(&self) -> (Vec3, Vec3) {
        (
            self.frame.basis.x_axis * (2.0 * self.tan_half_x() / self.width as f32),
            self.frame.basis.y_axis * (-2.0 * self.tan_half_y / self.height as f32),
        )
    }

    /// Camera-space point -> film position (inverse of [`Self::camera_dir`]), if in front.
    #[inline]
    pub fn film_of_camera_point(&self, q: Vec3) -> Option<Vec2> {
        if q.z >= 0.0 {
            return None;
        }
        let x = q.x / -q.z / self.tan_half_x() - self.shift.x;
        let y = q.y / -q.z / self.tan_half_y - self.shift.y;
        Some(Vec2::new(
            (x + 1.0) * 0.5 * self.width as f32,
            (1.0 - y) * 0.5 * self.height as f32,
        ))
    }
}

impl CameraModel for Pinhole {
    fn width(&self) -> u32 {
        self.width
    }
    fn height(&self) -> u32 {
        self.height
    }

    fn generate_ray(&self, film: Vec2, _lens: Vec2, _channel: usize) -> Option<CameraRay> {
        let d = self.camera_dir(film);
        let len = d.length();
        let dir = self.frame.dir_to_world(d / len);
        // d/dfilm of normalize(d) = (I - n n^T) / |d| * dd/dfilm, with dd/dx and dd/dy constant.
        let (dd_dx, dd_dy) = self.film_dir_derivatives();
        Some(CameraRay {
            ray: Ray::new(self.frame.position, dir),
            differential: RayDifferential {
                d_origin_dx: Vec3::ZERO,
                d_origin_dy: Vec3::ZERO,
                d_dir_dx: normalized_derivative(dir, len, dd_dx),
                d_dir_dy: normalized_derivative(dir, len, dd_dy),
            },
            depth_axis: self.frame.forward(),
        })
    }

    #[inline]
    fn project(&self, p: Vec3, _channel: usize) -> Option<Vec2> {
        self.film_of_camera_point(self.frame.to_camera(p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_ray_round_trip_and_centre() {
        let desc = CameraDesc::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 1.5, -2.0),
            Vec3::Y,
            50.0,
        );
        let cam = Pinhole::new(&desc, 64, 48).unwrap();
        for film in [
            Vec2::new(0.5, 0.5),
            Vec2::new(32.0, 24.0),
            Vec2::new(63.5, 10.25),
        ] {
            let r = cam.generate_ray(film, Vec2::ZERO, 0).unwrap();
            let p = r.ray.at(7.0);
            let back = cam.project(p, 0).unwrap();
            assert!((back - film).length() < 1e-3, "{film} -> {back}");
        }
        let c = cam
            .generate_ray(Vec2::new(32.0, 24.0), Vec2::ZERO, 0)
            .unwrap();
        assert!((c.ray.dir - (desc.target - desc.eye).normalize()).length() < 1e-5);
    }
}
