//! Headset presets (Hunt et al. 2018, §2 and Table 5): per-eye film, field of view, lens
//! (pre-)distortion and eye separation, and the two eye cameras of a head pose.
//!
//! | preset | per-eye film | model | field of view | distortion (R, G, B `(k1, k2)`) | IPD |
//! |---|---|---|---|---|---|
//! | `rift-cv1` | 1080 x 1200 | distorted | vertical edge half-tangent 1.33 (~106 deg) | (0.20, 0.22) (0.22, 0.24) (0.24, 0.26) | 0.064 |
//! | `vive` | 1080 x 1200 | distorted | vertical edge half-tangent 1.39 (~108 deg) | (0.23, 0.28) (0.25, 0.30) (0.27, 0.32) | 0.064 |
//! | `wide-210x130` | 1080 x 1200 | fisheye | 210 x 130 deg | - | 0.064 |
//! | `custom` | flags | flags | flags | flags | flags |
//!
//! **Simplified / approximate.** The field of view of the Rift CV1 is the Oculus SDK's default
//! eye-buffer tangents (up = down = 1.33, left/right ~1.06-1.09); the Vive's is its nominal
//! 110 deg class. The distortion is a two-coefficient radial polynomial (the
//! [`Distorted`](parallax_scene::camera::Distorted) model, display radius -> tangent radius),
//! chosen so that the green channel maps the display's vertical edge to the eye-buffer edge
//! tangent; it is *not* the SDK's Catmull-Rom spline, the lens centre is the display centre
//! (real lenses sit off-centre towards the nose), and the chromatic spread (+-0.02 per channel)
//! is a plausible magnitude, not a measured one. The centre field of view follows:
//! `tan(fov_y / 2) = edge_tan / (1 + k1_G + k2_G)`.
//!
//! Depth of field ([`Dof`]) replaces the eye model with a thin lens at the preset's centre field
//! of view: the camera models are a closed set and the thin lens has no lens distortion, so a
//! DoF render of a distorted preset is rendered undistorted (said in [`eye_cameras`]).

use glam::Vec2;
use parallax_scene::camera::{Camera, CameraOptions, Eye, ModelKind, eye_camera};
use parallax_scene::{CameraDesc, SceneError};

/// A named headset configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Preset {
    RiftCv1,
    Vive,
    Wide210x130,
    Custom,
}

impl Preset {
    pub const ALL: [Preset; 4] = [
        Preset::RiftCv1,
        Preset::Vive,
        Preset::Wide210x130,
        Preset::Custom,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Preset::RiftCv1 => "rift-cv1",
            Preset::Vive => "vive",
            Preset::Wide210x130 => "wide-210x130",
            Preset::Custom => "custom",
        }
    }

    pub fn parse(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|p| p.name()).collect();
                format!("unknown preset {s:?}; expected one of {}", names.join(", "))
            })
    }

    /// The preset's headset; `custom` gives a 1080 x 1200 pinhole at 90 deg vertical that the
    /// caller overrides from its flags.
    pub fn spec(self) -> HeadsetSpec {
        let distorted = |edge_tan: f32, coeffs: [[f32; 2]; 3]| {
            let [k1, k2] = coeffs[1];
            let fov_y = 2.0 * (edge_tan / (1.0 + k1 + k2)).atan().to_degrees();
            HeadsetSpec {
                name: self.name().into(),
                width: 1080,
                height: 1200,
                model: ModelKind::Distorted,
                fov_y_deg: fov_y,
                fov_deg: None,
                distortion: coeffs,
                ipd: 0.064,
            }
        };
        match self {
            Preset::RiftCv1 => distorted(1.33, [[0.20, 0.22], [0.22, 0.24], [0.24, 0.26]]),
            Preset::Vive => distorted(1.39, [[0.23, 0.28], [0.25, 0.30], [0.27, 0.32]]),
            Preset::Wide210x130 => HeadsetSpec {
                name: self.name().into(),
                width: 1080,
                height: 1200,
                model: ModelKind::Fisheye,
                fov_y_deg: 90.0,
                fov_deg: Some(Vec2::new(210.0, 130.0)),
                distortion: [[0.0; 2]; 3],
                ipd: 0.064,
            },
            Preset::Custom => HeadsetSpec {
                name: self.name().into(),
                width: 1080,
                height: 1200,
                model: ModelKind::Pinhole,
                fov_y_deg: 90.0,
                fov_deg: None,
                distortion: CameraOptions::default().distortion,
                ipd: 0.064,
            },
        }
    }
}

/// Everything that defines one eye's view apart from the head pose.
#[derive(Clone, Debug, PartialEq)]
pub struct HeadsetSpec {
    pub name: String,
    /// Film of one eye.
    pub width: u32,
    pub height: u32,
    /// Eye camera model (distorted, fisheye, pinhole, ...).
    pub model: ModelKind,
    /// Vertical field of view of the undistorted centre (pinhole-like models).
    pub fov_y_deg: f32,
    /// Angular field of view H x V of the fisheye / equirect.
    pub fov_deg: Option<Vec2>,
    /// Per-channel radial coefficients of the distorted model.
    pub distortion: [[f32; 2]; 3],
    /// Eye separation (m).
    pub ipd: f32,
}

/// Thin-lens depth of field: aperture *diameter* (a pupil, HVVR's Table 5 uses 3 mm) and the
/// focus distance, both in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dof {
    pub aperture: f32,
    pub focus: f32,
}

impl Dof {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.aperture.is_finite() && self.aperture >= 0.0) {
            return Err(format!(
                "DoF aperture must be finite and >= 0 m, got {}",
                self.aperture
            ));
        }
        if !(self.focus.is_finite() && self.focus > 0.0) {
            return Err(format!(
                "DoF focus distance must be finite and > 0 m, got {}",
                self.focus
            ));
        }
        Ok(())
    }
}

/// The left and right eye cameras of `spec` for head pose `head` (eyes `±ipd/2` along the
/// head's right axis, parallel axes), with depth of field when `dof` is given (a thin lens at
/// the spec's centre field of view — undistorted, see the module docs).
pub fn eye_cameras(
    spec: &HeadsetSpec,
    head: &CameraDesc,
    dof: Option<Dof>,
) -> Result<[Camera; 2], SceneError> {
    let mut desc = *head;
    desc.fov_y_deg = spec.fov_y_deg;
    let mut opts = CameraOptions {
        fov_deg: spec.fov_deg,
        distortion: spec.distortion,
        ipd: spec.ipd,
        ..CameraOptions::default()
    };
    let mut model = spec.model;
    if let Some(d) = dof {
        d.validate().map_err(SceneError::Camera)?;
        model = ModelKind::ThinLens;
        opts.aperture_radius = 0.5 * d.aperture;
        opts.focus_distance = Some(d.focus);
    }
    let make = |eye: Eye| -> Result<Camera, SceneError> {
        let e = eye_camera(&desc, spec.ipd, eye)?;
        Camera::new(model, &e, spec.width, spec.height, &opts)
    };
    Ok([make(Eye::Left)?, make(Eye::Right)?])
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use parallax_scene::camera::CameraModel;

    fn head() -> CameraDesc {
        CameraDesc::new(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 60.0)
    }

    #[test]
    fn presets_parse_and_build_both_eyes() {
        for p in Preset::ALL {
            assert_eq!(Preset::parse(p.name()), Ok(p));
            let [l, r] = eye_cameras(&p.spec(), &head(), None).unwrap();
            assert_eq!((l.width(), l.height()), (1080, 1200));
            // The eyes sit ipd apart along +x (the head's right).
            let c = Vec2::new(540.0, 600.0);
            let ol = l.generate_ray(c, Vec2::splat(0.5), 1).unwrap().ray.origin;
            let or = r.generate_ray(c, Vec2::splat(0.5), 1).unwrap().ray.origin;
            assert!(
                ((or - ol) - Vec3::X * 0.064).length() < 1e-6,
                "{}",
                p.name()
            );
        }
        assert!(Preset::parse("quest").is_err());
    }

    #[test]
    fn rift_edge_tangent_matches_the_fit() {
        let [l, _] = eye_cameras(&Preset::RiftCv1.spec(), &head(), None).unwrap();
        // The top edge at the horizontal centre, green channel.
        let d = l
            .generate_ray(Vec2::new(540.0, 0.0), Vec2::splat(0.5), 1)
            .unwrap()
            .ray
            .dir;
        assert!((d.y / -d.z - 1.33).abs() < 1e-3, "{d}");
    }

    #[test]
    fn dof_is_a_thin_lens_and_rejects_negative_apertures() {
        let dof = Dof {
            aperture: 0.003,
            focus: 0.5,
        };
        let [l, _] = eye_cameras(&Preset::RiftCv1.spec(), &head(), Some(dof)).unwrap();
        assert_eq!(l.kind(), ModelKind::ThinLens);
        let bad = Dof {
            aperture: -0.1,
            focus: 0.5,
        };
        assert!(eye_cameras(&Preset::RiftCv1.spec(), &head(), Some(bad)).is_err());
    }
}
