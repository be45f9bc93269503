//! Sample sets (Hunt et al. 2018, §5.1): a sample is a 2-D film position with a square
//! footprint; its `spp` subsample rays are generated just in time from a shared table of
//! low-discrepancy offsets within the footprint (and lens positions for depth of field).
//!
//! The film is the camera model's film (any [`Camera`]): a regular grid puts one sample at every
//! pixel centre (per colour channel when the camera distorts each channel separately), other
//! patterns (foveated) place samples anywhere on the film with larger footprints.

use glam::Vec2;
use parallax_core::Ray;
use parallax_core::sampling::lowdisc::sobol_2d;
use parallax_scene::camera::{Camera, CameraModel};

/// One sample: where on the film, which colour channel, and how large its footprint is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Film position of the footprint centre (pixels, y down).
    pub film: Vec2,
    /// Side of the square footprint in film pixels (1 for a grid sample).
    pub footprint: f32,
    /// Colour channel (0 unless the camera has per-channel distortion).
    pub channel: u8,
}

/// A set of samples with `spp` subsamples each.
#[derive(Clone, Debug)]
pub struct SampleSet {
    pub camera: Camera,
    pub samples: Vec<Sample>,
    /// Subsamples per sample (1..=32).
    pub spp: u32,
    /// Subsample offsets in `[-0.5, 0.5)^2` (scaled by each sample's footprint), length `spp`.
    pub offsets: Vec<Vec2>,
    /// Lens positions in `[0, 1)^2` for each subsample (ignored by models without aperture).
    pub lens: Vec<Vec2>,
}

/// Most subsamples per sample (HVVR's sample masks are 32 bits).
pub const MAX_SPP: u32 = 32;

impl SampleSet {
    /// Low-discrepancy subsample tables for `spp` subsamples: `spp == 1` is the footprint centre
    /// (and the lens centre); otherwise Sobol' (0,2) points, scrambled differently for the
    /// film and the lens so the two are decorrelated.
    pub fn subsample_tables(spp: u32) -> (Vec<Vec2>, Vec<Vec2>) {
        if spp <= 1 {
            return (vec![Vec2::ZERO], vec![Vec2::splat(0.5)]);
        }
        let offsets = (0..spp)
            .map(|k| sobol_2d(k, 0x9e37_79b9) - Vec2::splat(0.5))
            .collect();
        let lens = (0..spp).map(|k| sobol_2d(k, 0x85eb_ca6b)).collect();
        (offsets, lens)
    }

    /// One sample at every pixel centre (and every colour channel of a per-channel camera),
    /// `spp` subsamples each, in row-major pixel order, channels innermost.
    pub fn grid(camera: Camera, spp: u32) -> Self {
        let spp = spp.clamp(1, MAX_SPP);
        let (w, h) = (camera.width(), camera.height());
        let channels = camera.channel_count() as u8;
        let mut samples = Vec::with_capacity(w as usize * h as usize * channels as usize);
        for y in 0..h {
            for x in 0..w {
                for channel in 0..channels {
                    samples.push(Sample {
                        film: Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
                        footprint: 1.0,
                        channel,
                    });
                }
            }
        }
        let (offsets, lens) = Self::subsample_tables(spp);
        Self {
            camera,
            samples,
            spp,
            offsets,
            lens,
        }
    }

    /// Number of subsample rays.
    pub fn ray_count(&self) -> usize {
        self.samples.len() * self.spp as usize
    }

    /// Subsample `k` of sample `i`: the camera ray through `film + footprint * offsets[k]`
    /// with lens sample `lens[k]`; `None` where the camera has no ray (outside a fisheye's
    /// circle).
    #[inline]
    pub fn subsample_ray(&self, i: usize, k: usize) -> Option<Ray> {
        let s = &self.samples[i];
        let film = s.film + self.offsets[k] * s.footprint;
        self.camera.ray(film, self.lens[k], s.channel as usize)
    }
}
