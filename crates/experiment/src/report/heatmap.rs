//! Error heatmaps of a result image against its ground truth, and their colour scale.
//!
//! The error of a pixel is the mean absolute difference of the two PNGs' 8-bit sRGB channels
//! (what the eye compares on screen, 0..255), mapped through the viridis colour map from 0 to
//! the scale's top: the 99th percentile of the image's errors rounded up to a "nice" number
//! (1, 2, 5 x 10^k), so a few outliers do not wash the map out; larger errors saturate.
//!
//! Invariants: the heatmap has the result's size; images of different sizes are an error.

use std::path::Path;

use plotters::style::RGBColor;
use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};

use crate::error::ExperimentError;

/// A heatmap and the top of its scale.
pub struct Heatmap {
    pub png: Vec<u8>,
    pub scale_max: f32,
    pub mean_error: f32,
}

fn load(path: &Path) -> Result<image::RgbImage, ExperimentError> {
    image::open(path)
        .map(|i| i.to_rgb8())
        .map_err(|e| ExperimentError::Report(format!("{}: {e}", path.display())))
}

/// The smallest 1, 2 or 5 x 10^k >= `v` (>= 1).
pub fn nice_ceiling(v: f32) -> f32 {
    let v = v.max(1.0);
    let mut p = 10f32.powf(v.log10().floor());
    loop {
        for m in [1.0, 2.0, 5.0] {
            if m * p >= v {
                return m * p;
            }
        }
        p *= 10.0;
    }
}

/// The colour of `t` in 0..=1.
pub fn colour(t: f32) -> [u8; 3] {
    let RGBColor(r, g, b) = ViridisRGB.get_color(t.clamp(0.0, 1.0));
    [r, g, b]
}

/// The error heatmap of `result` against `truth` as PNG bytes.
pub fn error_heatmap(result: &Path, truth: &Path) -> Result<Heatmap, ExperimentError> {
    let a = load(result)?;
    let b = load(truth)?;
    if a.dimensions() != b.dimensions() {
        return Err(ExperimentError::Report(format!(
            "{} is {:?} but its ground truth {} is {:?}",
            result.display(),
            a.dimensions(),
            truth.display(),
            b.dimensions()
        )));
    }
    let err: Vec<f32> = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p[c] as f32 - q[c] as f32).abs())
                .sum::<f32>()
                / 3.0
        })
        .collect();
    let mut sorted = err.clone();
    sorted.sort_by(f32::total_cmp);
    let p99 = sorted
        .get(sorted.len().saturating_sub(1) * 99 / 100)
        .copied()
        .unwrap_or(0.0);
    let scale_max = nice_ceiling(p99);
    let mean_error = err.iter().sum::<f32>() / err.len().max(1) as f32;
    let mut img = image::RgbImage::new(a.width(), a.height());
    for (px, e) in img.pixels_mut().zip(&err) {
        *px = image::Rgb(colour(e / scale_max));
    }
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| ExperimentError::Report(format!("encoding a heatmap: {e}")))?;
    Ok(Heatmap {
        png,
        scale_max,
        mean_error,
    })
}

/// An inline SVG colour bar from 0 to `max` (8-bit sRGB units).
pub fn scale_svg(max: f32) -> String {
    let mut s = String::from(
        "<svg class=\"scale\" xmlns=\"http://www.w3.org/2000/svg\" width=\"220\" height=\"34\" viewBox=\"0 0 220 34\">",
    );
    let steps = 50;
    for i in 0..steps {
        let [r, g, b] = colour(i as f32 / (steps - 1) as f32);
        s += &format!(
            "<rect x=\"{}\" y=\"0\" width=\"4.4\" height=\"16\" fill=\"rgb({r},{g},{b})\"/>",
            i as f32 * 4.4
        );
    }
    s += &format!(
        "<text x=\"0\" y=\"30\" font-size=\"11\">0</text><text x=\"220\" y=\"30\" font-size=\"11\" text-anchor=\"end\">&#8805; {max} / 255</text></svg>"
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_numbers() {
        assert_eq!(nice_ceiling(0.0), 1.0);
        assert_eq!(nice_ceiling(3.0), 5.0);
        assert_eq!(nice_ceiling(20.0), 20.0);
        assert_eq!(nice_ceiling(51.0), 100.0);
    }
}
