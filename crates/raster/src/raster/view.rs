//! What the rasterizer needs to know about a camera: a world -> clip map, a viewport and how
//! view depth is measured.
//!
//! The clip vector of a world point is `(x, y, d, w)`: `x / w` and `y / w` are normalised
//! device coordinates in `[-1, 1]` over the viewport (y up), and `d` is the **view depth**
//! itself (positive distance along the view axis), not OpenGL's `z`. Keeping `d` linear lets the
//! near/far planes be clipped as `d >= near`, `d <= far` in homogeneous space (Blinn & Newell
//! 1978) and lets the G-buffer report view depth exactly as a ray caster does.
//!
//! | projection | `w` | built from |
//! |---|---|---|
//! | perspective | `-z_camera` | [`Pinhole`] (incl. off-axis `shift`, stereo eyes, cube faces) |
//! | orthographic | `1` | [`Orthographic`] |
//!
//! Screen (film) position of clip `(x, y, w)`: `sx = (x / w + 1) W / 2`, `sy = (1 - y / w) H / 2`,
//! the inverse of the camera models' `camera_dir` / ray origin maps, so the rasterizer's pixel
//! centres coincide with the camera's pixel-centre rays (tested in `tests/raster.rs`).

use glam::{DMat4, DVec4, Mat4, Vec3};
use parallax_scene::camera::{Camera, CubeMap, Eye, Orthographic, Pinhole};

use crate::error::RasterError;

/// The projection kind, with what resolving a fragment needs (the direction of the viewing ray).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Rays leave `eye`.
    Perspective { eye: Vec3 },
    /// Rays run parallel to `forward`.
    Orthographic { forward: Vec3 },
}

/// A view the rasterizer can capture.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    pub width: u32,
    pub height: u32,
    /// World -> clip `(x, y, d, w)` (see the module docs), kept in f64 for setup precision.
    pub world_to_clip: DMat4,
    pub projection: Projection,
    /// Fragments nearer than this view depth are clipped (metres, > 0 for perspective).
    pub near: f32,
    /// Fragments farther than this view depth are clipped (`+inf` = no far plane).
    pub far: f32,
}

/// Default near plane (metres): small enough that no test scene places a surface nearer.
pub const DEFAULT_NEAR: f32 = 1e-4;

fn check_size(width: u32, height: u32) -> Result<(), RasterError> {
    parallax_core::image::check_size(width, height).map_err(RasterError::Size)
}

fn check_frame(m: &DMat4) -> Result<(), RasterError> {
    if m.is_finite() {
        Ok(())
    } else {
        Err(RasterError::InvalidView(
            "non-finite camera frame or field of view".into(),
        ))
    }
}

/// `world -> camera` (camera looks down -z) as a 4x4 matrix in f64.
fn world_to_camera(basis: glam::Mat3, position: Vec3) -> DMat4 {
    let b = glam::DMat3::from_cols(
        basis.x_axis.as_dvec3(),
        basis.y_axis.as_dvec3(),
        basis.z_axis.as_dvec3(),
    );
    let rt = b.transpose();
    let t = -(rt * position.as_dvec3());
    DMat4::from_cols(
        rt.x_axis.extend(0.0),
        rt.y_axis.extend(0.0),
        rt.z_axis.extend(0.0),
        t.extend(1.0),
    )
}

impl View {
    /// The perspective view of a pinhole camera (any field of view, aspect and off-axis shift;
    /// also a stereo eye or a cube face — mirrored frames are fine: nothing is culled by
    /// winding).
    ///
    /// Camera space `q`: `x = q.x / tan_half_x + shift.x * q.z`, `y = q.y / tan_half_y +
    /// shift.y * q.z`, `d = w = -q.z`, so `x / w = q.x / (-q.z tan_half_x) - shift.x`, the
    /// inverse of [`Pinhole::camera_dir`].
    pub fn from_pinhole(cam: &Pinhole) -> Result<Self, RasterError> {
        check_size(cam.width, cam.height)?;
        let thy = cam.tan_half_y as f64;
        let thx = thy * cam.width as f64 / cam.height as f64;
        if !(thy.is_finite() && thy > 0.0) {
            return Err(RasterError::InvalidView(format!(
                "tan(fov_y / 2) must be finite and > 0, got {thy}"
            )));
        }
        let (sx, sy) = (cam.shift.x as f64, cam.shift.y as f64);
        // Rows act on camera space (q.x, q.y, q.z, 1).
        let proj = DMat4::from_cols(
            DVec4::new(1.0 / thx, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / thy, 0.0, 0.0),
            DVec4::new(sx, sy, -1.0, -1.0),
            DVec4::new(0.0, 0.0, 0.0, 0.0),
        );
        let m = proj * world_to_camera(cam.frame.basis, cam.frame.position);
        check_frame(&m)?;
        Ok(Self {
            width: cam.width,
            height: cam.height,
            world_to_clip: m,
            projection: Projection::Perspective {
                eye: cam.frame.position,
            },
            near: DEFAULT_NEAR,
            far: f32::INFINITY,
        })
    }

    /// The orthographic view: `x = q.x / half_width`, `y = q.y / half_height`, `d = -q.z`,
    /// `w = 1`; the near plane is the eye plane (the camera's rays start there).
    pub fn from_orthographic(cam: &Orthographic) -> Result<Self, RasterError> {
        check_size(cam.width, cam.height)?;
        let hh = cam.half_height as f64;
        let hw = hh * cam.width as f64 / cam.height as f64;
        if !(hh.is_finite() && hh > 0.0) {
            return Err(RasterError::InvalidView(format!(
                "orthographic half height must be finite and > 0, got {hh}"
            )));
        }
        let proj = DMat4::from_cols(
            DVec4::new(1.0 / hw, 0.0, 0.0, 0.0),
            DVec4::new(0.0, 1.0 / hh, 0.0, 0.0),
            DVec4::new(0.0, 0.0, -1.0, 0.0),
            DVec4::new(0.0, 0.0, 0.0, 1.0),
        );
        let m = proj * world_to_camera(cam.frame.basis, cam.frame.position);
        check_frame(&m)?;
        Ok(Self {
            width: cam.width,
            height: cam.height,
            world_to_clip: m,
            projection: Projection::Orthographic {
                forward: cam.frame.forward(),
            },
            near: 0.0,
            far: f32::INFINITY,
        })
    }

    /// Face `i` (0..6, order +X, -X, +Y, -Y, +Z, -Z) of a cube map.
    pub fn cube_face(cube: &CubeMap, i: usize) -> Result<Self, RasterError> {
        if i >= 6 {
            return Err(RasterError::InvalidView(format!(
                "cube face {i} is not in 0..6"
            )));
        }
        Self::from_pinhole(&cube.face_camera(i))
    }

    /// The views a camera model is made of: one for pinhole and orthographic, two for a stereo
    /// rig (left, right), six for a cube map. Models without a single centre of projection
    /// per view (thin lens, fisheye, equirect, distorted) are an error.
    pub fn views_of(camera: &Camera) -> Result<Vec<View>, RasterError> {
        match camera {
            Camera::Pinhole(c) => Ok(vec![Self::from_pinhole(c)?]),
            Camera::Orthographic(c) => Ok(vec![Self::from_orthographic(c)?]),
            Camera::Stereo(r) => Ok(vec![
                Self::from_pinhole(r.eye(Eye::Left))?,
                Self::from_pinhole(r.eye(Eye::Right))?,
            ]),
            Camera::Cube(c) => (0..6).map(|i| Self::cube_face(c, i)).collect(),
            other => Err(RasterError::InvalidView(format!(
                "camera model {} cannot be rasterized (no planar projection)",
                other.kind().name()
            ))),
        }
    }

    /// The same view with other near/far planes (view depths; `far` may be `+inf`).
    pub fn with_depth_range(mut self, near: f32, far: f32) -> Result<Self, RasterError> {
        if !(near.is_finite() && near >= 0.0 && far > near) {
            return Err(RasterError::InvalidView(format!(
                "depth range must satisfy 0 <= near < far, near finite; got {near}..{far}"
            )));
        }
        if matches!(self.projection, Projection::Perspective { .. }) && near <= 0.0 {
            return Err(RasterError::InvalidView(
                "a perspective near plane must be > 0".into(),
            ));
        }
        self.near = near;
        self.far = far;
        Ok(self)
    }

    /// Clip coordinates `(x, y, d, w)` of a world point.
    #[inline]
    pub fn clip(&self, p: Vec3) -> DVec4 {
        self.world_to_clip * p.as_dvec3().extend(1.0)
    }

    /// Film position (continuous pixels, y down) of a clip vector; meaningless for `w <= 0`.
    #[inline]
    pub fn screen_of_clip(&self, c: DVec4) -> glam::DVec2 {
        glam::DVec2::new(
            (c.x / c.w + 1.0) * 0.5 * self.width as f64,
            (1.0 - c.y / c.w) * 0.5 * self.height as f64,
        )
    }

    /// Film position of a world point, if it is in front of the view (`d > 0`).
    pub fn project(&self, p: Vec3) -> Option<glam::Vec2> {
        let c = self.clip(p);
        (c.z > 0.0 && c.w > 0.0).then(|| self.screen_of_clip(c).as_vec2())
    }

    /// View depth of a world point (positive in front).
    #[inline]
    pub fn view_depth(&self, p: Vec3) -> f64 {
        self.clip(p).z
    }

    /// Direction of the viewing ray that reaches world point `p` (not normalised).
    #[inline]
    pub fn ray_dir_to(&self, p: Vec3) -> Vec3 {
        match self.projection {
            Projection::Perspective { eye } => p - eye,
            Projection::Orthographic { forward } => forward,
        }
    }

    /// True for a perspective view.
    pub fn is_perspective(&self) -> bool {
        matches!(self.projection, Projection::Perspective { .. })
    }

    /// `world_to_clip` in f32 (for consumers that want the matrix, e.g. GPU backends).
    pub fn world_to_clip_f32(&self) -> Mat4 {
        self.world_to_clip.as_mat4()
    }
}
