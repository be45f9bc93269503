//! Sample patterns of HVVR (Hunt et al. 2018, §2, Table 5) as [`SampleSet`] constructors, and
//! the cheap bit-identical subsample ray generator the caster uses.
//!
//! | pattern | constructor | camera |
//! |---|---|---|
//! | regular grid | [`SampleSet::grid`] | any |
//! | direct per-channel lens distortion (§2.1) | [`SampleSet::distorted`] | `Camera::Distorted` (one sample per pixel *and* colour channel) |
//! | foveated (§2.3) | [`SampleSet::foveated`] | any (planar models make most sense) |
//! | wide FoV 210 x 130 (§2.2) | [`SampleSet::wide_fov`] | `Camera::Fisheye` (samples outside the image circle dropped) |
//! | stochastic depth of field (§2.4) | [`SampleSet::depth_of_field`] | `Camera::ThinLens` (lens sample per subsample) |
//!
//! The *pre-distortion* variant of §2.1 (render an enlarged pinhole image, warp it afterwards)
//! needs no constructor of its own: it is [`SampleSet::grid`] on a `Camera::Pinhole` of the
//! enlarged size (1.4x per side for the Rift-like default), followed by an image warp that is not
//! part of visibility.

use glam::Vec2;
use parallax_core::Ray;
use parallax_scene::camera::{Camera, CameraModel};

use crate::{Sample, SampleSet};

/// Why a pattern could not be built for a camera.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PatternError {
    #[error("the gaze must be a finite point of [-1, 1] x [-1, 1], got {x},{y}")]
    BadGaze { x: f32, y: f32 },
    #[error("the {pattern} pattern needs a {needs} camera, got {got}")]
    WrongCamera {
        pattern: &'static str,
        needs: &'static str,
        got: &'static str,
    },
    #[error(
        "foveation parameters must be finite with fovea radius >= 0 and slope >= 0, got radius {radius}, slope {slope}"
    )]
    BadFoveation { radius: f32, slope: f32 },
}

impl SampleSet {
    /// Direct rendering into post-distortion display space with a separate sample set per colour
    /// channel (§2.1 "Direct Distortion + Subpixel Rendering"): the grid of a per-channel camera.
    pub fn distorted(camera: Camera, spp: u32) -> Result<Self, PatternError> {
        if camera.channel_count() != 3 {
            return Err(PatternError::WrongCamera {
                pattern: "distorted",
                needs: "distorted (per-channel)",
                got: camera.kind().name(),
            });
        }
        Ok(Self::grid(camera, spp))
    }

    /// Stochastic depth of field (§2.4): a grid on a thin-lens camera; subsample `k` uses lens
    /// sample `lens[k]` (HVVR §5.1: "a separate low-discrepancy point set" for the origins).
    pub fn depth_of_field(camera: Camera, spp: u32) -> Result<Self, PatternError> {
        if !matches!(camera, Camera::ThinLens(_)) {
            return Err(PatternError::WrongCamera {
                pattern: "depth of field",
                needs: "thinlens",
                got: camera.kind().name(),
            });
        }
        Ok(Self::grid(camera, spp))
    }

    /// Very wide field of view (§2.2): the grid of a fisheye (210 x 130 degrees by default)
    /// without the samples whose footprint centre lies outside the image circle.
    pub fn wide_fov(camera: Camera, spp: u32) -> Result<Self, PatternError> {
        if !matches!(camera, Camera::Fisheye(_)) {
            return Err(PatternError::WrongCamera {
                pattern: "wide fov",
                needs: "fisheye",
                got: camera.kind().name(),
            });
        }
        let mut set = Self::grid(camera, spp);
        let cam = set.camera.clone();
        set.samples
            .retain(|s| cam.generate_ray(s.film, Vec2::splat(0.5), 0).is_some());
        Ok(set)
    }

    /// Foveated sampling (§2.3, after Guenter et al. 2012): a linear acuity model in film
    /// pixels — footprint 1 within `fovea_radius` pixels of `gaze`, growing as
    /// `1 + slope * (r - fovea_radius)` beyond. The fovea is the regular grid; outside it the
    /// samples lie on concentric rings spaced by the local footprint, `ceil(2 pi r / f)` per
    /// ring, each ring rotated by the golden angle (a jittered layout without clumping). Only
    /// samples whose centre is on the film are kept; each carries its footprint.
    ///
    /// Simplification: eccentricity is measured in film pixels, not visual degrees (for a
    /// pinhole the two are proportional near the centre).
    pub fn foveated(
        camera: Camera,
        gaze: Vec2,
        fovea_radius: f32,
        slope: f32,
        spp: u32,
    ) -> Result<Self, PatternError> {
        let ok = fovea_radius.is_finite()
            && fovea_radius >= 0.0
            && slope.is_finite()
            && slope >= 0.0
            && gaze.is_finite();
        if !ok {
            return Err(PatternError::BadFoveation {
                radius: fovea_radius,
                slope,
            });
        }
        let (w, h) = (camera.width() as f32, camera.height() as f32);
        let on_film = |p: Vec2| p.x >= 0.0 && p.x < w && p.y >= 0.0 && p.y < h;
        let mut set = Self::grid(camera, spp);
        set.samples.clear();
        // The fovea: the pixel grid inside the disc.
        let (x0, x1) = (
            (gaze.x - fovea_radius).floor().max(0.0) as u32,
            (gaze.x + fovea_radius).ceil().min(w) as u32,
        );
        let (y0, y1) = (
            (gaze.y - fovea_radius).floor().max(0.0) as u32,
            (gaze.y + fovea_radius).ceil().min(h) as u32,
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if (p - gaze).length() < fovea_radius {
                    set.samples.push(Sample {
                        film: p,
                        footprint: 1.0,
                        channel: 0,
                    });
                }
            }
        }
        // Rings out to the farthest film corner.
        let far = [
            Vec2::ZERO,
            Vec2::new(w, 0.0),
            Vec2::new(0.0, h),
            Vec2::new(w, h),
        ]
        .iter()
        .map(|c| (*c - gaze).length())
        .fold(0.0f32, f32::max);
        let footprint = |r: f32| 1.0 + slope * (r - fovea_radius).max(0.0);
        let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
        let mut r = fovea_radius + 0.5 * footprint(fovea_radius);
        let mut ring = 0u32;
        // Each ring advances r by >= 1, so this terminates within far + 1 rings.
        while r < far + 1.0 && ring < 1 << 20 {
            let f = footprint(r);
            let n = (std::f32::consts::TAU * r / f).ceil().max(1.0) as u32;
            let phase = ring as f32 * golden;
            for j in 0..n {
                let th = phase + std::f32::consts::TAU * j as f32 / n as f32;
                let p = gaze + Vec2::new(th.cos(), th.sin()) * r;
                if on_film(p) {
                    set.samples.push(Sample {
                        film: p,
                        footprint: f,
                        channel: 0,
                    });
                }
            }
            r += f;
            ring += 1;
        }
        Ok(set)
    }

    /// [`SampleSet::subsample_ray`] without the ray differentials the caster does not need: the
    /// same f32 operations as the camera models' `generate_ray` for the pinhole, stereo and
    /// thin-lens models (bit-identical rays, tested in `tests/cast.rs`), the full
    /// `generate_ray` for the others.
    #[inline]
    pub fn fast_subsample_ray(&self, i: usize, k: usize) -> Option<Ray> {
        let s = &self.samples[i];
        let film = s.film + self.offsets[k] * s.footprint;
        match &self.camera {
            Camera::Pinhole(p) => {
                let d = p.camera_dir(film);
                let len = d.length();
                Some(Ray::new(p.frame.position, p.frame.dir_to_world(d / len)))
            }
            Camera::Stereo(rig) => {
                let w = rig.eye_width() as f32;
                if !(film.x >= 0.0 && film.x <= 2.0 * w) {
                    return None;
                }
                let (p, film) = if film.x < w {
                    (&rig.eyes[0], film)
                } else {
                    (&rig.eyes[1], Vec2::new(film.x - w, film.y))
                };
                let d = p.camera_dir(film);
                let len = d.length();
                Some(Ray::new(p.frame.position, p.frame.dir_to_world(d / len)))
            }
            Camera::ThinLens(c) => {
                let frame = &c.pinhole.frame;
                let p_focus = c.pinhole.camera_dir(film) * c.focus_distance;
                let p_lens = c.lens_point(self.lens[k]);
                let d = p_focus - p_lens;
                let len = d.length();
                let dir = frame.dir_to_world(d / len);
                Some(Ray::new(frame.position + frame.dir_to_world(p_lens), dir))
            }
            _ => self.subsample_ray(i, k),
        }
    }
}

/// Foveated eye sets: fovea radius as a fraction of the eye's film height.
pub const FOVEA_RADIUS_FRACTION: f32 = 0.125;
/// Foveated eye sets: footprint growth per film pixel of eccentricity beyond the fovea (linear
/// acuity model, §2.3).
pub const FOVEA_SLOPE: f32 = 0.02;

/// The sample set of one headset eye: the pixel grid, or with `gaze` (normalised film
/// coordinates in `[-1, 1]^2`, y up) the foveated pattern around it ([`FOVEA_RADIUS_FRACTION`],
/// [`FOVEA_SLOPE`]). A per-channel (distorted) camera gets its three colour channels' rays with
/// `subpixel`, else only the green channel's, which then colour whole pixels.
pub fn eye_set(
    camera: Camera,
    spp: u32,
    subpixel: bool,
    gaze: Option<[f32; 2]>,
) -> Result<SampleSet, PatternError> {
    let channels = camera.channel_count() as u8;
    let mut set = match gaze {
        None => SampleSet::grid(camera, spp),
        Some([gx, gy]) => {
            if !(gx.abs() <= 1.0 && gy.abs() <= 1.0) {
                return Err(PatternError::BadGaze { x: gx, y: gy });
            }
            let (w, h) = (camera.width() as f32, camera.height() as f32);
            let film = Vec2::new((gx + 1.0) * 0.5 * w, (1.0 - gy) * 0.5 * h);
            let mut set =
                SampleSet::foveated(camera, film, FOVEA_RADIUS_FRACTION * h, FOVEA_SLOPE, spp)?;
            // The pattern is built for channel 0; give a per-channel camera all its channels.
            if channels > 1 {
                set.samples = set
                    .samples
                    .iter()
                    .flat_map(|s| (0..channels).map(move |c| Sample { channel: c, ..*s }))
                    .collect();
            }
            set
        }
    };
    if !subpixel && channels > 1 {
        set.samples.retain(|s| s.channel == 1);
    }
    Ok(set)
}
