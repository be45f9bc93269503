//! A parallel stereo rig: two pinhole eyes `ipd` apart along the pose's right axis, both looking
//! along the pose's forward with the same up and field of view (parallel optical axes, no
//! toe-in, no off-axis window), the eyes symmetric about the pose's eye.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `fov_y_deg` | f32 | from the pose | vertical field of view of each eye |
//! | `ipd` | f32 (m) | 0.065 | interpupillary distance: eye separation along `right` |
//! | `width` | u32 | - | film width of ONE eye; the rig's film is `2 * width x height` |
//!
//! Film layout: film x in `[0, width)` is the left eye, `[width, 2 * width]` the right eye (its
//! own film x minus `width`). `generate_ray` ignores `channel`; `project(p, channel)` uses the
//! eye named by `channel` (0 = left, 1 = right, anything else = `None`) and returns `None` when
//! the point falls outside that eye's half of the film (the halves must not bleed into each
//! other). Differentials are each eye's analytic pinhole differentials.

use glam::{Vec2, Vec3};

use super::{CameraFrame, CameraModel, CameraRay, Pinhole, camera_error, check_film};
use crate::{CameraDesc, Result};

/// One eye of the rig.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Eye {
    Left,
    Right,
}

impl Eye {
    /// The eye of a `project` channel: 0 = left, 1 = right.
    pub fn from_channel(channel: usize) -> Option<Eye> {
        match channel {
            0 => Some(Eye::Left),
            1 => Some(Eye::Right),
            _ => None,
        }
    }

    /// -1 for the left eye, +1 for the right (the offset along `right` in units of `ipd / 2`).
    pub fn sign(self) -> f32 {
        match self {
            Eye::Left => -1.0,
            Eye::Right => 1.0,
        }
    }

    fn index(self) -> usize {
        match self {
            Eye::Left => 0,
            Eye::Right => 1,
        }
    }
}

/// The pose of one eye: `desc` moved by `sign * ipd / 2` along its right axis (eye and target
/// move together, so the two eyes' axes stay parallel).
pub fn eye_camera(desc: &CameraDesc, ipd: f32, eye: Eye) -> Result<CameraDesc> {
    if !(ipd.is_finite() && ipd >= 0.0) {
        return Err(camera_error(format!(
            "ipd (eye separation) must be finite and >= 0, got {ipd}"
        )));
    }
    let frame = CameraFrame::look_at(desc)?;
    let offset = frame.right() * (eye.sign() * 0.5 * ipd);
    Ok(CameraDesc {
        eye: desc.eye + offset,
        target: desc.target + offset,
        ..*desc
    })
}

#[derive(Clone, Debug, PartialEq)]
pub struct StereoRig {
    /// Left, right.
    pub eyes: [Pinhole; 2],
    pub ipd: f32,
}

impl StereoRig {
    /// `width x height` is the film of one eye.
    pub fn new(desc: &CameraDesc, width: u32, height: u32, ipd: f32) -> Result<Self> {
        check_film(2 * width as u64, height as u64)?;
        let left = Pinhole::new(&eye_camera(desc, ipd, Eye::Left)?, width, height)?;
        let right = Pinhole::new(&eye_camera(desc, ipd, Eye::Right)?, width, height)?;
        Ok(Self {
            eyes: [left, right],
            ipd,
        })
    }

    /// The pinhole of one eye (film `width x height` of its own).
    pub fn eye(&self, eye: Eye) -> &Pinhole {
        &self.eyes[eye.index()]
    }

    /// Film width of one eye.
    #[inline]
    pub fn eye_width(&self) -> u32 {
        self.eyes[0].width
    }
}

impl CameraModel for StereoRig {
    fn width(&self) -> u32 {
        2 * self.eye_width()
    }
    fn height(&self) -> u32 {
        self.eyes[0].height
    }

    fn generate_ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<CameraRay> {
        let w = self.eye_width() as f32;
        if !(film.x >= 0.0 && film.x <= 2.0 * w) {
            return None;
        }
        if film.x < w {
            self.eyes[0].generate_ray(film, lens, channel)
        } else {
            self.eyes[1].generate_ray(Vec2::new(film.x - w, film.y), lens, channel)
        }
    }

    fn project(&self, p: Vec3, channel: usize) -> Option<Vec2> {
        let eye = Eye::from_channel(channel)?;
        let f = self.eye(eye).project(p, 0)?;
        let w = self.eye_width() as f32;
        if !(f.x >= 0.0 && f.x <= w) {
            return None;
        }
        Some(Vec2::new(f.x + w * eye.index() as f32, f.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_map_to_their_eyes() {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let rig = StereoRig::new(&desc, 16, 12, 0.1).unwrap();
        assert_eq!((rig.width(), rig.height()), (32, 12));
        let l = rig
            .generate_ray(Vec2::new(8.0, 6.0), Vec2::ZERO, 0)
            .unwrap();
        let r = rig
            .generate_ray(Vec2::new(24.0, 6.0), Vec2::ZERO, 0)
            .unwrap();
        assert!((l.ray.origin - Vec3::new(-0.05, 0.0, 0.0)).length() < 1e-6);
        assert!((r.ray.origin - Vec3::new(0.05, 0.0, 0.0)).length() < 1e-6);
        assert!((l.ray.dir - Vec3::NEG_Z).length() < 1e-6);
        assert!((r.ray.dir - Vec3::NEG_Z).length() < 1e-6);
        // A far point straight ahead lands just right of the left eye's centre.
        let p = Vec3::new(0.0, 0.0, -100.0);
        assert!(rig.project(p, 0).unwrap().x > 8.0);
        assert!(rig.project(p, 1).unwrap().x < 24.0);
        assert!(rig.project(p, 2).is_none());
        // Outside the left eye's frustum: not projected into the right half.
        assert!(rig.project(Vec3::new(50.0, 0.0, -1.0), 0).is_none());
    }
}
