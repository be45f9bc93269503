//! The sequences the reprojection is measured on (Mäkitalo et al. 2019, §4: "seven
//! stereoscopic test scenes, each having 60 frames with 720p resolution for each eye, and a
//! moving observer"): a scene, a 60-frame camera path for the head (the eyes are a parallel
//! rig around it), and a variant.
//!
//! | scene | path (2 s at 30 fps) | paper's motion |
//! |---|---|---|
//! | `sponza_dabrovic` | backward along the nave with a slight sideways curve, eye 2.2-2.5 m high | "smoothly curved backward movement" |
//! | `japanese_classroom` | from the back of the room, panning 30 degrees across the front while drifting sideways | "smoothly curved panning" |
//! | built-in scenes with a path (atrium, cornell, foliage) | the scene's own path | - |
//! | any other scene | backward dolly from its default camera by 15 % of the target distance, curving sideways by 5 % | - |
//!
//! | [`Variant`] | change |
//! |---|---|
//! | `base` | the scene as it is (the default sky and sun if it has no light) |
//! | `glossy` | GGX roughness 0.2 on the materials that cover the largest half of the surface area ("Sponza (Glossy)") |
//! | `moving-light` | the analytic lights replaced by one point light moving along a keyframed path through the view (environment kept) |
//! | `moving-objects` | the scene's props move ([`Animation::for_scene`]: rigid spin and bob, or the file's own clips), the BVH is refit every frame |
//!
//! **Invariant:** a dataset's frame `f` is a function of `f` alone (poses are computed from the
//! time, never accumulated), so any frame can be rendered on its own.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_core::WorldTracer;
use parallax_scene::animation::Animation;
use parallax_scene::camera::CameraFrame;
use parallax_scene::path::{CameraKey, CameraPath};
use parallax_scene::{CameraDesc, Light, Scene};

use super::error::{ReprojectError, Result, option_error};

/// Frames per second and length of the sequences defined here (the paper's 60 frames).
pub const FPS: f32 = 30.0;
pub const FRAMES: u32 = 60;

/// A change of the scene (module table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Variant {
    Base,
    Glossy,
    MovingLight,
    MovingObjects,
}

impl Variant {
    pub const ALL: [Variant; 4] = [
        Variant::Base,
        Variant::Glossy,
        Variant::MovingLight,
        Variant::MovingObjects,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Variant::Base => "base",
            Variant::Glossy => "glossy",
            Variant::MovingLight => "moving-light",
            Variant::MovingObjects => "moving-objects",
        }
    }

    pub fn parse(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                ReprojectError::Option(format!(
                    "unknown variant {s:?}; expected one of {}",
                    Self::ALL.map(|v| v.name()).join(", ")
                ))
            })
    }
}

/// What a sequence runner needs of a scene at each frame.
pub trait FrameWorld {
    /// Frames of the sequence.
    fn frames(&self) -> u32;
    /// Poses the scene (lights, geometry) for frame `f`.
    fn pose(&mut self, f: u32) -> Result<()>;
    /// The scene as posed.
    fn scene(&self) -> &Scene;
    /// The tracer of the scene as posed.
    fn tracer(&self) -> &dyn WorldTracer;
    /// The head camera (centre of the eyes) of frame `f`.
    fn head(&self, f: u32) -> CameraDesc;
    /// True when [`Self::pose`] moves geometry (content hashes must be taken per frame).
    fn geometry_moves(&self) -> bool {
        false
    }
    /// A name for tables: scene, and the variant unless it is the base.
    fn label(&self) -> String;
}

/// A point light moving along straight segments between keys (time, position).
#[derive(Clone, Debug, PartialEq)]
pub struct LightTrack {
    pub keys: Vec<(f32, Vec3)>,
    pub intensity: Vec3,
}

impl LightTrack {
    /// The position at time `t` (clamped to the keys).
    pub fn at(&self, t: f32) -> Vec3 {
        let k = &self.keys;
        if t <= k[0].0 {
            return k[0].1;
        }
        for w in k.windows(2) {
            if t <= w[1].0 {
                let s = (t - w[0].0) / (w[1].0 - w[0].0).max(1e-9);
                return w[0].1.lerp(w[1].1, s);
            }
        }
        k[k.len() - 1].1
    }
}

/// A scene, its head path, its variant and its BVH (module docs).
pub struct Dataset {
    pub scene: Scene,
    pub path: CameraPath,
    pub variant: Variant,
    pub light: Option<LightTrack>,
    /// The props' motion of [`Variant::MovingObjects`].
    pub animation: Option<Animation>,
    bvh: Bvh,
}

fn keys(path: &[(f32, Vec3, Vec3)], fov: f32) -> CameraPath {
    CameraPath::new(
        path.iter()
            .map(|&(time, eye, target)| CameraKey {
                time,
                camera: CameraDesc::new(eye, target, Vec3::Y, fov),
            })
            .collect(),
        FPS,
        FRAMES,
    )
}

/// The head path of `scene` (module table).
pub fn head_path(scene: &Scene) -> Result<CameraPath> {
    Ok(match scene.name.as_str() {
        "sponza_dabrovic" => keys(
            &[
                (0.0, Vec3::new(2.0, 2.2, 0.6), Vec3::new(12.0, 3.2, -0.4)),
                (1.0, Vec3::new(-2.5, 2.5, -0.2), Vec3::new(9.0, 3.5, 0.3)),
                (2.0, Vec3::new(-7.0, 2.4, 0.5), Vec3::new(6.0, 3.0, 0.8)),
            ],
            60.0,
        ),
        "japanese_classroom" => keys(
            &[
                (0.0, Vec3::new(2.8, 1.5, 5.0), Vec3::new(-2.5, 1.2, -5.5)),
                (1.0, Vec3::new(2.0, 1.55, 5.2), Vec3::new(0.0, 1.1, -5.5)),
                (2.0, Vec3::new(1.0, 1.5, 5.0), Vec3::new(2.5, 1.2, -5.5)),
            ],
            60.0,
        ),
        _ => match &scene.camera_path {
            Some(p) => p.clone(),
            None => dolly_path(&scene.camera(None)?)?,
        },
    })
}

/// A backward dolly from `d` by 15 % of its target distance, curving sideways by 5 %
/// (module table: the path of scenes without one, and of a camera given on the command line).
pub fn dolly_path(d: &CameraDesc) -> Result<CameraPath> {
    let f = CameraFrame::look_at(d)?;
    let back = f.forward() * (-0.15 * (d.target - d.eye).length());
    let side = f.right() * (0.05 * (d.target - d.eye).length());
    Ok(keys(
        &[
            (0.0, d.eye, d.target),
            (1.0, d.eye + back * 0.5 + side, d.target + side * 0.5),
            (2.0, d.eye + back, d.target),
        ],
        d.fov_y_deg,
    ))
}

/// The moving light of `scene` (module table): along the view of the path's first frame, 1.2x
/// the eye height above the floor of the view, from one side of the first view to the other
/// over the sequence; intensity so that it gives about the sun's irradiance (3 W/m²) at half
/// the distance to the first target.
pub fn moving_light(path: &CameraPath) -> Result<LightTrack> {
    let d0 = path.frame(0);
    let f = CameraFrame::look_at(&d0)?;
    let dist = (d0.target - d0.eye).length();
    let centre = d0.eye + f.forward() * (0.5 * dist) + Vec3::Y * (0.4 * d0.eye.y.abs().max(0.5));
    let side = f.right() * (0.35 * dist);
    let t0 = path.keys[0].time;
    let t1 = t0 + path.frames as f32 / path.fps;
    let r = 0.5 * dist;
    Ok(LightTrack {
        keys: vec![(t0, centre - side), (t1, centre + side)],
        intensity: Vec3::new(1.0, 0.9, 0.75) * (3.0 * r * r),
    })
}

/// Roughness 0.2 on the materials covering the largest half of the triangle area.
fn make_glossy(scene: &mut Scene) {
    let mut area = vec![0.0f64; scene.materials.len()];
    for (t, &m) in scene.mesh.material_ids.iter().enumerate() {
        let [a, b, c] = scene.mesh.triangle(t);
        area[m as usize] += 0.5 * (b - a).cross(c - a).length() as f64;
    }
    let total: f64 = area.iter().sum();
    let mut order: Vec<usize> = (0..area.len()).collect();
    order.sort_by(|&a, &b| area[b].total_cmp(&area[a]).then(a.cmp(&b)));
    let mut covered = 0.0;
    for m in order {
        if covered >= 0.5 * total {
            break;
        }
        covered += area[m];
        let mat = &mut scene.materials[m];
        if !mat.is_emissive() {
            mat.roughness = 0.2;
        }
    }
}

impl Dataset {
    /// The dataset of `scene` in `variant`; scenes without light get the default sky first.
    pub fn new(scene: Scene, variant: Variant) -> Result<Self> {
        Self::with_head(scene, variant, None)
    }

    /// As [`Self::new`]; a given `head` camera replaces the scene's path by [`dolly_path`]
    /// from it.
    pub fn with_head(mut scene: Scene, variant: Variant, head: Option<CameraDesc>) -> Result<Self> {
        scene.add_default_lighting_if_unlit();
        let path = match head {
            Some(d) => dolly_path(&d)?,
            None => head_path(&scene)?,
        };
        let light = match variant {
            Variant::MovingLight => Some(moving_light(&path)?),
            _ => None,
        };
        if variant == Variant::Glossy {
            make_glossy(&mut scene);
        }
        let animation = (variant == Variant::MovingObjects).then(|| Animation::for_scene(&scene));
        let bvh = Bvh::try_build(&scene.mesh).map_err(|e| ReprojectError::Bvh(e.to_string()))?;
        Ok(Self {
            scene,
            path,
            variant,
            light,
            animation,
            bvh,
        })
    }

    /// Time of frame `f` (seconds).
    pub fn time(&self, f: u32) -> f32 {
        self.path.keys[0].time + f as f32 / self.path.fps
    }

    /// Checks that a run of `frames` frames fits the path.
    pub fn check_frames(&self, frames: u32) -> Result<()> {
        if frames == 0 || frames > self.path.frames {
            return option_error(format!(
                "--frames must be in 1..={} (the length of {}'s path), got {frames}",
                self.path.frames, self.scene.name
            ));
        }
        Ok(())
    }
}

impl FrameWorld for Dataset {
    fn frames(&self) -> u32 {
        self.path.frames
    }

    fn pose(&mut self, f: u32) -> Result<()> {
        if let Some(track) = &self.light {
            self.scene.lights = vec![Light::Point {
                position: track.at(self.time(f)),
                intensity: track.intensity,
            }];
        }
        let t = self.time(f);
        if let Some(anim) = &self.animation {
            anim.apply(&mut self.scene.mesh, t)
                .map_err(|e| ReprojectError::Bvh(format!("posing frame {f}: {e}")))?;
            self.bvh
                .refit(&self.scene.mesh)
                .map_err(|e| ReprojectError::Bvh(e.to_string()))?;
        }
        Ok(())
    }

    fn scene(&self) -> &Scene {
        &self.scene
    }

    fn tracer(&self) -> &dyn WorldTracer {
        &self.bvh
    }

    fn head(&self, f: u32) -> CameraDesc {
        self.path.frame(f)
    }

    fn geometry_moves(&self) -> bool {
        self.animation.is_some()
    }

    fn label(&self) -> String {
        match self.variant {
            Variant::Base => self.scene.name.clone(),
            v => format!("{} ({})", self.scene.name, v.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_parse_and_change_what_they_say() {
        assert_eq!(Variant::parse("glossy").unwrap(), Variant::Glossy);
        assert!(
            Variant::parse("shiny")
                .unwrap_err()
                .to_string()
                .contains("base")
        );
        let base = Dataset::new(Scene::load("atrium").unwrap(), Variant::Base).unwrap();
        assert_eq!(base.frames(), 60);
        let glossy = Dataset::new(Scene::load("atrium").unwrap(), Variant::Glossy).unwrap();
        assert!(glossy.scene.materials.iter().any(|m| m.roughness == 0.2));
        let mut moving =
            Dataset::new(Scene::load("atrium").unwrap(), Variant::MovingLight).unwrap();
        moving.pose(0).unwrap();
        let p0 = moving.scene.lights.clone();
        moving.pose(59).unwrap();
        assert_eq!(moving.scene.lights.len(), 1);
        assert_ne!(p0, moving.scene.lights);
        assert!(moving.check_frames(61).is_err() && moving.check_frames(0).is_err());
    }
}
