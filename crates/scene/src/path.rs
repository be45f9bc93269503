//! Keyframed camera paths.

use glam::Vec3;

use crate::CameraDesc;

/// A camera pose at a time (seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    pub time: f32,
    pub camera: CameraDesc,
}

/// A camera path through keyframes, interpolated with centripetal-free uniform Catmull-Rom
/// splines for eye and target (C1, passes through every key) and linearly for up and FoV.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// Keys sorted by time; at least one.
    pub keys: Vec<CameraKey>,
    /// Frames per second the path is sampled at.
    pub fps: f32,
    /// Number of frames of the default sequence.
    pub frames: u32,
}

fn catmull_rom(p0: Vec3, p1: Vec3, p2: Vec3, p3: Vec3, t: f32) -> Vec3 {
    let t2 = t * t;
    let t3 = t2 * t;
    0.5 * ((2.0 * p1)
        + (-p0 + p2) * t
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3)
}

impl CameraPath {
    /// A path over `keys` (sorted here) sampled at `fps` for `frames` frames.
    pub fn new(mut keys: Vec<CameraKey>, fps: f32, frames: u32) -> Self {
        assert!(!keys.is_empty(), "a camera path needs at least one key");
        keys.sort_by(|a, b| a.time.total_cmp(&b.time));
        Self { keys, fps, frames }
    }

    /// The pose at time `t` (clamped to the keys' range).
    pub fn at(&self, t: f32) -> CameraDesc {
        let k = &self.keys;
        if k.len() == 1 || t <= k[0].time {
            return k[0].camera;
        }
        if t >= k[k.len() - 1].time {
            return k[k.len() - 1].camera;
        }
        let i = k.partition_point(|key| key.time <= t) - 1;
        let (a, b) = (&k[i], &k[i + 1]);
        let s = ((t - a.time) / (b.time - a.time).max(1e-9)).clamp(0.0, 1.0);
        let prev = &k[i.saturating_sub(1)];
        let next = &k[(i + 2).min(k.len() - 1)];
        let c = |f: fn(&CameraDesc) -> Vec3| {
            catmull_rom(
                f(&prev.camera),
                f(&a.camera),
                f(&b.camera),
                f(&next.camera),
                s,
            )
        };
        CameraDesc {
            eye: c(|d| d.eye),
            target: c(|d| d.target),
            up: a.camera.up.lerp(b.camera.up, s).normalize_or(a.camera.up),
            fov_y_deg: a.camera.fov_y_deg + (b.camera.fov_y_deg - a.camera.fov_y_deg) * s,
        }
    }

    /// The pose of frame `i` of the default sequence.
    pub fn frame(&self, i: u32) -> CameraDesc {
        self.at(self.keys[0].time + i as f32 / self.fps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_passes_through_keys_and_clamps() {
        let cam = |x: f32| {
            CameraDesc::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x, 0.0, -1.0),
                Vec3::Y,
                60.0,
            )
        };
        let p = CameraPath::new(
            vec![
                CameraKey {
                    time: 0.0,
                    camera: cam(0.0),
                },
                CameraKey {
                    time: 1.0,
                    camera: cam(1.0),
                },
                CameraKey {
                    time: 2.0,
                    camera: cam(3.0),
                },
            ],
            30.0,
            60,
        );
        assert_eq!(p.at(1.0).eye, Vec3::X);
        assert_eq!(p.at(-5.0).eye, Vec3::ZERO);
        assert_eq!(p.at(5.0).eye.x, 3.0);
        let mid = p.at(0.5).eye.x;
        assert!(mid > 0.0 && mid < 1.0);
        assert_eq!(p.frame(30).eye, Vec3::X);
    }
}
