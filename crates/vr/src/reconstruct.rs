//! Reconstruction (Hunt et al. 2018, §2.1 and §2.3): resolved samples -> display image, and a
//! picture of the sample pattern.
//!
//! - A **grid** set (every sample at a pixel centre with a one-pixel footprint) maps each sample
//!   to its pixel; per-channel sets (subpixel rendering of a distorted display, §2.1) write
//!   each sample's own colour channel into the pixel, so R, G and B of one pixel come from three
//!   different rays.
//! - An **irregular** set (foveated, §2.3) splats each sample's colour over its footprint with a
//!   separable tent filter of half-width one footprint, and normalises by the summed weights
//!   (per channel, so per-channel irregular sets work too). Pixels no footprint reaches stay
//!   black. (HVVR visualises foveation with nearest-neighbour; the tent gives a smooth image.)
//! - The **pattern** image colours each sample's footprint by the solid angle it covers (log
//!   scale, see [`pattern_image`]), alternating brightness by sample parity so that neighbouring
//!   footprints are told apart. Tile ids will replace this colour once the beam hierarchy
//!   exists (issue 5 part 2).

use glam::Vec3;
use parallax_core::{Image, NO_ID, Rgb};
use parallax_scene::camera::CameraModel;

use crate::{SampleSet, VisibilityBuffer};

/// True when every sample sits at a pixel centre with a one-pixel footprint.
pub fn is_grid(set: &SampleSet) -> bool {
    set.samples
        .iter()
        .all(|s| s.footprint == 1.0 && s.film.x.fract() == 0.5 && s.film.y.fract() == 0.5)
}

/// True when the set's samples carry more than one colour channel (subpixel rendering); a
/// set of one channel (e.g. only the green rays of a distorted camera) colours whole pixels.
pub fn is_per_channel(set: &SampleSet) -> bool {
    set.samples
        .first()
        .is_some_and(|f| set.samples.iter().any(|s| s.channel != f.channel))
}

/// The display image of `colors` (one per sample of `set`).
pub fn reconstruct(set: &SampleSet, colors: &[Vec3]) -> Image<Rgb> {
    assert_eq!(colors.len(), set.samples.len());
    let (w, h) = (set.camera.width(), set.camera.height());
    let per_channel = is_per_channel(set);
    let mut img = Image::new(w, h, Rgb::ZERO).expect("camera film size is valid");
    if is_grid(set) {
        for (s, c) in set.samples.iter().zip(colors) {
            let (x, y) = (s.film.x as u32, s.film.y as u32);
            if x >= w || y >= h {
                continue;
            }
            let p = img.get_mut(x, y);
            if per_channel {
                p[s.channel as usize] = c[s.channel as usize];
            } else {
                *p = *c;
            }
        }
        return img;
    }
    let mut weight = vec![Vec3::ZERO; img.len()];
    let mut sum = vec![Vec3::ZERO; img.len()];
    for (s, c) in set.samples.iter().zip(colors) {
        let r = s.footprint.max(1e-3);
        let mask = if per_channel {
            let mut m = Vec3::ZERO;
            m[s.channel as usize] = 1.0;
            m
        } else {
            Vec3::ONE
        };
        let x0 = (s.film.x - r).floor().max(0.0) as u32;
        let y0 = (s.film.y - r).floor().max(0.0) as u32;
        let x1 = ((s.film.x + r).ceil().max(0.0) as u32).min(w);
        let y1 = ((s.film.y + r).ceil().max(0.0) as u32).min(h);
        for y in y0..y1 {
            let wy = (1.0 - (y as f32 + 0.5 - s.film.y).abs() / r).max(0.0);
            for x in x0..x1 {
                let wx = (1.0 - (x as f32 + 0.5 - s.film.x).abs() / r).max(0.0);
                let wgt = wx * wy;
                if wgt > 0.0 {
                    let i = (y * w + x) as usize;
                    weight[i] += mask * wgt;
                    sum[i] += *c * mask * wgt;
                }
            }
        }
    }
    for ((p, s), wgt) in img.data_mut().iter_mut().zip(&sum).zip(&weight) {
        *p = Vec3::select(
            wgt.cmpgt(Vec3::ZERO),
            *s / wgt.max(Vec3::splat(1e-20)),
            Vec3::ZERO,
        );
    }
    img
}

/// Per-pixel closest triangle of subsample 0 of a grid set (the green channel's sample of a
/// per-channel set): the primary-visibility id image of the visibility buffer, comparable with
/// the reference G-buffer's `primitive_id`. Pixels without a sample are [`NO_ID`].
pub fn grid_ids(set: &SampleSet, vis: &VisibilityBuffer) -> Image<u32> {
    let (w, h) = (set.camera.width(), set.camera.height());
    let mut img = Image::new(w, h, NO_ID).expect("camera film size is valid");
    let want = if set.camera.channel_count() > 1 { 1 } else { 0 };
    let spp = set.spp as usize;
    for (i, s) in set.samples.iter().enumerate() {
        if s.channel != want {
            continue;
        }
        let (x, y) = (s.film.x as u32, s.film.y as u32);
        if x < w && y < h {
            img.set(x, y, vis.prim[i * spp]);
        }
    }
    img
}

/// Ramp from blue (`t = 0`) over green to red (`t = 1`).
fn ramp(t: f32) -> Vec3 {
    let t = t.clamp(0.0, 1.0);
    Vec3::new(t, 1.0 - (2.0 * t - 1.0).abs(), 1.0 - t)
}

/// Solid angle (sr) covered by each sample's footprint: `footprint^2 |dD/dx x dD/dy|` from the
/// camera's ray differentials at the footprint centre (lens centre); 0 where there is no ray.
pub fn footprint_solid_angles(set: &SampleSet) -> Vec<f32> {
    set.samples
        .iter()
        .map(|s| {
            set.camera
                .generate_ray(s.film, glam::Vec2::splat(0.5), s.channel as usize)
                .map_or(0.0, |r| {
                    let d = r.differential;
                    d.d_dir_dx.cross(d.d_dir_dy).length() * s.footprint * s.footprint
                })
        })
        .collect()
}

/// The sample pattern (module docs): each footprint filled with a colour for the solid angle it
/// covers, `log2(solid angle / smallest)` over the set's range (at least one stop) from blue
/// (smallest) to red (largest) — a lens-distorted or wide-angle grid shows how unevenly it
/// samples directions, a foveated set its footprint sizes — in a checkerboard of footprint
/// cells (alternating brightness); centres of footprints wider than two pixels white; samples
/// without a ray black.
pub fn pattern_image(set: &SampleSet) -> Image<Rgb> {
    let (w, h) = (set.camera.width(), set.camera.height());
    let mut img = Image::new(w, h, Rgb::ZERO).expect("camera film size is valid");
    let per_channel = is_per_channel(set);
    let solid = footprint_solid_angles(set);
    let min = solid
        .iter()
        .copied()
        .filter(|&a| a > 0.0)
        .fold(f32::INFINITY, f32::min);
    let max = solid.iter().copied().fold(0.0f32, f32::max);
    // Stops from the smallest to the largest footprint (at least one, so a uniform grid is blue).
    let stops = (max / min).log2().max(1.0);
    for (i, s) in set.samples.iter().enumerate() {
        let half = 0.5 * s.footprint;
        let cell = (s.film / s.footprint.max(1e-3)).floor();
        let shade = if (cell.x + cell.y).rem_euclid(2.0) == 0.0 {
            1.0
        } else {
            0.6
        };
        let c = if solid[i] > 0.0 {
            ramp((solid[i] / min).log2() / stops) * shade
        } else {
            Vec3::ZERO
        };
        let x0 = (s.film.x - half).round().max(0.0) as u32;
        let y0 = (s.film.y - half).round().max(0.0) as u32;
        let x1 = ((s.film.x + half).round().max(0.0) as u32).min(w);
        let y1 = ((s.film.y + half).round().max(0.0) as u32).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = img.get_mut(x, y);
                if per_channel {
                    p[s.channel as usize] = c[s.channel as usize];
                } else {
                    *p = c;
                }
            }
        }
        if s.footprint > 2.0 {
            let (x, y) = (s.film.x as u32, s.film.y as u32);
            if x < w && y < h {
                img.set(x, y, Vec3::ONE);
            }
        }
    }
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;
    use parallax_scene::CameraDesc;
    use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

    fn set(model: ModelKind) -> SampleSet {
        let desc = CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0);
        let cam = Camera::new(model, &desc, 16, 12, &CameraOptions::default()).unwrap();
        SampleSet::grid(cam, 1)
    }

    #[test]
    fn grid_maps_samples_to_pixels_and_channels() {
        let s = set(ModelKind::Distorted);
        assert!(is_grid(&s) && is_per_channel(&s));
        let colors: Vec<Vec3> = (0..s.samples.len())
            .map(|i| Vec3::splat(i as f32))
            .collect();
        let img = reconstruct(&s, &colors);
        let p = *img.get(3, 2);
        let i = (2 * 16 + 3) * 3;
        assert_eq!(p, Vec3::new(i as f32, (i + 1) as f32, (i + 2) as f32));
    }

    #[test]
    fn irregular_tent_splat_is_normalised() {
        let mut s = set(ModelKind::Pinhole);
        // Coarse samples every 3 pixels with a 3-pixel footprint, off the pixel centres.
        s.samples.clear();
        for y in 0..5 {
            for x in 0..7 {
                s.samples.push(crate::Sample {
                    film: Vec2::new(x as f32 * 3.0 + 0.2, y as f32 * 3.0 + 0.1),
                    footprint: 3.0,
                    channel: 0,
                });
            }
        }
        assert!(!is_grid(&s));
        let c = Vec3::new(0.25, 0.5, 1.0);
        let img = reconstruct(&s, &vec![c; s.samples.len()]);
        // Every pixel some footprint reaches gets exactly the constant colour.
        let covered = img.data().iter().filter(|p| **p != Vec3::ZERO).count();
        assert!(covered > 150, "{covered}");
        for p in img.data().iter().filter(|p| **p != Vec3::ZERO) {
            assert!((*p - c).abs().max_element() < 1e-5, "{p}");
        }
        let pat = pattern_image(&s);
        assert_eq!((pat.width(), pat.height()), (16, 12));
    }
}
