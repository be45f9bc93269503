//! Near-eye light-field elemental images (Lanman & Luebke 2013, "Near-eye light field
//! displays"; Widmer et al. 2015, §5.3: "given color+depth buffers for the left and right
//! eye, we generate a complete elemental image set with our ray tracing approach").
//!
//! **Display model.** Per eye, a microdisplay sits behind a microlens array; the eye looks
//! through the array from the eye relief `d_e`. In the eye's camera frame (looking down
//! `-z`) the lens array is the plane `z = -d_e` and the display the plane
//! `z = -(d_e + f)`: the display at the lenslets' focal distance `f`, so each lenslet shows
//! its elemental image at infinity (the collimated case; a display slightly inside `f` would
//! put the virtual image at a finite distance). Lenslets are pinholes at their optical
//! centres `c_k = (k_x, k_y) w_l` (pitch `w_l`, one lenslet centred on the axis). The
//! elemental images tile the display with pitch `w_e = w_l (d_e + f) / d_e` — the lens
//! pitch projected from the eye's centre onto the display, so that from the eye every
//! lenslet shows its own elemental image (Lanman & Luebke's eye-box construction) — and
//! display pixel `P` (pitch `p`) belongs to the lenslet `k = round(P / w_e)`.
//!
//! **Rays.** The light pixel `P` sends through its lenslet's centre `c_k` reaches the eye
//! along `c_k - P`; the eye sees it coming from `P - c_k`, the line through the pinhole
//! continued behind the display into the virtual scene. So the pixel shows the scene's
//! radiance along the world ray from `c_k` along `P - c_k` (away from the eye):
//! `origin = eye + R c_k`, `dir = R normalize(P - c_k)`. Every display pixel's ray is traced through the layers of
//! that eye's reference ([`crate::warp::warp_rays`]); [`NearEye::reference_camera`] is the
//! eye's pinhole whose field of view holds every ray direction.
//!
//! | parameter | type | default | meaning |
//! |---|---|---|---|
//! | `display_w`, `display_h` | u32 | 1280 x 720 | display pixels per eye |
//! | `pixel_pitch_m` | f32 | 12e-6 | display pixel pitch (m) |
//! | `lens_pitch_m` | f32 | 1.0e-3 | microlens pitch `w_l` (m) |
//! | `focal_m` | f32 | 3.3e-3 | lenslet focal length `f` = lens-display gap (m) |
//! | `eye_relief_m` | f32 | 0.035 | eye to lens array `d_e` (m) |
//!
//! The defaults are of the scale of Lanman & Luebke's prototype (a 1280 x 720 OLED
//! microdisplay, ~1 mm lenslets of a few mm focal length; our values, the paper is not in
//! `papers/`). Parameters whose elemental image is narrower than one display pixel
//! (`w_e < p`), or zero / non-finite values, are errors.

use glam::{UVec2, Vec3};
use parallax_core::Ray;
use parallax_scene::camera::{CameraFrame, Pinhole};
use serde::Serialize;

use crate::SynthError;

/// A near-eye light-field display (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct NearEye {
    pub display_w: u32,
    pub display_h: u32,
    pub pixel_pitch_m: f32,
    pub lens_pitch_m: f32,
    pub focal_m: f32,
    pub eye_relief_m: f32,
}

impl Default for NearEye {
    fn default() -> Self {
        Self {
            display_w: 1280,
            display_h: 720,
            pixel_pitch_m: 12e-6,
            lens_pitch_m: 1.0e-3,
            focal_m: 3.3e-3,
            eye_relief_m: 0.035,
        }
    }
}

impl NearEye {
    /// Checks the parameter table's ranges.
    pub fn validate(&self) -> Result<(), SynthError> {
        parallax_core::image::check_size(self.display_w, self.display_h)?;
        for (name, v) in [
            ("pixel pitch", self.pixel_pitch_m),
            ("lens pitch", self.lens_pitch_m),
            ("focal length", self.focal_m),
            ("eye relief", self.eye_relief_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SynthError::Invalid(format!(
                    "near-eye display: the {name} must be finite and > 0 m, got {v}"
                )));
            }
        }
        let px = self.elemental_px();
        if !(px >= 1.0) {
            return Err(SynthError::Invalid(format!(
                "near-eye display: an elemental image spans {px:.3} display pixels (lens pitch {} m x (eye relief + focal length) / eye relief over pixel pitch {} m): it is empty; use a larger lens pitch or a finer display",
                self.lens_pitch_m, self.pixel_pitch_m
            )));
        }
        Ok(())
    }

    /// Elemental image pitch `w_e` (m).
    pub fn elemental_pitch_m(&self) -> f32 {
        self.lens_pitch_m * (self.eye_relief_m + self.focal_m) / self.eye_relief_m
    }

    /// Elemental image pitch in display pixels.
    pub fn elemental_px(&self) -> f32 {
        self.elemental_pitch_m() / self.pixel_pitch_m
    }

    /// Camera-space centre of display pixel `(x, y)` (y down in the image, up in space).
    #[inline]
    pub fn pixel_position(&self, x: u32, y: u32) -> Vec3 {
        let p = self.pixel_pitch_m;
        Vec3::new(
            (x as f32 + 0.5 - 0.5 * self.display_w as f32) * p,
            (0.5 * self.display_h as f32 - y as f32 - 0.5) * p,
            -(self.eye_relief_m + self.focal_m),
        )
    }

    /// The lenslet (integer lattice index, `(0, 0)` on the axis) of display pixel `(x, y)`.
    #[inline]
    pub fn lenslet_of(&self, x: u32, y: u32) -> (i32, i32) {
        let p = self.pixel_position(x, y);
        let we = self.elemental_pitch_m();
        ((p.x / we).round() as i32, (p.y / we).round() as i32)
    }

    /// Camera-space optical centre of lenslet `k`.
    #[inline]
    pub fn lens_centre(&self, k: (i32, i32)) -> Vec3 {
        Vec3::new(
            k.0 as f32 * self.lens_pitch_m,
            k.1 as f32 * self.lens_pitch_m,
            -self.eye_relief_m,
        )
    }

    /// The camera-space ray of display pixel `(x, y)`: from its lenslet's centre through
    /// the pixel, into the scene (module docs).
    #[inline]
    pub fn camera_ray(&self, x: u32, y: u32) -> (Vec3, Vec3) {
        let c = self.lens_centre(self.lenslet_of(x, y));
        let d = self.pixel_position(x, y) - c;
        (c, d / d.length())
    }

    /// The world ray of display pixel `(x, y)` for an eye at `frame`.
    #[inline]
    pub fn ray(&self, frame: &CameraFrame, x: u32, y: u32) -> Ray {
        let (o, d) = self.camera_ray(x, y);
        Ray::new(
            frame.position + frame.dir_to_world(o),
            frame.dir_to_world(d),
        )
    }

    /// The largest `|d.x / d.z|` and `|d.y / d.z|` over every display pixel's ray (the
    /// extremes lie on the display's border rows and columns).
    pub fn max_tangents(&self) -> (f32, f32) {
        let (w, h) = (self.display_w, self.display_h);
        let (mut tx, mut ty) = (0.0f32, 0.0f32);
        let mut visit = |x: u32, y: u32| {
            let (_, d) = self.camera_ray(x, y);
            tx = tx.max((d.x / d.z).abs());
            ty = ty.max((d.y / d.z).abs());
        };
        for x in 0..w {
            visit(x, 0);
            visit(x, h - 1);
            visit(x, h / 2);
        }
        for y in 0..h {
            visit(0, y);
            visit(w - 1, y);
            visit(w / 2, y);
        }
        (tx, ty)
    }

    /// The eye's reference pinhole: `width` pixels wide, its field of view the rays'
    /// extreme tangents plus `margin` (a fraction), square pixels.
    pub fn reference_camera(
        &self,
        frame: CameraFrame,
        width: u32,
        margin: f32,
    ) -> Result<Pinhole, SynthError> {
        self.validate()?;
        let (tx, ty) = self.max_tangents();
        let (tx, ty) = (tx * (1.0 + margin), ty * (1.0 + margin));
        let height = ((width as f32 * ty / tx).round() as u32).max(1);
        parallax_core::image::check_size(width, height)?;
        // tan_half_x = tan_half_y * width / height must cover tx.
        let tan_half_y = ty.max(tx * height as f32 / width as f32);
        Ok(Pinhole::from_frame(frame, width, height, tan_half_y))
    }

    /// Elemental image count (lenslets with at least one pixel) along x and y.
    pub fn lenslets(&self) -> UVec2 {
        let (a, b) = self.lenslet_of(0, self.display_h - 1);
        let (c, d) = self.lenslet_of(self.display_w - 1, 0);
        UVec2::new((c - a + 1) as u32, (d - b + 1) as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometry_of_the_default_display() {
        let d = NearEye::default();
        d.validate().unwrap();
        // w_e = 1 mm * 38.3 / 35 = 1.0943 mm = 91.2 px.
        assert!(
            (d.elemental_px() - 91.19).abs() < 0.05,
            "{}",
            d.elemental_px()
        );
        // The centre pixel's ray leaves the axial lenslet along the axis.
        let (o, dir) = d.camera_ray(640, 360);
        assert!(o.x.abs() < 1e-9 && (o.z + 0.035).abs() < 1e-9);
        assert!(dir.z < -0.99, "{dir}");
        // Rays through one lenslet fan out: pixels left of its centre look left.
        let k = d.lenslet_of(640, 360);
        assert_eq!(k, (0, 0));
        let (_, a) = d.camera_ray(600, 360);
        assert!(a.x < 0.0, "{a}");
        // From the eye, the lenslet centre projects onto its elemental image's centre.
        let c = d.lens_centre((3, -2));
        let on_display = c * ((d.eye_relief_m + d.focal_m) / d.eye_relief_m);
        let we = d.elemental_pitch_m();
        assert!((on_display.x - 3.0 * we).abs() < 1e-9 && (on_display.y + 2.0 * we).abs() < 1e-9);
        let n = d.lenslets();
        assert!(n.x >= 14 && n.y >= 8, "{n}");
    }

    #[test]
    fn empty_elemental_images_and_bad_values_are_errors() {
        let tiny = NearEye {
            lens_pitch_m: 5e-6,
            ..NearEye::default()
        };
        assert!(tiny.validate().unwrap_err().to_string().contains("empty"));
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let d = NearEye {
                focal_m: bad,
                ..NearEye::default()
            };
            assert!(d.validate().is_err());
        }
        let d = NearEye {
            display_w: 0,
            ..NearEye::default()
        };
        assert!(d.validate().is_err());
    }
}
