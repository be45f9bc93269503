//! Lights. Emissive triangles are lights too: they come from materials with non-zero
//! `emissive` and are gathered by the renderer; the environment is [`crate::Scene::environment`].

use glam::Vec3;

/// An analytic light (glTF KHR_lights_punctual's three kinds).
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Radiant intensity `intensity` (W/sr, linear RGB) from a point.
    Point { position: Vec3, intensity: Vec3 },
    /// A point light restricted to a cone around `direction` with a smooth falloff between the
    /// inner and outer half-angles (radians).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_angle: f32,
        outer_angle: f32,
    },
    /// Irradiance `irradiance` (W/m^2) arriving along `direction` (the direction light travels).
    Directional { direction: Vec3, irradiance: Vec3 },
}
