//! Materials.
//!
//! | field | type | default | meaning |
//! |---|---|---|---|
//! | `kind` | [`MaterialKind`] | `Standard` | scattering model |
//! | `base_color` | Vec3 | 0.8 | linear RGB albedo (times the texture) |
//! | `base_color_texture` | `Option<u32>` | none | index into the scene's textures |
//! | `roughness` | f32 | 0.5 | perceptual roughness (GGX alpha = roughness^2) |
//! | `metallic` | f32 | 0 | glTF metalness |
//! | `emissive` | Vec3 | 0 | emitted radiance (area light when non-zero) |
//! | `alpha_mode` | [`AlphaMode`] | `Opaque` | glTF `alphaMode` (`alphaCutoff` in `Mask`) |
//! | `alpha` | f32 | 1 | glTF `baseColorFactor` alpha (coverage) |
//! | `transmission` | f32 | 0 | `KHR_materials_transmission` factor |
//!
//! [`Material::is_glass`] names the glTF convention for glass that renderers without a
//! transparency model map to a thin dielectric: a `Blend` material with alpha below 0.5, or any
//! transmission.

use glam::Vec3;

/// glTF's `alphaMode`: how the base colour's alpha covers the surface.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    /// Alpha ignored; the surface is opaque.
    #[default]
    Opaque,
    /// Covered where alpha >= `cutoff` (glTF default 0.5), a hole elsewhere.
    Mask { cutoff: f32 },
    /// Alpha blended: alpha is the fraction of light the surface covers.
    Blend,
}

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
    /// glTF `alphaMode` (with `alphaCutoff`).
    pub alpha_mode: AlphaMode,
    /// Alpha of the base colour factor in [0, 1].
    pub alpha: f32,
    /// `KHR_materials_transmission` factor in [0, 1] (0 without the extension).
    pub transmission: f32,
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
            alpha_mode: AlphaMode::Opaque,
            alpha: 1.0,
            transmission: 0.0,
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

    /// glTF glass: alpha-blended with alpha below 0.5, or transmissive
    /// (`KHR_materials_transmission` > 0).
    pub fn is_glass(&self) -> bool {
        (self.alpha_mode == AlphaMode::Blend && self.alpha < 0.5) || self.transmission > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glass_is_blend_below_half_or_transmissive() {
        let mut m = Material::default();
        assert!(!m.is_glass());
        m.alpha = 0.1;
        assert!(!m.is_glass(), "alpha alone does not matter when opaque");
        m.alpha_mode = AlphaMode::Blend;
        assert!(m.is_glass());
        m.alpha = 0.5;
        assert!(!m.is_glass());
        m.transmission = 0.3;
        assert!(m.is_glass());
    }
}
