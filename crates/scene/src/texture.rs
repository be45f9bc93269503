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

/// `x.floor()` for the texel coordinates, inline: `f32::floor` is a call into the software
/// `floorf` where the build targets x86-64 without SSE 4.1 (~24 instructions, four per
/// bilinear look-up and prefetch). Equal to `x.floor()` for every `x` but `-0.0` (which it
/// returns as `+0.0`; texel coordinates `uv * size - 0.5` are never `-0.0`).
#[inline]
fn floor(x: f32) -> f32 {
    // |x| >= 2^23 (and infinities, NaN) is already integral or passes through.
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        if t > x { t - 1.0 } else { t }
    } else {
        x
    }
}

impl Texture {
    #[inline]
    fn wrap(mode: WrapMode, i: i64, n: u32) -> u32 {
        let n = n as i64;
        if (0..n).contains(&i) {
            return i as u32; // every mode maps the texture's own texels to themselves
        }
        match mode {
            WrapMode::Repeat => i.rem_euclid(n) as u32,
            WrapMode::ClampToEdge => i.clamp(0, n - 1) as u32,
            WrapMode::MirroredRepeat => {
                let p = i.rem_euclid(2 * n);
                (if p < n { p } else { 2 * n - 1 - p }) as u32
            }
        }
    }

    #[inline]
    fn at(&self, x: u32, y: u32) -> Vec3 {
        self.texels[y as usize * self.width as usize + x as usize]
    }

    /// The texels the bilinear taps of [`Self::sample`] at `uv` start at: the first tap's
    /// row-major index and the index one row below it (for cache prefetching).
    pub fn tap_rows(&self, uv: Vec2) -> Option<(usize, usize)> {
        if !uv.is_finite() {
            return None;
        }
        let ix = floor(uv.x * self.width as f32 - 0.5) as i64;
        let iy = floor(uv.y * self.height as f32 - 0.5) as i64;
        let x = Self::wrap(self.wrap_s, ix, self.width) as usize;
        let (ya, yb) = (
            Self::wrap(self.wrap_t, iy, self.height) as usize,
            Self::wrap(self.wrap_t, iy + 1, self.height) as usize,
        );
        let w = self.width as usize;
        Some((ya * w + x, yb * w + x))
    }

    /// Bilinear lookup; `uv = (0, 0)` is the top-left corner of the image (glTF convention).
    /// Texel centres sit at half-integer positions (`uv * size - 0.5`, as Mitsuba 3's bitmap
    /// and OpenGL filter); the four taps are wrapped once per axis.
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        if !uv.is_finite() {
            return Vec3::ZERO;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (floor(x), floor(y));
        let (fx, fy) = (x - x0, y - y0);
        // Far-out coordinates saturate in the cast; wrapping keeps them in range.
        let (ix, iy) = (x0 as i64, y0 as i64);
        let (xa, xb) = (
            Self::wrap(self.wrap_s, ix, self.width),
            Self::wrap(self.wrap_s, ix + 1, self.width),
        );
        let (ya, yb) = (
            Self::wrap(self.wrap_t, iy, self.height),
            Self::wrap(self.wrap_t, iy + 1, self.height),
        );
        let a = self.at(xa, ya).lerp(self.at(xb, ya), fx);
        let b = self.at(xa, yb).lerp(self.at(xb, yb), fx);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inline_floor_is_f32_floor_bit_for_bit() {
        let mut xs = vec![
            0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.999_999_94,
            -0.999_999_94,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_609.0,
            1e20,
            -1e20,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        // Every 1021st float between -2^24 and 2^24 (both signs, all exponents below).
        let mut b = 0u32;
        while b < 0x4B80_0000 {
            xs.push(f32::from_bits(b));
            xs.push(-f32::from_bits(b + 1));
            b += 1021;
        }
        for x in xs {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "{x}");
        }
        assert!(floor(f32::NAN).is_nan());
        assert_eq!(floor(-0.0), 0.0);
    }
}
