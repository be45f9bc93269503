//! The equirectangular (longitude/latitude) camera (pbrt-v4 §5.4's `SphericalCamera` with the
//! equirectangular mapping), optionally restricted to a window of longitudes and latitudes.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_deg` | Vec2 | (360, 180) | longitude range (0, 360] and latitude range (0, 180] in degrees |
//!
//! The window is centred on the pose's forward direction, latitude measured towards the pose's
//! up: film `(x, y)` -> `lon = (x / w - 1/2) * fov.x` (positive to the right) and
//! `lat = (1/2 - y / h) * fov.y` (positive up), camera-space direction
//! `(cos lat sin lon, sin lat, -cos lat cos lon)`. The ray starts at the eye; the depth axis is
//! the ray direction (view depth = radial distance). Differentials are analytic:
//! `d dir / d lon = (cos lat cos lon, 0, cos lat sin lon)`,
//! `d dir / d lat = (-sin lat sin lon, cos lat, sin lat cos lon)`, scaled by
//! `d lon / dx = fov.x / w` and `d lat / dy = -fov.y / h`.
//! `generate_ray` returns `None` off the film, `project` returns `None` outside the window; at a full 360-degree window the seam behind the
//! camera maps to `x = w` (lon = +180) or `x = 0`, and the poles (longitude undefined) to the
//! film centre column.

use glam::{Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraFrame, CameraModel, CameraRay, angular_fov};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Equirect {
    pub frame: CameraFrame,
    pub width: u32,
    pub height: u32,
    /// Longitude and latitude ranges in radians.
    pub fov: Vec2,
}

impl Equirect {
    /// `fov_deg = None` = the full sphere (360 x 180).
    pub fn new(desc: &CameraDesc, width: u32, height: u32, fov_deg: Option<Vec2>) -> Result<Self> {
        let frame = CameraFrame::look_at(desc)?;
        let fov = angular_fov(
            "equirect",
            fov_deg,
            Vec2::new(360.0, 180.0),
            Vec2::new(360.0, 180.0),
        )?;
        Ok(Self {
            frame,
            width,
            height,
            fov,
        })
    }

    /// (longitude, latitude) of film position `film`.
    #[inline]
    pub fn angles(&self, film: Vec2) -> Vec2 {
        Vec2::new(
            (film.x / self.width as f32 - 0.5) * self.fov.x,
            (0.5 - film.y / self.height as f32) * self.fov.y,
        )
    }
}

impl CameraModel for Equirect {
    fn width(&self) -> u32 {
        self.width
    }
    fn height(&self) -> u32 {
        self.height
    }

    fn generate_ray(&self, film: Vec2, _lens: Vec2, _channel: usize) -> Option<CameraRay> {
        let (w, h) = (self.width as f32, self.height as f32);
        if !(film.x >= 0.0 && film.x <= w && film.y >= 0.0 && film.y <= h) {
            return None;
        }
        let a = self.angles(film);
        let (sin_lon, cos_lon) = a.x.sin_cos();
        let (sin_lat, cos_lat) = a.y.sin_cos();
        let d = Vec3::new(cos_lat * sin_lon, sin_lat, -cos_lat * cos_lon);
        let d_lon = Vec3::new(cos_lat * cos_lon, 0.0, cos_lat * sin_lon);
        let d_lat = Vec3::new(-sin_lat * sin_lon, cos_lat, sin_lat * cos_lon);
        let dir = self.frame.dir_to_world(d);
        Some(CameraRay {
            ray: Ray::new(self.frame.position, dir),
            differential: RayDifferential {
                d_origin_dx: Vec3::ZERO,
                d_origin_dy: Vec3::ZERO,
                d_dir_dx: self.frame.dir_to_world(d_lon * (self.fov.x / w)),
                d_dir_dy: self.frame.dir_to_world(d_lat * (-self.fov.y / h)),
            },
            depth_axis: dir,
        })
    }

    fn project(&self, p: Vec3, _channel: usize) -> Option<Vec2> {
        let q = self.frame.to_camera(p);
        if !(q.is_finite() && q != Vec3::ZERO) {
            return None;
        }
        // atan2 forms stay accurate near the poles and the seam (asin/acos would not).
        let lon = if q.x == 0.0 && q.z == 0.0 {
            0.0 // a pole: any longitude; atan2(0, -0) would say 180
        } else {
            q.x.atan2(-q.z)
        };
        let lat = q.y.atan2(q.x.hypot(q.z));
        // Accept directions a rounding error outside the window (its edge rays).
        const EPS: f32 = 1e-5;
        if lon.abs() > 0.5 * self.fov.x + EPS || lat.abs() > 0.5 * self.fov.y + EPS {
            return None;
        }
        let (w, h) = (self.width as f32, self.height as f32);
        Some(Vec2::new(
            ((lon / self.fov.x + 0.5) * w).clamp(0.0, w),
            ((0.5 - lat / self.fov.y) * h).clamp(0.0, h),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_sphere_axes() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let cam = Equirect::new(&desc, 40, 20, None).unwrap();
        let dir = |x: f32, y: f32| cam.generate_ray(Vec2::new(x, y), Vec2::ZERO, 0).unwrap();
        assert!((dir(20.0, 10.0).ray.dir - Vec3::NEG_Z).length() < 1e-6);
        assert!((dir(30.0, 10.0).ray.dir - Vec3::X).length() < 1e-6);
        assert!((dir(10.0, 10.0).ray.dir - Vec3::NEG_X).length() < 1e-6);
        assert!((dir(0.0, 10.0).ray.dir - Vec3::Z).length() < 1e-6);
        assert!((dir(7.0, 0.0).ray.dir - Vec3::Y).length() < 1e-6);
        assert!((dir(7.0, 20.0).ray.dir - Vec3::NEG_Y).length() < 1e-6);
        assert_eq!(cam.project(Vec3::Y, 0), Some(Vec2::new(20.0, 0.0)));
    }

    #[test]
    fn window_rejects_outside() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let cam = Equirect::new(&desc, 40, 20, Some(Vec2::new(90.0, 60.0))).unwrap();
        assert!(cam.project(Vec3::new(1.0, 0.0, -0.9), 0).is_none());
        assert!(cam.project(Vec3::new(0.0, 1.0, -1.0), 0).is_none());
        assert!(cam.project(Vec3::new(0.5, 0.5, -1.0), 0).is_some());
        assert!(Equirect::new(&desc, 4, 4, Some(Vec2::new(361.0, 90.0))).is_err());
        assert!(Equirect::new(&desc, 4, 4, Some(Vec2::new(90.0, 181.0))).is_err());
        assert!(Equirect::new(&desc, 4, 4, Some(Vec2::new(0.0, 90.0))).is_err());
    }
}
