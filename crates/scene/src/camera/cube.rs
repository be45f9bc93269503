//! A cube map around the eye: six 90-degree pinhole faces along the world axes, in the order
//! +X, -X, +Y, -Y, +Z, -Z, oriented as OpenGL cube-map faces (OpenGL 4.6 core spec §8.13,
//! table 8.19 "Selection of cube map images"), so each face's film can be uploaded unchanged as
//! `GL_TEXTURE_CUBE_MAP_POSITIVE_X + i` (film row 0 = texture t = 0).
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `eye` | Vec3 | from the pose | centre of the cube; the pose's target, up and fov are unused |
//! | `width` | u32 | - | face size: each face is `width x width`, the film `6 * width x width` |
//!
//! Film layout: face `i` covers film x in `[i * width, (i + 1) * width]`, faces side by side.
//! Face `i` maps direction `r` with major axis `ma` to `s = (sc / |ma| + 1) / 2`,
//! `t = (tc / |ma| + 1) / 2` (film `x = s * width`, `y = t * width`), with `(sc, tc)` from the
//! table: +X `(-rz, -ry)`, -X `(rz, -ry)`, +Y `(rx, rz)`, -Y `(rx, -rz)`, +Z `(rx, -ry)`,
//! -Z `(-rx, -ry)`. As a pinhole, face `i` looks along its axis with:
//!
//! | face | forward | right (film +x) | up (film -y) |
//! |---|---|---|---|
//! | 0 | +X | -Z | +Y |
//! | 1 | -X | +Z | +Y |
//! | 2 | +Y | +X | -Z |
//! | 3 | -Y | +X | +Z |
//! | 4 | +Z | +X | +Y |
//! | 5 | -Z | -X | +Y |
//!
//! **Mirrored frames:** like every OpenGL/RenderMan cube map these face frames are left-handed
//! (`right x up = forward`), so a rasterizer that culls by winding order must flip it for faces.
//!
//! The faces meet without gaps: each face is exactly 90 degrees, so a direction on the boundary
//! of two faces projects to the edge pixel of both ([`CubeMap::face_camera`]). `project` picks the
//! face of the dominant axis of `p - eye` (ties to the first face in the order above) and clamps
//! the result onto that face. The depth axis of a ray is its face axis; differentials are the
//! face pinhole's analytic ones.

use glam::{Mat3, Vec2, Vec3};

use super::{CameraFrame, CameraModel, CameraRay, Pinhole, check_film};
use crate::{CameraDesc, Result};

/// The face axes in face order.
pub const FACE_AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// (right, up) of each face, from the OpenGL table (see the module docs).
const FACE_RIGHT_UP: [(Vec3, Vec3); 6] = [
    (Vec3::NEG_Z, Vec3::Y),
    (Vec3::Z, Vec3::Y),
    (Vec3::X, Vec3::NEG_Z),
    (Vec3::X, Vec3::Z),
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
];

#[derive(Clone, Debug, PartialEq)]
pub struct CubeMap {
    /// Centre of the cube.
    pub eye: Vec3,
    /// Face size in pixels.
    pub face: u32,
}

impl CubeMap {
    /// A cube map of faces `face x face` around `desc.eye` (the pose is validated as a whole).
    pub fn new(desc: &CameraDesc, face: u32) -> Result<Self> {
        check_film(6 * face as u64, face as u64)?;
        CameraFrame::look_at(desc)?;
        Ok(Self {
            eye: desc.eye,
            face,
        })
    }

    /// Face size in pixels.
    #[inline]
    pub fn face_size(&self) -> u32 {
        self.face
    }

    /// The 90-degree pinhole of face `i` (0..6, order +X, -X, +Y, -Y, +Z, -Z) with its own
    /// `face x face` film, for rasterizing one face.
    ///
    /// # Panics
    /// If `i >= 6`.
    #[inline]
    pub fn face_camera(&self, i: usize) -> Pinhole {
        let (right, up) = FACE_RIGHT_UP[i];
        let frame = CameraFrame {
            position: self.eye,
            basis: Mat3::from_cols(right, up, -FACE_AXES[i]),
        };
        // tan(90 deg / 2) = 1.
        Pinhole::from_frame(frame, self.face, self.face, 1.0)
    }

    /// The face that direction `d` (non-zero) falls on: the dominant axis, ties to the first.
    pub fn face_of(d: Vec3) -> usize {
        let a = d.abs();
        if a.x >= a.y && a.x >= a.z {
            if d.x >= 0.0 { 0 } else { 1 }
        } else if a.y >= a.z {
            if d.y >= 0.0 { 2 } else { 3 }
        } else if d.z >= 0.0 {
            4
        } else {
            5
        }
    }
}

impl CameraModel for CubeMap {
    fn width(&self) -> u32 {
        6 * self.face_size()
    }
    fn height(&self) -> u32 {
        self.face_size()
    }

    fn generate_ray(&self, film: Vec2, lens: Vec2, channel: usize) -> Option<CameraRay> {
        let s = self.face_size() as f32;
        if !(film.x >= 0.0 && film.x <= 6.0 * s && film.y >= 0.0 && film.y <= s) {
            return None;
        }
        let i = ((film.x / s) as usize).min(5);
        self.face_camera(i)
            .generate_ray(Vec2::new(film.x - i as f32 * s, film.y), lens, channel)
    }

    fn project(&self, p: Vec3, _channel: usize) -> Option<Vec2> {
        let d = p - self.eye;
        if !(d.is_finite() && d != Vec3::ZERO) {
            return None;
        }
        let i = Self::face_of(d);
        let s = self.face_size() as f32;
        let f = self
            .face_camera(i)
            .project(p, 0)?
            .clamp(Vec2::ZERO, Vec2::splat(s));
        Some(Vec2::new(f.x + i as f32 * s, f.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The OpenGL table, written out independently of the face frames.
    fn gl_st(face: usize, r: Vec3) -> Vec2 {
        let (sc, tc, ma) = match face {
            0 => (-r.z, -r.y, r.x),
            1 => (r.z, -r.y, r.x),
            2 => (r.x, r.z, r.y),
            3 => (r.x, -r.z, r.y),
            4 => (r.x, -r.y, r.z),
            _ => (-r.x, -r.y, r.z),
        };
        Vec2::new(sc / ma.abs() + 1.0, tc / ma.abs() + 1.0) * 0.5
    }

    #[test]
    fn faces_follow_the_opengl_table() {
        let desc = CameraDesc::new(Vec3::new(1.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0);
        let cube = CubeMap::new(&desc, 8).unwrap();
        let dirs = [
            Vec3::new(0.9, 0.3, -0.2),
            Vec3::new(-0.8, -0.1, 0.4),
            Vec3::new(0.2, 0.7, 0.5),
            Vec3::new(-0.3, -0.9, 0.1),
            Vec3::new(0.1, -0.2, 0.8),
            Vec3::new(0.4, 0.3, -0.9),
        ];
        for (i, d) in dirs.into_iter().enumerate() {
            assert_eq!(CubeMap::face_of(d), i);
            let f = cube.project(desc.eye + d, 0).unwrap();
            let expect = gl_st(i, d) * 8.0 + Vec2::new(8.0 * i as f32, 0.0);
            assert!((f - expect).length() < 1e-4, "face {i}: {f} vs {expect}");
            let basis = cube.face_camera(i).frame.basis;
            assert!(basis.determinant() < 0.0, "mirrored");
        }
    }
}
