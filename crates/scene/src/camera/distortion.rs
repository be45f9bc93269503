//! A head-mounted-display eye view rendered pre-distorted: radial distortion with per-colour
//! coefficients (chromatic aberration correction) wrapped around a pinhole, as HMD runtimes
//! warp the eye buffer so that the lens's pincushion distortion cancels (Brown 1966 /
//! Conrady 1919 radial model; the Oculus SDK's "distortion correction" and its per-channel
//! chromatic scales follow the same form).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_y_deg` | f32 | from the pose | vertical field of view of the undistorted centre |
//! | `distortion` | [[f32; 2]; 3] | R (0.22, 0.24), G (0.24, 0.26), B (0.26, 0.28) | per-channel `(k1, k2)` |
//!
//! Film position `p` is a display pixel. Its normalised lens coordinates are taken relative to
//! the image centre in units of the half-height: `n = ((x - w/2) / (h/2), (h/2 - y) / (h/2))`,
//! radius `r_d = |n|`. For channel `c` with coefficients `(k1, k2)` the undistorted
//! tangent-space point is `n_u = n (1 + k1 r_d^2 + k2 r_d^4)`, i.e.
//! `r_u = r_d (1 + k1 r_d^2 + k2 r_d^4)`, and the ray leaves the eye towards camera-space
//! `(n_u.x * tan(fov_y/2), n_u.y * tan(fov_y/2), -1)`. Positive coefficients push display pixels
//! outward in the scene (a barrel pre-distortion) that the lens's pincushion undoes. With all
//! coefficients zero this is exactly the pinhole; at the image centre the mapping has the
//! pinhole's derivative, so the pose's field of view is that of the undistorted centre.
//!
//! The coefficients must make `r_u(r_d)` strictly increasing over the film (up to the corner
//! radius `r_max = sqrt((w/h)^2 + 1)`), else the model is rejected: the map is then one-to-one
//! and invertible.
//!
//! `project` inverts `r_u(r_d)` by Newton's method in f64, safeguarded by bisection on the
//! bracket `[0, r_max]` (a Newton step leaving the bracket is replaced by the midpoint). The
//! start `r = min(r_u, r_max)` lies in the bracket; with non-negative coefficients `r_u` is
//! convex, and Newton from the right converges monotonically and quadratically: measured at
//! most 7 iterations to 1e-12 over a 16:9 film with the defaults (test
//! `newton_converges_in_a_few_iterations`, which allows 8). It returns `None` when the point is behind the eye plane, when `r_u`
//! exceeds `r_u(r_max)` (beyond the film's corner radius) or when 60 iterations do not converge
//! (not observed). `channel` 0, 1, 2 = R, G, B; any other channel gives `None`.
//!
//! Differentials are analytic: `d n_u / d n = g I + 2 g'(r_d^2) n n^T` with
//! `g(s) = 1 + k1 s + k2 s^2`, through the normalised-direction derivative of the pinhole.

use glam::{DVec2, Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraModel, CameraRay, Pinhole, camera_error, normalized_derivative};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Distorted {
    /// The undistorted view (frame, film size, field of view).
    pub pinhole: Pinhole,
    /// Per channel (R, G, B) `(k1, k2)`.
    pub coeffs: [[f32; 2]; 3],
    /// Corner radius of the film in normalised lens coordinates.
    pub r_max: f32,
}

impl Distorted {
    pub fn new(desc: &CameraDesc, width: u32, height: u32, coeffs: [[f32; 2]; 3]) -> Result<Self> {
        let pinhole = Pinhole::new(desc, width, height)?;
        let aspect = width as f32 / height as f32;
        let r_max = (aspect * aspect + 1.0).sqrt();
        let s_max = r_max * r_max;
        for (c, &[k1, k2]) in coeffs.iter().enumerate() {
            if !(k1.is_finite() && k2.is_finite()) {
                return Err(camera_error(format!(
                    "distortion coefficients of channel {c} must be finite, got ({k1}, {k2})"
                )));
            }
            // d r_u / d r_d = 1 + 3 k1 s + 5 k2 s^2 with s = r_d^2 in [0, s_max]: a quadratic
            // in s whose minimum is at an end or at the vertex -3 k1 / (10 k2).
            let slope = |s: f32| 1.0 + 3.0 * k1 * s + 5.0 * k2 * s * s;
            let mut min = slope(0.0).min(slope(s_max));
            if k2 > 0.0 {
                let v = -3.0 * k1 / (10.0 * k2);
                if v > 0.0 && v < s_max {
                    min = min.min(slope(v));
                }
            }
            if min.is_nan() || min <= 0.0 {
                return Err(camera_error(format!(
                    "distortion coefficients ({k1}, {k2}) of channel {c} fold the image: \
                     r_d (1 + k1 r_d^2 + k2 r_d^4) must increase up to the film corner \
                     r_d = {r_max:.3}"
                )));
            }
        }
        Ok(Self {
            pinhole,
            coeffs,
            r_max,
        })
    }

    /// Normalised lens coordinates of film position `film` (units of the half-height, y up).
    #[inline]
    pub fn lens_coords(&self, film: Vec2) -> Vec2 {
        let hh = 0.5 * self.pinhole.height as f32;
        Vec2::new(
            (film.x - 0.5 * self.pinhole.width as f32) / hh,
            (hh - film.y) / hh,
        )
    }

    /// `r_u / r_d` at `r_d^2 = s` for `channel`.
    #[inline]
    fn gain(&self, channel: usize, s: f32) -> f32 {
        let [k1, k2] = self.coeffs[channel];
        1.0 + s * (k1 + k2 * s)
    }

    /// Solves `r (1 + k1 r^2 + k2 r^4) = r_u` for `r` in `[0, r_max]` (see the module docs);
    /// also returns the number of iterations taken.
    fn undistort_radius(&self, channel: usize, r_u: f64) -> Option<(f64, u32)> {
        let [k1, k2] = self.coeffs[channel].map(f64::from);
        let f = |r: f64| r * (1.0 + r * r * (k1 + k2 * r * r));
        let df = |r: f64| 1.0 + r * r * (3.0 * k1 + 5.0 * k2 * r * r);
        // A hair of slack beyond the corner so the corner pixel's own radius (rounded in f32)
        // is inside; the slope is positive at r_max, so the map stays one-to-one there.
        let (mut lo, mut hi) = (0.0f64, self.r_max as f64 * (1.0 + 1e-5));
        let tol = 1e-12 * r_u.max(1.0);
        if f(hi) < r_u - tol {
            return None;
        }
        let mut r = r_u.min(hi);
        for i in 0..60 {
            let e = f(r) - r_u;
            if e.abs() <= tol {
                return Some((r, i));
            }
            if e > 0.0 {
                hi = r;
            } else {
                lo = r;
            }
            let next = r - e / df(r);
            r = if next > lo && next < hi {
                next
            } else {
                0.5 * (lo + hi)
            };
        }
        None
    }
}

impl Distorted {
    /// The camera-space direction through `film` for `channel` (0-2) before normalising,
    /// `(x, y, -1)`: the ray's direction is its normalised turn into the world, bit for bit
    /// (the same operations as [`CameraModel::ray`]).
    pub fn camera_vector(&self, film: Vec2, channel: usize) -> Option<Vec3> {
        (channel <= 2).then(|| self.lens_vector(film, channel).3)
    }

    /// The lens coordinates `n`, `s = |n|^2`, the gain `g(s)` and the camera-space direction
    /// before normalising (`channel` at most 2).
    #[inline(always)]
    fn lens_vector(&self, film: Vec2, channel: usize) -> (Vec2, f32, f32, Vec3) {
        let n = self.lens_coords(film);
        let s = n.length_squared();
        let g = self.gain(channel, s);
        let t = self.pinhole.tan_half_y;
        let nu = n * g;
        (n, s, g, Vec3::new(nu.x * t, nu.y * t, -1.0))
    }

    /// The ray's part of [`CameraModel::generate_ray`] (shared with [`CameraModel::ray`], so
    /// both give the same bits): the lens coordinates `n`, `s = |n|^2`, the gain `g(s)`, the
    /// length of the camera-space direction before normalising, and the world direction.
    #[inline(always)]
    fn lens_ray(&self, film: Vec2, channel: usize) -> Option<(Vec2, f32, f32, f32, Vec3)> {
        if channel > 2 {
            return None;
        }
        let (n, s, g, d) = self.lens_vector(film, channel);
        let len = d.length();
        let dir = self.pinhole.frame.dir_to_world(d / len);
        Some((n, s, g, len, dir))
    }
}

impl CameraModel for Distorted {
    fn ray(&self, film: Vec2, _lens: Vec2, channel: usize) -> Option<Ray> {
        let (.., dir) = self.lens_ray(film, channel)?;
        Some(Ray::new(self.pinhole.frame.position, dir))
    }
    fn width(&self) -> u32 {
        self.pinhole.width
    }
    fn height(&self) -> u32 {
        self.pinhole.height
    }

    fn generate_ray(&self, film: Vec2, _lens: Vec2, channel: usize) -> Option<CameraRay> {
        let (n, s, g, len, dir) = self.lens_ray(film, channel)?;
        let [k1, k2] = self.coeffs[channel];
        let dg = k1 + 2.0 * k2 * s; // g'(s)
        let t = self.pinhole.tan_half_y;
        let frame = &self.pinhole.frame;
        // d n / dx = (2/h, 0), d n / dy = (0, -2/h); d n_u = g dn + 2 g' (n . dn) n.
        let k = 2.0 / self.pinhole.height as f32;
        let dnu_dx = (Vec2::X * g + n * (2.0 * dg * n.x)) * k;
        let dnu_dy = (Vec2::Y * g + n * (2.0 * dg * n.y)) * -k;
        let to_world = |v: Vec2| frame.dir_to_world(Vec3::new(v.x * t, v.y * t, 0.0));
        Some(CameraRay {
            ray: Ray::new(frame.position, dir),
            differential: RayDifferential {
                d_origin_dx: Vec3::ZERO,
                d_origin_dy: Vec3::ZERO,
                d_dir_dx: normalized_derivative(dir, len, to_world(dnu_dx)),
                d_dir_dy: normalized_derivative(dir, len, to_world(dnu_dy)),
            },
            depth_axis: frame.forward(),
        })
    }

    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2> {
        if channel > 2 {
            return None;
        }
        let q = self.pinhole.frame.to_camera(p).as_dvec3();
        if q.z.is_nan() || q.z >= 0.0 {
            return None;
        }
        let nu = DVec2::new(q.x, q.y) / (-q.z * self.pinhole.tan_half_y as f64);
        let r_u = nu.length();
        let n = if r_u > 0.0 {
            nu * (self.undistort_radius(channel, r_u)?.0 / r_u)
        } else {
            DVec2::ZERO
        };
        let hh = 0.5 * self.pinhole.height as f64;
        Some(Vec2::new(
            (n.x * hh + 0.5 * self.pinhole.width as f64) as f32,
            (hh - n.y * hh) as f32,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn desc() -> CameraDesc {
        CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0)
    }

    #[test]
    fn zero_coefficients_are_the_pinhole() {
        let d = Distorted::new(&desc(), 30, 20, [[0.0; 2]; 3]).unwrap();
        for film in [
            Vec2::new(0.5, 0.5),
            Vec2::new(29.0, 7.25),
            Vec2::new(15.0, 10.0),
        ] {
            let a = d.generate_ray(film, Vec2::ZERO, 1).unwrap();
            let b = d.pinhole.generate_ray(film, Vec2::ZERO, 0).unwrap();
            assert!((a.ray.dir - b.ray.dir).length() < 1e-6);
            assert!((a.differential.d_dir_dy - b.differential.d_dir_dy).length() < 1e-6);
        }
    }

    #[test]
    fn corner_radius_maps_as_the_polynomial_says() {
        let d = Distorted::new(&desc(), 20, 20, [[0.1, 0.05], [0.2, 0.1], [0.3, 0.2]]).unwrap();
        // Film corner: n = (1, 1), r_d^2 = 2; tan(45 deg) = 1.
        for (c, g) in [
            (0, 1.0 + 0.2 + 0.2),
            (1, 1.0 + 0.4 + 0.4),
            (2, 1.0 + 0.6 + 0.8),
        ] {
            let r = d.generate_ray(Vec2::new(20.0, 0.0), Vec2::ZERO, c).unwrap();
            let t = r.ray.dir / -r.ray.dir.z;
            assert!((t.x - g).abs() < 1e-5 && (t.y - g).abs() < 1e-5, "{c}: {t}");
        }
        assert!(d.generate_ray(Vec2::ZERO, Vec2::ZERO, 3).is_none());
        // Beyond the corner radius: no inverse.
        assert!(d.project(Vec3::new(10.0, 0.0, -1.0), 0).is_none());
    }

    #[test]
    fn newton_converges_in_a_few_iterations() {
        let defaults = crate::camera::CameraOptions::default().distortion;
        for coeffs in [defaults, [[-0.05, 0.01]; 3], [[0.5, 0.5]; 3]] {
            let d = Distorted::new(&desc(), 32, 18, coeffs).unwrap();
            let mut worst = 0;
            for c in 0..3 {
                for i in 0..=200 {
                    let r_d = d.r_max as f64 * i as f64 / 200.0;
                    let [k1, k2] = coeffs[c].map(f64::from);
                    let r_u = r_d * (1.0 + k1 * r_d * r_d + k2 * r_d.powi(4));
                    let (r, n) = d.undistort_radius(c, r_u).unwrap();
                    assert!((r - r_d).abs() < 1e-9, "{coeffs:?} {c}: {r} vs {r_d}");
                    worst = worst.max(n);
                }
            }
            assert!(worst <= 8, "{coeffs:?}: {worst} iterations");
        }
    }

    #[test]
    fn rejects_folding_coefficients() {
        assert!(Distorted::new(&desc(), 20, 10, [[0.0, 0.0], [-0.5, 0.0], [0.0, 0.0]]).is_err());
        assert!(
            Distorted::new(&desc(), 20, 10, [[0.0, 0.0], [0.0, 0.0], [0.0, f32::NAN]]).is_err()
        );
        // Negative k1 balanced by k2 that stays monotone is fine.
        assert!(Distorted::new(&desc(), 20, 20, [[-0.05, 0.01]; 3]).is_ok());
    }
}
