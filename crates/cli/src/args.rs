//! Flags shared by every command that renders or measures a view: the scene and the camera.

use anyhow::{Context, Result, bail};
use clap::Args;
use glam::Vec3;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};

/// `--scene` and the camera flags of `render` (every `bench` command takes them too).
#[derive(Args, Clone, Debug)]
pub struct ViewArgs {
    /// A built-in scene name (see `parallax scenes`) or a .gltf / .glb / .obj / .ply file.
    #[arg(long, default_value = "atrium")]
    pub scene: String,
    /// A named camera of the scene (default: the scene's first camera).
    #[arg(long, conflicts_with_all = ["eye", "target"])]
    pub camera: Option<String>,
    /// Eye position: three values `--eye x y z`, or `--eye=x,y,z` (the `=` form is needed when
    /// the comma list starts with a minus sign).
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true)]
    pub eye: Option<Vec<f32>>,
    /// Look-at target: x,y,z.
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true, requires = "eye")]
    pub target: Option<Vec<f32>>,
    /// Up vector: x,y,z.
    #[arg(long, num_args = 1..=3, value_delimiter = ',', allow_negative_numbers = true, default_value = "0,1,0")]
    pub up: Vec<f32>,
    /// Vertical field of view in degrees (default: the named camera's, else 60).
    #[arg(long)]
    pub fov_y: Option<f32>,
    /// Camera model.
    #[arg(long, default_value = "pinhole", value_parser = parse_model)]
    pub model: ModelKind,
    /// Thin lens: aperture radius in metres.
    #[arg(long)]
    pub aperture: Option<f32>,
    /// Thin lens: focus distance in metres (default: distance to the target).
    #[arg(long)]
    pub focus: Option<f32>,
    /// Stereo: interpupillary distance in metres.
    #[arg(long, default_value_t = 0.065)]
    pub ipd: f32,
    /// Fisheye / equirect field of view: H,V degrees.
    #[arg(long, num_args = 1..=2, value_delimiter = ',')]
    pub fov: Option<Vec<f32>>,
}

fn parse_model(s: &str) -> Result<ModelKind, String> {
    ModelKind::parse(s).map_err(|e| e.to_string())
}

fn vec3(name: &str, v: &[f32]) -> Result<Vec3> {
    match v {
        [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
        _ => bail!("--{name} expects three numbers x,y,z, got {v:?}"),
    }
}

impl ViewArgs {
    /// Loads the scene named by `--scene`.
    pub fn load_scene(&self) -> Result<Scene> {
        Scene::load(&self.scene).with_context(|| format!("loading scene {:?}", self.scene))
    }

    /// The camera pose from `--camera` or `--eye/--target/--up/--fov-y`.
    pub fn camera_desc(&self, scene: &Scene) -> Result<CameraDesc> {
        let mut desc = match (&self.eye, &self.target) {
            (Some(eye), target) => {
                let eye = vec3("eye", eye)?;
                let target = match target {
                    Some(t) => vec3("target", t)?,
                    None => bail!("--eye needs --target"),
                };
                CameraDesc::new(eye, target, vec3("up", &self.up)?, 60.0)
            }
            (None, _) => scene.camera(self.camera.as_deref())?,
        };
        if let Some(f) = self.fov_y {
            desc.fov_y_deg = f;
        }
        desc.validate()?;
        Ok(desc)
    }

    /// The camera model options from the flags.
    pub fn camera_options(&self) -> Result<CameraOptions> {
        let mut o = CameraOptions {
            ipd: self.ipd,
            focus_distance: self.focus,
            ..CameraOptions::default()
        };
        if let Some(a) = self.aperture {
            o.aperture_radius = a;
        }
        if let Some(f) = &self.fov {
            o.fov_deg = Some(match f.as_slice() {
                [h, v] => glam::Vec2::new(*h, *v),
                [h] => glam::Vec2::new(*h, *h),
                _ => bail!("--fov expects H,V degrees"),
            });
        }
        Ok(o)
    }

    /// The camera for a `width x height` film.
    pub fn camera(&self, scene: &Scene, width: u32, height: u32) -> Result<Camera> {
        let desc = self.camera_desc(scene)?;
        Ok(Camera::new(
            self.model,
            &desc,
            width,
            height,
            &self.camera_options()?,
        )?)
    }
}
