//! Materials.

use glam::Vec3;

/// How a surface scatters light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialKind {
    /// Metallic-roughness GGX (glTF's PBR model): Lambert base + GGX specular.
    Standard,
    /// A perfect mirror tinted by the base colour.
    Mirror,
    /// A smooth dielectric (glass) with index of refraction `ior`.
    Dielectric { ior: f32 },
}

/// A surface material (glTF metallic-roughness, plus mirror and dielectric).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    /// Linear RGB base colour (multiplied by the texture, if any).
    pub base_color: Vec3,
    /// Index into [`crate::Scene::textures`].
    pub base_color_texture: Option<u32>,
    /// Perceptual roughness in [0, 1] (GGX alpha = roughness^2).
    pub roughness: f32,
    pub metallic: f32,
    /// Emitted radiance (W / sr / m^2, linear RGB); non-zero makes the triangles area lights.
    pub emissive: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            kind: MaterialKind::Standard,
            base_color: Vec3::splat(0.8),
            base_color_texture: None,
            roughness: 0.5,
            metallic: 0.0,
            emissive: Vec3::ZERO,
        }
    }
}

impl Material {
    /// A diffuse (rough, non-metallic) material.
    pub fn diffuse(name: &str, color: Vec3) -> Self {
        Self {
            name: name.into(),
            base_color: color,
            roughness: 1.0,
            ..Self::default()
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emissive.max_element() > 0.0
    }
}
