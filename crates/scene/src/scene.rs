//! The scene: geometry, materials, lights, cameras.

use std::path::Path;

use glam::Vec3;
use parallax_core::Aabb;

use crate::{CameraPath, Light, Material, Result, SceneError, Texture, TriangleMesh};

/// A look-at camera pose with a vertical field of view: what `--eye --target --up --fov-y`
/// and the named cameras of a scene describe. Camera models are built from it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees (pinhole-like models).
    pub fov_y_deg: f32,
}

impl CameraDesc {
    pub fn new(eye: Vec3, target: Vec3, up: Vec3, fov_y_deg: f32) -> Self {
        Self {
            eye,
            target,
            up,
            fov_y_deg,
        }
    }

    /// Checks the pose: finite, target distinct from eye, up not parallel to the view direction,
    /// field of view in (0, 180).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: &str| Err(SceneError::Camera(m.to_string()));
        if !(self.eye.is_finite() && self.target.is_finite() && self.up.is_finite()) {
            return bad("eye, target and up must be finite");
        }
        let f = self.target - self.eye;
        if f.length_squared() <= 1e-20 {
            return bad("target must differ from eye");
        }
        if f.normalize()
            .cross(self.up.normalize_or_zero())
            .length_squared()
            < 1e-10
        {
            return bad("up must not be parallel to the view direction");
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return bad("fov-y must be in (0, 180) degrees");
        }
        Ok(())
    }
}

/// A camera the scene file or built-in scene names.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedCamera {
    pub name: String,
    pub desc: CameraDesc,
}

/// Everything that is rendered. Geometry is one world-space [`TriangleMesh`].
#[derive(Clone, Debug, Default)]
pub struct Scene {
    pub name: String,
    pub mesh: TriangleMesh,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    /// Constant environment radiance seen by rays that leave the scene.
    pub environment: Vec3,
    /// Named cameras; the first is the default.
    pub cameras: Vec<NamedCamera>,
    /// The default camera path (60 frames for the built-ins).
    pub camera_path: Option<CameraPath>,
    /// glTF skins and animations, listed.
    pub animations: Vec<crate::load::AnimationInfo>,
    /// The glTF node animation and skins that pose `mesh` over time (glTF files with
    /// animations or skinned meshes; see [`crate::skin`]).
    pub gltf_animation: Option<std::sync::Arc<crate::skin::GltfAnimation>>,
    /// True when [`Scene::add_default_lighting_if_unlit`] gave the scene its lights (the file
    /// carried none), so that renderers can say so.
    pub default_lighting: bool,
}

impl Scene {
    /// A built-in scene by name, or a scene file (.gltf, .glb, .obj, .ply) by path.
    pub fn load(name_or_path: &str) -> Result<Scene> {
        if let Some(scene) = crate::builtin::by_name(name_or_path) {
            return Ok(scene);
        }
        let path = Path::new(name_or_path);
        if path.extension().is_none() && !path.exists() {
            return Err(SceneError::UnknownScene {
                name: name_or_path.to_string(),
                known: crate::builtin::NAMES.join(", "),
            });
        }
        crate::load::load_file(path)
    }

    /// Bounds of all geometry.
    pub fn bounds(&self) -> Aabb {
        self.mesh.bounds()
    }

    /// The named camera, or the first one, or a default framing of the bounds.
    pub fn camera(&self, name: Option<&str>) -> Result<CameraDesc> {
        match name {
            Some(n) => self
                .cameras
                .iter()
                .find(|c| c.name == n)
                .map(|c| c.desc)
                .ok_or_else(|| {
                    let known: Vec<_> = self.cameras.iter().map(|c| c.name.as_str()).collect();
                    SceneError::Camera(format!(
                        "scene {:?} has no camera {n:?}; it has: {}",
                        self.name,
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ))
                }),
            None => Ok(self
                .cameras
                .first()
                .map(|c| c.desc)
                .unwrap_or_else(|| self.framing_camera())),
        }
    }

    /// A camera that looks at the whole scene from the +z side, 45 degrees vertical FoV.
    pub fn framing_camera(&self) -> CameraDesc {
        let b = self.bounds();
        let (c, r) = if b.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (b.center(), 0.5 * b.extent().length().max(1e-3))
        };
        let dist = r / (22.5f32.to_radians()).sin();
        CameraDesc::new(c + Vec3::new(0.0, 0.3 * r, dist), c, Vec3::Y, 45.0)
    }

    /// True when nothing in the scene emits light: no analytic lights, no emissive material,
    /// black environment.
    pub fn is_unlit(&self) -> bool {
        self.lights.is_empty()
            && self.environment.max_element() <= 0.0
            && !self.materials.iter().any(|m| m.is_emissive())
    }

    /// Scene files often carry no lights (Sponza, the classroom, scans): rendering them as
    /// they are gives a black image. Such scenes get a default rig instead — a white sky
    /// (radiance 0.5) and a sun from high above (about 70 degrees elevation, irradiance 3) — and keep
    /// it visible in `parallax info`. Scenes with any light are left as they are.
    pub fn add_default_lighting_if_unlit(&mut self) {
        if self.is_unlit() {
            self.default_lighting = true;
            self.environment = Vec3::splat(0.5);
            let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
            self.lights.push(Light::Directional {
                direction,
                irradiance: Vec3::splat(3.0),
            });
        }
    }

    /// Checks the scene invariants (see the crate docs).
    pub fn validate(&self) -> std::result::Result<(), String> {
        self.mesh.validate(self.materials.len())?;
        for (i, m) in self.materials.iter().enumerate() {
            if let Some(t) = m.base_color_texture
                && t as usize >= self.textures.len()
            {
                return Err(format!(
                    "material {i} ({}) uses missing texture {t}",
                    m.name
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unlit_scenes_get_the_default_rig_and_lit_ones_are_untouched() {
        let mut s = Scene {
            materials: vec![Material::default()],
            ..Scene::default()
        };
        assert!(s.is_unlit());
        s.add_default_lighting_if_unlit();
        assert!(!s.is_unlit() && s.default_lighting);
        assert_eq!(s.lights.len(), 1);
        s.add_default_lighting_if_unlit();
        assert_eq!(s.lights.len(), 1, "a lit scene is left as it is");
        let mut emissive = Material::default();
        emissive.emissive = Vec3::ONE;
        let mut e = Scene {
            materials: vec![emissive],
            ..Scene::default()
        };
        e.add_default_lighting_if_unlit();
        assert!(e.lights.is_empty() && e.environment == Vec3::ZERO && !e.default_lighting);
    }
}
