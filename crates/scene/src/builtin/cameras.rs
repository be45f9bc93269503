//! The cameras of the built-in scenes: named look-at cameras and their default camera paths.

use glam::Vec3;

use crate::{CameraDesc, CameraKey, CameraPath, NamedCamera};

/// Frames of every built-in default camera path.
pub(crate) const PATH_FRAMES: u32 = 60;
/// Frame rate of every built-in default camera path.
pub(crate) const PATH_FPS: f32 = 30.0;

/// A named look-at camera with +Y up.
pub(crate) fn named(name: &str, eye: Vec3, target: Vec3, fov_y_deg: f32) -> NamedCamera {
    NamedCamera {
        name: name.to_string(),
        desc: CameraDesc::new(eye, target, Vec3::Y, fov_y_deg),
    }
}

/// A 60-frame, 30 fps path through `(time, eye, target)` keys with +Y up and a fixed FoV.
pub(crate) fn path(keys: &[(f32, Vec3, Vec3)], fov_y_deg: f32) -> CameraPath {
    let keys = keys
        .iter()
        .map(|&(time, eye, target)| CameraKey {
            time,
            camera: CameraDesc::new(eye, target, Vec3::Y, fov_y_deg),
        })
        .collect();
    CameraPath::new(keys, PATH_FPS, PATH_FRAMES)
}
