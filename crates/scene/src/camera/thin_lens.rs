//! The thin-lens camera: a pinhole with a circular aperture focused on a plane (pbrt-v4 §5.2.3,
//! "The Thin Lens Model and Depth of Field"; Potmesil & Chakravarty 1981).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_y_deg` | f32 | from the pose | vertical field of view (of the lens-centre pinhole) |
//! | `aperture_radius` | f32 (m) | 0.05 | lens radius; 0 = pinhole |
//! | `focus_distance` | f32 (m) | `|target - eye|` | view depth of the plane in focus |
//!
//! The lens sample `lens` in `[0,1)^2` is mapped to the unit disk by the concentric map of
//! Shirley & Chiu 1997 ("A Low Distortion Map Between Disk and Square"); `lens = (0.5, 0.5)` is
//! the lens centre. The ray starts at the lens point `eye + aperture * (right * u + up * v)` and
//! passes through the point the lens-centre pinhole ray meets the focus plane (view depth
//! `focus_distance`), so every lens sample of one film position converges there.
//!
//! Ray differentials are analytic for the given lens sample: the origin does not move with the
//! film position, the direction `n = normalize(p_focus - p_lens)` moves by
//! `(I - n n^T) * focus * dd / |p_focus - p_lens|` where `dd` is the pinhole's direction
//! derivative. At the lens centre this is exactly the pinhole's differential.
//! `project` projects through the lens centre (the pinhole of the same frame).

use glam::{Vec2, Vec3};
use parallax_core::{Ray, math::RayDifferential};

use super::{CameraModel, CameraRay, Pinhole, camera_error, normalized_derivative};
use crate::{CameraDesc, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct ThinLens {
    /// The pinhole at the lens centre (frame, film, field of view).
    pub pinhole: Pinhole,
    pub aperture_radius: f32,
    pub focus_distance: f32,
}

impl ThinLens {
    /// `focus_distance = None` focuses on the target.
    pub fn new(
        desc: &CameraDesc,
        width: u32,
        height: u32,
        aperture_radius: f32,
        focus_distance: Option<f32>,
    ) -> Result<Self> {
        let pinhole = Pinhole::new(desc, width, height)?;
        if !(aperture_radius.is_finite() && aperture_radius >= 0.0) {
            return Err(camera_error(format!(
                "aperture radius must be finite and >= 0, got {aperture_radius}"
            )));
        }
        let focus = focus_distance.unwrap_or_else(|| (desc.target - desc.eye).length());
        if !(focus.is_finite() && focus > 0.0) {
            return Err(camera_error(format!(
                "focus distance must be finite and > 0, got {focus}"
            )));
        }
        Ok(Self {
            pinhole,
            aperture_radius,
            focus_distance: focus,
        })
    }

    /// The camera-space lens point (z = 0) of lens sample `lens`.
    #[inline]
    pub fn lens_point(&self, lens: Vec2) -> Vec3 {
        let d = concentric_disk(lens) * self.aperture_radius;
        Vec3::new(d.x, d.y, 0.0)
    }

    /// The camera-space direction of the ray through `film` and lens sample `lens` before the
    /// camera frame turns it (the ray's direction is `frame.dir_to_world` of it, its origin
    /// `position + frame.dir_to_world(lens_point(lens))`, bit for bit). Pose-free.
    pub fn camera_vector(&self, film: Vec2, lens: Vec2) -> Vec3 {
        let (_, d, len) = self.lens_ray(film, lens);
        d / len
    }

    /// The camera-space lens point, the direction from it to the focus point and that
    /// direction's length: the one computation of [`Self::camera_vector`] and the rays.
    #[inline]
    fn lens_ray(&self, film: Vec2, lens: Vec2) -> (Vec3, Vec3, f32) {
        // The focus point lies at depth `focus` on the lens-centre ray (camera_dir has
        // z = -1), the lens point on the z = 0 plane.
        let p_lens = self.lens_point(lens);
        let d = self.pinhole.camera_dir(film) * self.focus_distance - p_lens;
        (p_lens, d, d.length())
    }

    /// The world point on the focus plane that film position `film` is focused on.
    #[inline]
    pub fn focus_point(&self, film: Vec2) -> Vec3 {
        let f = &self.pinhole.frame;
        f.position + f.dir_to_world(self.pinhole.camera_dir(film) * self.focus_distance)
    }
}

/// Shirley & Chiu 1997 concentric square-to-disk map of `u` in `[0,1]^2` (pbrt-v4
/// `SampleUniformDiskConcentric`): maps concentric squares to concentric circles, preserving
/// area fractions and adjacency with low distortion. `(0.5, 0.5)` -> the centre.
fn concentric_disk(u: Vec2) -> Vec2 {
    let o = u * 2.0 - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, std::f32::consts::FRAC_PI_4 * (o.y / o.x))
    } else {
        (
            o.y,
            std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (o.x / o.y),
        )
    };
    Vec2::new(theta.cos(), theta.sin()) * r
}

impl CameraModel for ThinLens {
    fn width(&self) -> u32 {
        self.pinhole.width
    }
    fn height(&self) -> u32 {
        self.pinhole.height
    }

    fn generate_ray(&self, film: Vec2, lens: Vec2, _channel: usize) -> Option<CameraRay> {
        let frame = &self.pinhole.frame;
        let (p_lens, d, len) = self.lens_ray(film, lens);
        let dir = frame.dir_to_world(d / len);
        let (dd_dx, dd_dy) = self.pinhole.film_dir_derivatives();
        let k = self.focus_distance;
        Some(CameraRay {
            ray: Ray::new(frame.position + frame.dir_to_world(p_lens), dir),
            differential: RayDifferential {
                d_origin_dx: Vec3::ZERO,
                d_origin_dy: Vec3::ZERO,
                d_dir_dx: normalized_derivative(dir, len, dd_dx * k),
                d_dir_dy: normalized_derivative(dir, len, dd_dy * k),
            },
            depth_axis: frame.forward(),
        })
    }

    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2> {
        self.pinhole.project(p, channel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn concentric_map_is_on_the_disk_and_hits_the_rim() {
        assert_eq!(concentric_disk(Vec2::splat(0.5)), Vec2::ZERO);
        for (u, r) in [
            (Vec2::new(1.0, 0.5), 1.0),
            (Vec2::new(0.0, 0.0), 1.0),
            (Vec2::new(0.75, 0.5), 0.5),
            (Vec2::new(0.5, 0.25), 0.5),
        ] {
            assert!((concentric_disk(u).length() - r).abs() < 1e-6, "{u}");
        }
        for i in 0..=16 {
            for j in 0..=16 {
                let d = concentric_disk(Vec2::new(i as f32, j as f32) / 16.0);
                assert!(d.length() <= 1.0 + 1e-6);
            }
        }
    }

    #[test]
    fn zero_aperture_is_the_pinhole() {
        let desc = CameraDesc::new(Vec3::new(0.3, 1.0, 2.0), Vec3::ZERO, Vec3::Y, 40.0);
        let tl = ThinLens::new(&desc, 32, 24, 0.0, None).unwrap();
        let film = Vec2::new(3.25, 17.5);
        let a = tl.generate_ray(film, Vec2::new(0.9, 0.1), 0).unwrap();
        let b = tl.pinhole.generate_ray(film, Vec2::ZERO, 0).unwrap();
        assert!((a.ray.dir - b.ray.dir).length() < 1e-6);
        assert_eq!(a.ray.origin, b.ray.origin);
        assert!((a.differential.d_dir_dx - b.differential.d_dir_dx).length() < 1e-6);
    }
}
