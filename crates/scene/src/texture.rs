//! Textures (base colour), stored linear.

use glam::{Vec2, Vec3};

/// How texture coordinates outside [0, 1] are mapped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WrapMode {
    #[default]
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// An RGB texture in linear light (sRGB inputs are linearised on load).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<Vec3>,
    pub wrap_s: WrapMode,
    pub wrap_t: WrapMode,
}

impl Texture {
    fn wrap(mode: WrapMode, i: i64, n: u32) -> u32 {
        let n = n as i64;
        match mode {
            WrapMode::Repeat => i.rem_euclid(n) as u32,
            WrapMode::ClampToEdge => i.clamp(0, n - 1) as u32,
            WrapMode::MirroredRepeat => {
                let p = i.rem_euclid(2 * n);
                (if p < n { p } else { 2 * n - 1 - p }) as u32
            }
        }
    }

    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = Self::wrap(self.wrap_s, x, self.width);
        let y = Self::wrap(self.wrap_t, y, self.height);
        self.texels[y as usize * self.width as usize + x as usize]
    }

    /// Bilinear lookup; `uv = (0, 0)` is the top-left corner of the image (glTF convention).
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        if !uv.is_finite() {
            return Vec3::ZERO;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let a = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let b = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        a.lerp(b, fy)
    }
}

/// sRGB transfer function -> linear (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}
