//! The equidistant fisheye: the image radius grows in proportion to the angle from the forward
//! axis (`r = f * theta`, the "f-theta" lens; Kannala & Brandt 2006, eq. 3 "equidistance
//! projection"), stretched per axis so the film spans exactly the requested horizontal and
//! vertical field of view.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_deg` | Vec2 | (210, 130) | horizontal and vertical field of view in degrees, each in (0, 360] |
//!
//! Mapping (azimuthal equidistant in scaled angles): film `(x, y)` -> normalised
//! `n = (2x/w - 1, 1 - 2y/h)` -> angle vector `(u, v) = (n.x * fov.x / 2, n.y * fov.y / 2)`;
//! the ray makes the angle `theta = |(u, v)|` with forward, in the azimuth of `(u, v)` around it:
//! camera-space direction `(u sin(theta)/theta, v sin(theta)/theta, -cos theta)`. So the film's
//! horizontal centre line sweeps `fov.x` (the left and right edge rays are `fov.x / 2` from
//! forward on either side) and the vertical centre line sweeps `fov.y`. When the film aspect
//! equals `fov.x / fov.y` (e.g. 210 x 130 on a 420 x 260 film) pixels are equal angles in both
//! axes: the classic isotropic fisheye.
//!
//! Covered region: the ellipse inscribed in the film, `|n| <= 1`; film positions outside it
//! (the corners) give `None`, and `project` gives `None` for directions outside the cone of
//! directions it covers. The depth axis is the ray direction (radial distance).
//!
//! Differentials are analytic. With `S = sin(theta)/theta` and
//! `T = S'(theta)/theta = (theta cos theta - sin theta) / theta^3` (a Taylor series below
//! `theta = 0.1` where the formula cancels):
//! `d dir / du = (S + u^2 T, u v T, u S)`, `d dir / dv = (u v T, S + v^2 T, v S)`,
//! scaled by `du/dx = fov.x / w`, `dv/dy = -fov.y / h`.

use glam::{Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraFrame, CameraModel, CameraRay, angular_fov};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Fisheye {
    pub frame: CameraFrame,
    pub width: u32,
    pub height: u32,
    /// Horizontal and vertical field of view in radians.
    pub fov: Vec2,
}

/// `(S, T)` of the module docs at `theta`.
#[inline]
fn sinc_terms(theta: f32) -> (f32, f32) {
    let t2 = theta * theta;
    if theta < 0.1 {
        // sin(t)/t = 1 - t^2/6 + t^4/120 - t^6/5040
        // (t cos t - sin t)/t^3 = -1/3 + t^2/30 - t^4/840 + t^6/45360
        let s = 1.0 + t2 * (-1.0 / 6.0 + t2 * (1.0 / 120.0 - t2 / 5040.0));
        let t = -1.0 / 3.0 + t2 * (1.0 / 30.0 + t2 * (-1.0 / 840.0 + t2 / 45360.0));
        (s, t)
    } else {
        let (sin, cos) = theta.sin_cos();
        (sin / theta, (theta * cos - sin) / (t2 * theta))
    }
}

impl Fisheye {
    /// `fov_deg = None` = 210 x 130 degrees.
    pub fn new(desc: &CameraDesc, width: u32, height: u32, fov_deg: Option<Vec2>) -> Result<Self> {
        let frame = CameraFrame::look_at(desc)?;
        let fov = angular_fov(
            "fisheye",
            fov_deg,
            Vec2::new(210.0, 130.0),
            Vec2::new(360.0, 360.0),
        )?;
        Ok(Self {
            frame,
            width,
            height,
            fov,
        })
    }

    /// Normalised film position `n` (the covered ellipse is `|n| <= 1`).
    #[inline]
    pub fn normalized(&self, film: Vec2) -> Vec2 {
        Vec2::new(
            2.0 * film.x / self.width as f32 - 1.0,
            1.0 - 2.0 * film.y / self.height as f32,
        )
    }
}

impl Fisheye {
    /// The ray's part of [`CameraModel::generate_ray`] (shared with [`CameraModel::ray`], so
    /// both give the same bits): the angles `(u, v)`, the [`sinc_terms`] of their length and
    /// the camera-space direction; `None` outside the image circle.
    #[inline(always)]
    fn camera_dir(&self, film: Vec2) -> Option<((f32, f32), (f32, f32), Vec3)> {
        let n = self.normalized(film);
        if n.is_nan() || n.length_squared() > 1.0 {
            return None;
        }
        let uv = n * self.fov * 0.5;
        let theta = uv.length();
        let (s, t) = sinc_terms(theta);
        let (u, v) = (uv.x, uv.y);
        Some(((u, v), (s, t), Vec3::new(u * s, v * s, -theta.cos())))
    }
}

impl CameraModel for Fisheye {
    fn width(&self) -> u32 {
        self.width
    }
    fn height(&self) -> u32 {
        self.height
    }

    fn ray(&self, film: Vec2, _lens: Vec2, _channel: usize) -> Option<Ray> {
        let (.., d) = self.camera_dir(film)?;
        Some(Ray::new(self.frame.position, self.frame.dir_to_world(d)))
    }

    fn generate_ray(&self, film: Vec2, _lens: Vec2, _channel: usize) -> Option<CameraRay> {
        let ((u, v), (s, t), d) = self.camera_dir(film)?;
        let d_du = Vec3::new(s + u * u * t, u * v * t, u * s);
        let d_dv = Vec3::new(u * v * t, s + v * v * t, v * s);
        let dir = self.frame.dir_to_world(d);
        Some(CameraRay {
            ray: Ray::new(self.frame.position, dir),
            differential: RayDifferential {
                d_origin_dx: Vec3::ZERO,
                d_origin_dy: Vec3::ZERO,
                d_dir_dx: self
                    .frame
                    .dir_to_world(d_du * (self.fov.x / self.width as f32)),
                d_dir_dy: self
                    .frame
                    .dir_to_world(d_dv * (-self.fov.y / self.height as f32)),
            },
            depth_axis: dir,
        })
    }

    fn project(&self, p: Vec3, _channel: usize) -> Option<Vec2> {
        let q = self.frame.to_camera(p);
        if !(q.is_finite() && q != Vec3::ZERO) {
            return None;
        }
        let rho = q.x.hypot(q.y);
        let theta = rho.atan2(-q.z);
        let uv = if rho > 0.0 {
            Vec2::new(q.x, q.y) * (theta / rho)
        } else {
            Vec2::new(theta, 0.0) // on the axis (theta = 0 or pi): azimuth undefined
        };
        let n = uv / (self.fov * 0.5);
        // Accept directions a rounding error outside the ellipse (its rim rays).
        if n.length_squared() > 1.0 + 1e-5 {
            return None;
        }
        Some(Vec2::new(
            (n.x + 1.0) * 0.5 * self.width as f32,
            (1.0 - n.y) * 0.5 * self.height as f32,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_matches_the_formula_at_the_switch() {
        let (s0, t0) = sinc_terms(0.0999999);
        let (s1, t1) = sinc_terms(0.1000001);
        assert!(
            (s0 - s1).abs() < 1e-6 && (t0 - t1).abs() < 1e-4,
            "{t0} {t1}"
        );
        assert_eq!(sinc_terms(0.0), (1.0, -1.0 / 3.0));
    }

    #[test]
    fn edges_and_corners() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let cam = Fisheye::new(&desc, 42, 26, None).unwrap();
        let right = cam
            .generate_ray(Vec2::new(42.0, 13.0), Vec2::ZERO, 0)
            .unwrap();
        let top = cam
            .generate_ray(Vec2::new(21.0, 0.0), Vec2::ZERO, 0)
            .unwrap();
        assert!((right.ray.dir.angle_between(Vec3::NEG_Z).to_degrees() - 105.0).abs() < 1e-3);
        assert!((top.ray.dir.angle_between(Vec3::NEG_Z).to_degrees() - 65.0).abs() < 1e-3);
        assert!(right.ray.dir.x > 0.0 && top.ray.dir.y > 0.0);
        assert!(
            cam.generate_ray(Vec2::new(1.0, 1.0), Vec2::ZERO, 0)
                .is_none()
        );
        assert!(cam.project(Vec3::Z, 0).is_none());
    }
}
