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
//!
//! The directions' sine and cosine come from [`sin_cos_0_pi`] (polynomials, absolute error
//! below 2.5e-7), not libm: written once over SIMD lanes ([`Fisheye::dir_lanes`]), so the VR
//! caster's packets of fisheye rays equal [`CameraModel::ray`] bit for bit. `T` (differentials
//! only) keeps libm's.

use glam::{Vec2, Vec3};
use parallax_core::Ray;
use parallax_core::math::{RayDifferential, sin_cos_0_pi};
use parallax_core::simd::Lanes;

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

/// `S` of the module docs at `theta` (in `[0, pi]`) and `cos theta`, lane by lane (one value:
/// `f32`): the sine and cosine by [`sin_cos_0_pi`] (not libm), so that the camera's SIMD twin
/// ([`Fisheye::dir_lanes`]) gives its rays bit for bit; the Taylor series below `theta = 0.1`.
#[inline(always)]
fn sinc_cos<L: Lanes>(theta: L) -> (L, L) {
    let c = |v: f32| L::splat(v);
    let t2 = theta * theta;
    // sin(t)/t = 1 - t^2/6 + t^4/120 - t^6/5040
    let series = c(1.0) + t2 * (c(-1.0 / 6.0) + t2 * (c(1.0 / 120.0) - t2 / c(5040.0)));
    let (sin, cos) = sin_cos_0_pi(theta);
    (L::select(theta.lt(c(0.1)), series, sin / theta), cos)
}

/// `T` of the module docs at `theta` (the differentials only; libm's sine and cosine).
#[inline]
fn sinc_derivative(theta: f32) -> f32 {
    let t2 = theta * theta;
    if theta < 0.1 {
        // (t cos t - sin t)/t^3 = -1/3 + t^2/30 - t^4/840 + t^6/45360
        -1.0 / 3.0 + t2 * (1.0 / 30.0 + t2 * (-1.0 / 840.0 + t2 / 45360.0))
    } else {
        let (sin, cos) = theta.sin_cos();
        (theta * cos - sin) / (t2 * theta)
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
    /// The camera-space directions of film positions `(fx, fy)` lane by lane (one value:
    /// `f32`), with the angles `(u, v)` and `S` of the module docs, and the lanes inside the
    /// image ellipse (`|n| <= 1`; NaN positions are outside). Every lane does the f32
    /// operations of one, so a packet's rays equal [`CameraModel::ray`]'s bit for bit.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    pub fn dir_lanes<L: Lanes>(&self, fx: L, fy: L) -> ([L; 3], (L, L), L, L::M) {
        let c = |v: f32| L::splat(v);
        let nx = c(2.0) * fx / c(self.width as f32) - c(1.0);
        let ny = c(1.0) - c(2.0) * fy / c(self.height as f32);
        let inside = (nx * nx + ny * ny).le(c(1.0));
        let u = nx * c(self.fov.x) * c(0.5);
        let v = ny * c(self.fov.y) * c(0.5);
        let theta = (u * u + v * v).sqrt();
        let (s, cos) = sinc_cos(theta);
        ([u * s, v * s, c(-1.0) * cos], (u, v), s, inside)
    }

    /// The ray's part of [`CameraModel::generate_ray`] (shared with [`CameraModel::ray`], so
    /// both give the same bits): the angles `(u, v)`, `S` and the camera-space direction;
    /// `None` outside the image circle.
    #[inline(always)]
    fn camera_dir(&self, film: Vec2) -> Option<((f32, f32), f32, Vec3)> {
        let ([x, y, z], uv, s, inside) = self.dir_lanes(film.x, film.y);
        inside.then_some((uv, s, Vec3::new(x, y, z)))
    }

    /// The camera-space direction of the ray through `film` before the camera frame turns it
    /// (the ray's direction is `frame.dir_to_world` of it, bit for bit); `None` outside the
    /// image circle. Pose-free: a moved head turns these vectors, it does not change them.
    pub fn camera_vector(&self, film: Vec2) -> Option<Vec3> {
        self.camera_dir(film).map(|(.., d)| d)
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
        let ((u, v), s, d) = self.camera_dir(film)?;
        let t = sinc_derivative((u * u + v * v).sqrt());
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
        let (s0, _) = sinc_cos(0.0999999f32);
        let (s1, _) = sinc_cos(0.1000001f32);
        let (t0, t1) = (sinc_derivative(0.0999999), sinc_derivative(0.1000001));
        assert!(
            (s0 - s1).abs() < 1e-5 && (t0 - t1).abs() < 1e-4,
            "{s0} {s1} {t0} {t1}"
        );
        assert_eq!(sinc_cos(0.0f32).0, 1.0);
        assert_eq!(sinc_derivative(0.0), -1.0 / 3.0);
    }

    /// The polynomial sine and cosine keep the directions unit length and on the stated
    /// angle (within f32 noise) over the whole film.
    #[test]
    fn directions_are_unit_and_at_their_angle() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let cam = Fisheye::new(&desc, 64, 64, Some(Vec2::new(360.0, 360.0))).unwrap();
        for j in 0..=64 {
            for i in 0..=64 {
                let Some(((u, v), _, d)) = cam.camera_dir(Vec2::new(i as f32, j as f32)) else {
                    continue;
                };
                let theta = (u as f64).hypot(v as f64);
                assert!((d.length() - 1.0).abs() < 1e-6, "{d}");
                let angle = (d.as_dvec3().angle_between(glam::DVec3::NEG_Z) - theta).abs();
                assert!(angle < 2e-6, "{i} {j}: {angle}");
            }
        }
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
