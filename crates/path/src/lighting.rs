//! The lights a render uses: the scene's own, the cross-renderer overrides (`--env`,
//! `--point`), or the default sky for scenes that carry no light at all.
//!
//! | override | meaning | Mitsuba 3 equivalent |
//! |---|---|---|
//! | `env` | constant environment radiance (linear RGB) | `constant` emitter, `radiance` |
//! | `points` | point lights: position, radiant intensity (W/sr, linear RGB) | `point` emitter, `intensity` |
//!
//! Any override replaces the scene's analytic lights and environment (emissive surfaces stay):
//! both renderers of a cross-check then see exactly the listed lights.

use glam::Vec3;
use parallax_scene::{Light, Scene};

use crate::error::{PathError, Result};

/// `--env` and `--point`/`--point-intensity`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightOverrides {
    pub env: Option<Vec3>,
    /// `(position, intensity)` of each point light.
    pub points: Vec<(Vec3, Vec3)>,
}

impl LightOverrides {
    pub fn is_empty(&self) -> bool {
        self.env.is_none() && self.points.is_empty()
    }

    /// Checks the values: radiance and intensity finite and non-negative, positions finite.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(PathError::Light(m));
        if let Some(e) = self.env
            && !(e.is_finite() && e.min_element() >= 0.0)
        {
            return bad(format!(
                "--env radiance must be finite and non-negative, got {e}"
            ));
        }
        for (p, i) in &self.points {
            if !p.is_finite() {
                return bad(format!("--point position must be finite, got {p}"));
            }
            if !(i.is_finite() && i.min_element() >= 0.0) {
                return bad(format!(
                    "--point-intensity must be finite and non-negative, got {i}"
                ));
            }
        }
        Ok(())
    }
}

/// What [`apply_lighting`] did, for the user.
#[derive(Clone, Debug, PartialEq)]
pub enum LightingNote {
    /// The scene's own lights are used.
    SceneLights,
    /// The overrides replaced the scene's analytic lights and environment.
    Overridden,
    /// Nothing in the scene emits light: the default sky and sun were added (here, or by the
    /// loader: [`Scene::default_lighting`]).
    DefaultSky,
}

impl LightingNote {
    /// The message to print, if any.
    pub fn message(&self, scene: &Scene) -> Option<String> {
        match self {
            LightingNote::DefaultSky => Some(format!(
                "{}: the scene has no light; using the default sky (radiance {}) and sun \
                 (irradiance {}); pass --env / --point to choose the lights",
                scene.name,
                scene.environment.x,
                scene
                    .lights
                    .iter()
                    .find_map(|l| match l {
                        Light::Directional { irradiance, .. } => Some(irradiance.x),
                        _ => None,
                    })
                    .unwrap_or(0.0)
            )),
            _ => None,
        }
    }
}

/// Applies `overrides` to `scene`, or gives an unlit scene the default sky
/// ([`Scene::add_default_lighting_if_unlit`]). Errors on invalid overrides, and when the
/// overrides leave nothing that emits light.
pub fn apply_lighting(scene: &mut Scene, overrides: &LightOverrides) -> Result<LightingNote> {
    overrides.validate()?;
    if overrides.is_empty() {
        scene.add_default_lighting_if_unlit();
        return Ok(if scene.default_lighting {
            LightingNote::DefaultSky
        } else {
            LightingNote::SceneLights
        });
    }
    scene.environment = overrides.env.unwrap_or(Vec3::ZERO);
    scene.lights = overrides
        .points
        .iter()
        .map(|&(position, intensity)| Light::Point {
            position,
            intensity,
        })
        .collect();
    let lit = scene.environment.max_element() > 0.0
        || scene.lights.iter().any(|l| match l {
            Light::Point { intensity, .. } => intensity.max_element() > 0.0,
            _ => true,
        })
        || scene.materials.iter().any(|m| m.is_emissive());
    if !lit {
        return Err(PathError::Unlit(format!(
            "the overrides leave {} without any light (zero --env and --point-intensity, no \
             emissive surface)",
            scene.name
        )));
    }
    Ok(LightingNote::Overridden)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parallax_scene::Material;

    fn unlit() -> Scene {
        Scene {
            name: "empty".into(),
            materials: vec![Material::default()],
            ..Scene::default()
        }
    }

    #[test]
    fn unlit_scenes_get_the_default_sky_with_a_message() {
        let mut s = unlit();
        let note = apply_lighting(&mut s, &LightOverrides::default()).unwrap();
        assert_eq!(note, LightingNote::DefaultSky);
        assert!(s.environment.x > 0.0 && !s.lights.is_empty());
        assert!(note.message(&s).unwrap().contains("default sky"));
        // Still the default rig when applied again (as for files the loader already lit).
        let note = apply_lighting(&mut s, &LightOverrides::default()).unwrap();
        assert_eq!(note, LightingNote::DefaultSky);
        let mut lit = Scene::load("atrium").unwrap();
        let note = apply_lighting(&mut lit, &LightOverrides::default()).unwrap();
        assert_eq!(note, LightingNote::SceneLights);
        assert!(note.message(&lit).is_none());
    }

    #[test]
    fn overrides_replace_the_analytic_lights_and_are_checked() {
        let mut s = Scene::load("atrium").unwrap();
        let o = LightOverrides {
            env: Some(Vec3::splat(0.2)),
            points: vec![(Vec3::Y, Vec3::splat(10.0))],
        };
        assert_eq!(
            apply_lighting(&mut s, &o).unwrap(),
            LightingNote::Overridden
        );
        assert_eq!(s.environment, Vec3::splat(0.2));
        assert_eq!(s.lights.len(), 1);
        for bad in [
            LightOverrides {
                env: Some(Vec3::new(-1.0, 0.0, 0.0)),
                ..Default::default()
            },
            LightOverrides {
                env: Some(Vec3::NAN),
                ..Default::default()
            },
            LightOverrides {
                points: vec![(Vec3::ZERO, Vec3::splat(-2.0))],
                ..Default::default()
            },
            LightOverrides {
                points: vec![(Vec3::INFINITY, Vec3::ONE)],
                ..Default::default()
            },
        ] {
            let e = apply_lighting(&mut unlit(), &bad).unwrap_err();
            assert!(matches!(e, PathError::Light(_)), "{e}");
        }
        let dark = LightOverrides {
            env: Some(Vec3::ZERO),
            ..Default::default()
        };
        assert!(matches!(
            apply_lighting(&mut unlit(), &dark),
            Err(PathError::Unlit(_))
        ));
    }
}
