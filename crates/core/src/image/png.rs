//! 8-bit PNG output (display-referred) and PNG/JPEG input (decoded to linear light).
//!
//! Output pipeline for colour ([`write_png`]): linear RGB × `2^exposure` → tonemap
//! ([`Tonemap::Clamp`] or the ACES filmic fit of Narkowicz 2015) → sRGB OETF (IEC 61966-2-1)
//! → 8 bits with rounding. Depth previews ([`write_depth_png`]) and id false colour
//! ([`write_id_png`]) are helpers for inspection, not data: use EXR for data.

use std::path::Path;

use ::image::{ExtendedColorType, ImageFormat, ImageReader, Limits};
use rayon::prelude::*;

use super::buffer::{Image, Rgb, check_size};
use super::gbuffer::NO_ID;
use crate::sampling::pcg_hash;
use crate::{CoreError, Result};

/// The tone curve applied before sRGB encoding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Tonemap {
    /// Clamp to `[0, 1]` (exact for low-dynamic-range content).
    #[default]
    Clamp,
    /// Narkowicz 2015, "ACES Filmic Tone Mapping Curve":
    /// `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)`, applied per channel as published
    /// (without the 0.6 pre-exposure of the blog's ACES comparison; use `exposure` for that).
    AcesFilmic,
}

/// How linear values become display values.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToneMapping {
    /// Exposure in stops: values are multiplied by `2^exposure` before the tone curve.
    pub exposure: f32,
    pub tonemap: Tonemap,
}

impl ToneMapping {
    /// One linear value to a display value in `[0, 1]` (sRGB-encoded). NaN maps to 0.
    #[inline]
    pub fn apply(&self, linear: f32) -> f32 {
        let x = (linear * self.exposure.exp2()).max(0.0);
        let t = match self.tonemap {
            Tonemap::Clamp => x,
            Tonemap::AcesFilmic => aces_narkowicz(x),
        };
        if t.is_nan() {
            0.0
        } else {
            srgb_oetf(t.min(1.0))
        }
    }
}

/// The ACES filmic curve fit of Narkowicz 2015, clamped to `[0, 1]`.
#[inline]
pub fn aces_narkowicz(x: f32) -> f32 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// sRGB OETF (IEC 61966-2-1): linear `[0, 1]` → encoded `[0, 1]`.
#[inline]
pub fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear.max(0.0)
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// sRGB EOTF (inverse of [`srgb_oetf`]): encoded `[0, 1]` → linear `[0, 1]`.
#[inline]
pub fn srgb_eotf(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded.max(0.0) / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

#[inline]
fn to_u8(v: f32) -> u8 {
    (v * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

/// Display values of a linear image (sRGB-encoded floats in `[0, 1]`): what [`write_png`]
/// quantises. Useful to compute metrics on displayed rather than linear values.
pub fn tonemap_image(img: &Image<Rgb>, tm: &ToneMapping) -> Image<Rgb> {
    img.map(|c| Rgb::new(tm.apply(c.x), tm.apply(c.y), tm.apply(c.z)))
}

/// Tonemapped 8-bit sRGB bytes (`RGBRGB...`, row-major), rows converted in parallel.
pub fn to_srgb8(img: &Image<Rgb>, tm: &ToneMapping) -> Vec<u8> {
    let w = img.width() as usize;
    let mut out = vec![0u8; img.len() * 3];
    out.par_chunks_mut(w * 3)
        .zip(img.data().par_chunks(w))
        .for_each(|(dst, src)| {
            for (d, c) in dst.chunks_exact_mut(3).zip(src) {
                d[0] = to_u8(tm.apply(c.x));
                d[1] = to_u8(tm.apply(c.y));
                d[2] = to_u8(tm.apply(c.z));
            }
        });
    out
}

fn io_err(path: &Path, e: impl std::fmt::Display) -> CoreError {
    CoreError::ImageIo {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

fn save(path: &Path, bytes: &[u8], w: u32, h: u32, color: ExtendedColorType) -> Result<()> {
    ::image::save_buffer_with_format(path, bytes, w, h, color, ImageFormat::Png)
        .map_err(|e| io_err(path, format!("writing PNG: {e}")))
}

/// Writes a linear RGB image as an 8-bit sRGB PNG after exposure and tonemapping.
pub fn write_png(path: impl AsRef<Path>, img: &Image<Rgb>, tm: &ToneMapping) -> Result<()> {
    let bytes = to_srgb8(img, tm);
    save(
        path.as_ref(),
        &bytes,
        img.width(),
        img.height(),
        ExtendedColorType::Rgb8,
    )
}

/// Writes values clamped to `[0, 1]` and quantised directly — no exposure, tone curve or
/// sRGB encoding. For data previews such as normal maps (`n * 0.5 + 0.5`), not for colour.
pub fn write_png_linear_clamped(path: impl AsRef<Path>, img: &Image<Rgb>) -> Result<()> {
    let bytes: Vec<u8> = img
        .data()
        .iter()
        .flat_map(|c| [to_u8(c.x), to_u8(c.y), to_u8(c.z)])
        .collect();
    save(
        path.as_ref(),
        &bytes,
        img.width(),
        img.height(),
        ExtendedColorType::Rgb8,
    )
}

/// Grey preview bytes of a depth image: finite values mapped linearly from `min..max` to
/// `255..0` (near is white), non-finite values (misses) to 0. A constant finite image is
/// all white.
pub fn depth_to_grey8(depth: &Image<f32>) -> Vec<u8> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &d in depth.data().iter().filter(|d| d.is_finite()) {
        lo = lo.min(d);
        hi = hi.max(d);
    }
    let scale = if hi > lo { 1.0 / (hi - lo) } else { 0.0 };
    depth
        .data()
        .iter()
        .map(|&d| {
            if d.is_finite() {
                to_u8(1.0 - (d - lo) * scale)
            } else {
                0
            }
        })
        .collect()
}

/// Writes a depth image as a normalised grey PNG (see [`depth_to_grey8`]).
pub fn write_depth_png(path: impl AsRef<Path>, depth: &Image<f32>) -> Result<()> {
    let bytes = depth_to_grey8(depth);
    save(
        path.as_ref(),
        &bytes,
        depth.width(),
        depth.height(),
        ExtendedColorType::L8,
    )
}

/// A stable false colour for an id (hashed, each channel in `64..=255` so no id is black);
/// [`NO_ID`] is black.
#[inline]
pub fn id_colour(id: u32) -> [u8; 3] {
    if id == NO_ID {
        return [0; 3];
    }
    let h = pcg_hash(id);
    let c = |shift: u32| 64 + (((h >> shift) & 0xff) * 191 / 255) as u8;
    [c(0), c(8), c(16)]
}

/// Writes an id image (material / primitive / object ids) in false colour.
pub fn write_id_png(path: impl AsRef<Path>, ids: &Image<u32>) -> Result<()> {
    let bytes: Vec<u8> = ids.data().iter().flat_map(|&i| id_colour(i)).collect();
    save(
        path.as_ref(),
        &bytes,
        ids.width(),
        ids.height(),
        ExtendedColorType::Rgb8,
    )
}

/// Reads a PNG or JPEG (format guessed from the content) into linear RGB: 8- and 16-bit
/// values are normalised and sRGB-decoded, alpha is dropped. The size is limited to 16384
/// per side and [`super::MAX_IMAGE_PIXELS`] before pixels are decoded.
pub fn read_image(path: impl AsRef<Path>) -> Result<Image<Rgb>> {
    let path = path.as_ref();
    let mut reader = ImageReader::open(path)
        .map_err(|e| io_err(path, e))?
        .with_guessed_format()
        .map_err(|e| io_err(path, e))?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(16384);
    limits.max_image_height = Some(16384);
    reader.limits(limits);
    let dynamic = reader
        .decode()
        .map_err(|e| io_err(path, format!("decoding: {e}")))?;
    let (w, h) = (dynamic.width(), dynamic.height());
    check_size(w, h)?;
    let rgb = dynamic.into_rgb32f();
    let data: Vec<Rgb> = rgb
        .as_raw()
        .chunks_exact(3)
        .map(|p| Rgb::new(srgb_eotf(p[0]), srgb_eotf(p[1]), srgb_eotf(p[2])))
        .collect();
    Image::from_vec(w, h, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curves_invert_and_hit_known_points() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_eotf(srgb_oetf(x)) - x).abs() < 1e-5);
        }
        assert!((srgb_oetf(0.18) - 0.4613).abs() < 1e-3); // mid grey encodes near 118/255
        assert!((srgb_oetf(1.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn tone_mapping_applies_exposure_and_curve() {
        let clamp = ToneMapping::default();
        assert!((clamp.apply(2.0) - 1.0).abs() < 1e-6);
        assert_eq!(clamp.apply(-1.0), 0.0);
        assert_eq!(clamp.apply(f32::NAN), 0.0);
        let half = ToneMapping {
            exposure: -1.0,
            ..clamp
        };
        assert!((half.apply(1.0) - srgb_oetf(0.5)).abs() < 1e-6);
        // ACES: monotone, below 1 for moderate values, ~0.8 at 1.0.
        assert!((aces_narkowicz(1.0) - 0.8038).abs() < 1e-3);
        assert!(aces_narkowicz(0.5) < aces_narkowicz(1.0));
        assert_eq!(aces_narkowicz(100.0), 1.0);
    }

    #[test]
    fn depth_preview_maps_near_to_white_and_misses_to_black() {
        let d = Image::from_vec(4, 1, vec![1.0, 3.0, f32::INFINITY, 2.0]).unwrap();
        assert_eq!(depth_to_grey8(&d), vec![255, 0, 0, 128]);
        let c = Image::new(2, 1, 5.0f32).unwrap();
        assert_eq!(depth_to_grey8(&c), vec![255, 255]);
    }

    #[test]
    fn id_colours_are_stable_distinct_and_never_black() {
        assert_eq!(id_colour(NO_ID), [0, 0, 0]);
        assert_eq!(id_colour(5), id_colour(5));
        let mut seen = std::collections::HashSet::new();
        for i in 0..200 {
            let c = id_colour(i);
            assert!(c.iter().all(|&v| v >= 64));
            seen.insert(c);
        }
        assert!(seen.len() >= 199);
    }
}
