//! The scene: geometry, materials, lights, cameras. Loading ([`Scene::load`]) lives in
//! [`crate::load`], so that this file depends on no loader.

use glam::Vec3;
use parallax_core::Aabb;

use crate::camera_desc::{CameraDesc, NamedCamera};
use crate::{CameraPath, Light, Material, Result, SceneError, Texture, TriangleMesh};

/// A glTF animation or skin, parsed for later use (listed by `parallax info`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationInfo {
    pub name: String,
    /// Number of channels (animation) or joints (skin).
    pub channels: usize,
    pub is_skin: bool,
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
    pub animations: Vec<AnimationInfo>,
    /// The glTF node animation and skins that pose `mesh` over time (glTF files with
    /// animations or skinned meshes; see [`crate::skin`]).
    pub gltf_animation: Option<std::sync::Arc<crate::skin::GltfAnimation>>,
    /// True when [`Scene::add_default_lighting_if_unlit`] gave the scene its lights (the file
    /// carried none), so that renderers can say so.
    pub default_lighting: bool,
}

impl Scene {
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
            None => match self.cameras.first() {
                Some(c) => Ok(c.desc),
                None => {
                    let desc = self.framing_camera();
                    if desc.eye.is_finite() {
                        Ok(desc)
                    } else {
                        let b = self.bounds();
                        Err(SceneError::Camera(format!(
                            "scene {:?} spans {} to {}: too large to frame a default camera in \
                             f32; give one with --eye and --target",
                            self.name, b.min, b.max
                        )))
                    }
                }
            },
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
        let emissive = Material {
            emissive: Vec3::ONE,
            ..Material::default()
        };
        let mut e = Scene {
            materials: vec![emissive],
            ..Scene::default()
        };
        e.add_default_lighting_if_unlit();
        assert!(e.lights.is_empty() && e.environment == Vec3::ZERO && !e.default_lighting);
    }

    /// A scene of one triangle with corners at `±x`.
    fn one_triangle(x: f32) -> Scene {
        Scene {
            mesh: TriangleMesh {
                positions: vec![Vec3::new(-x, 0.0, 0.0), Vec3::new(x, 0.0, 0.0), Vec3::Y * x],
                indices: vec![[0, 1, 2]],
                material_ids: vec![0],
                ..TriangleMesh::default()
            },
            materials: vec![Material::default()],
            ..Scene::default()
        }
    }

    #[test]
    fn the_default_camera_frames_the_bounds_or_says_it_cannot() {
        let c = one_triangle(2.0).camera(None).unwrap();
        assert!(c.eye.is_finite() && c.eye.z > 0.0 && c.target == Vec3::new(0.0, 1.0, 0.0));
        // Corners near f32::MAX: the framing distance overflows.
        match one_triangle(1e38).camera(None) {
            Err(SceneError::Camera(m)) => assert!(m.contains("too large"), "{m}"),
            other => panic!("expected a camera error, got {other:?}"),
        }
    }
}
