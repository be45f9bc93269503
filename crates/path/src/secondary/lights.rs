//! The lights of the Whitted-style renderer: the scene's point, spot and directional lights;
//! a scene without any lights with its emissive triangles taken as point lights (each at its
//! centroid, radiating `L A cos(theta)` around its normal — the far-field intensity of a small
//! Lambertian emitter), at most [`MAX_EMITTER_LIGHTS`] of them (the most powerful).

use glam::Vec3;
use parallax_render::lights::analytic_light_at;
use parallax_scene::{Light, Scene};

/// Most emissive triangles taken as point lights.
pub const MAX_EMITTER_LIGHTS: usize = 64;

/// A light of the renderer.
#[derive(Clone, Debug, PartialEq)]
pub enum WhittedLight {
    Analytic(Light),
    /// An emissive triangle as a point light: `intensity = L A` along `normal`.
    Emitter {
        position: Vec3,
        normal: Vec3,
        intensity: Vec3,
    },
}

/// The renderer's lights of `scene` (module docs).
pub fn whitted_lights(scene: &Scene) -> Vec<WhittedLight> {
    if !scene.lights.is_empty() {
        return scene
            .lights
            .iter()
            .cloned()
            .map(WhittedLight::Analytic)
            .collect();
    }
    let mesh = &scene.mesh;
    let mut emitters: Vec<(f32, WhittedLight)> = (0..mesh.indices.len())
        .filter_map(|p| {
            let m = scene.materials.get(mesh.material_ids[p] as usize)?;
            if !m.is_emissive() {
                return None;
            }
            let [a, b, c] = mesh.triangle(p);
            let n = (b - a).cross(c - a);
            let area = 0.5 * n.length();
            let intensity = m.emissive * area;
            let power = intensity.dot(Vec3::splat(1.0 / 3.0));
            (power > 0.0 && power.is_finite()).then(|| {
                (
                    power,
                    WhittedLight::Emitter {
                        position: (a + b + c) / 3.0,
                        normal: n.normalize(),
                        intensity,
                    },
                )
            })
        })
        .collect();
    // Most powerful first; ties keep triangle order (stable sort).
    emitters.sort_by(|x, y| y.0.total_cmp(&x.0));
    emitters.truncate(MAX_EMITTER_LIGHTS);
    emitters.into_iter().map(|(_, l)| l).collect()
}

/// Direction to the light from `p`, its distance (inf for directional) and the irradiance it
/// delivers perpendicular to that direction.
pub fn light_at(light: &WhittedLight, p: Vec3) -> Option<(Vec3, f32, Vec3)> {
    match light {
        WhittedLight::Analytic(l) => analytic_light_at(l, p),
        WhittedLight::Emitter {
            position,
            normal,
            intensity,
        } => {
            let d = *position - p;
            let dist2 = d.length_squared();
            if !(dist2 > 0.0) {
                return None;
            }
            let dist = dist2.sqrt();
            let wi = d / dist;
            let cos = normal.dot(-wi);
            (cos > 0.0).then(|| (wi, dist, *intensity * (cos / dist2)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornell_lights_with_its_emitter() {
        let scene = Scene::load("cornell").unwrap();
        let lights = whitted_lights(&scene);
        assert_eq!(lights.len(), 2, "the light quad's two triangles");
        // Below the light (facing down) it shines; above it does not.
        let below = light_at(&lights[0], glam::Vec3::new(0.0, 1.0, 0.0)).unwrap();
        assert!(below.0.y > 0.9 && below.2.max_element() > 0.0);
        assert!(light_at(&lights[0], glam::Vec3::new(0.0, 2.5, 0.0)).is_none());
        let room = parallax_scene::Scene::load("atrium").unwrap();
        assert!(
            whitted_lights(&room)
                .iter()
                .all(|l| matches!(l, WhittedLight::Analytic(_)))
        );
    }
}
