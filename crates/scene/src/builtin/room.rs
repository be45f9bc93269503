//! `room:<file>`: any model staged in a small room made for secondary rays — a mirror on the
//! back wall, a glass sphere beside the model, and point, spot and directional lights that
//! cast shadows — so reflections, refractions and shadows of a real model (e.g. the Stanford
//! bunny) can be rendered and compared between ray tracers. `room-mirror:<file>` and
//! `room-glass:<file>` also turn the model itself into a mirror or into glass (ior 1.5).
//!
//! The model is scaled uniformly so that its bounding box's longest side is [`MODEL_SIZE`],
//! centred on x and z, and stood on the floor (its lowest point at y = 0). Its materials and
//! textures are kept (unless turned to mirror or glass); its lights, cameras and animations
//! are dropped (the room brings its own).
//!
//! | part | value |
//! |---|---|
//! | floor | x, z in [-1.6, 1.6] m, top at y = 0, light grey diffuse |
//! | back wall | z = -1.6, 2.2 m high, pale blue diffuse; a 1.8 x 1.3 m mirror panel on it |
//! | left wall | x = -1.6, 2.2 m high, terracotta diffuse |
//! | glass sphere | r = 0.28 m at (0.78, 0.28, 0.42), ior 1.5 |
//! | lights | point (6 W/sr) at (-0.9, 1.9, 1.1); spot (14 W/sr, 18-28 deg) from (1.3, 2.3, 1.2) at the model; directional 1.2 W/m^2 from above-front-right |
//! | environment | (0.35, 0.4, 0.5) sky |
//! | cameras | `front` (eye (0, 0.85, 2.9) at (0, 0.45, -0.3), 45 deg), `mirror` (eye (1.2, 0.7, 1.8) at (-0.4, 0.6, -1.6), 50 deg) |

use glam::Vec3;

use super::cameras::named;
use super::shapes::MeshBuilder;
use crate::{Light, Material, MaterialKind, ObjectRange, Scene};

/// Longest side of the staged model (metres).
pub const MODEL_SIZE: f32 = 1.0;

/// What the model is made of in the room.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFinish {
    /// Its own materials.
    Keep,
    Mirror,
    Glass,
}

/// `room:` / `room-mirror:` / `room-glass:` and the rest of the name (the model file).
pub fn parse(name: &str) -> Option<(ModelFinish, &str)> {
    [
        ("room:", ModelFinish::Keep),
        ("room-mirror:", ModelFinish::Mirror),
        ("room-glass:", ModelFinish::Glass),
    ]
    .into_iter()
    .find_map(|(p, f)| name.strip_prefix(p).map(|rest| (f, rest)))
}

fn mirror() -> Material {
    Material {
        name: "room mirror".into(),
        kind: MaterialKind::Mirror,
        base_color: Vec3::splat(0.92),
        roughness: 0.0,
        ..Material::default()
    }
}

fn glass() -> Material {
    Material {
        name: "room glass".into(),
        kind: MaterialKind::Dielectric { ior: 1.5 },
        base_color: Vec3::ONE,
        roughness: 0.0,
        ..Material::default()
    }
}

/// Stages `model` in the room (module docs). Errors when the model has no finite bounds.
pub fn stage(model: Scene, finish: ModelFinish) -> Result<Scene, String> {
    let b = model.mesh.bounds();
    let size = b.extent().max_element();
    if b.is_empty() || !(b.min.is_finite() && b.max.is_finite()) || !(size > 0.0) {
        return Err(format!(
            "model {:?} has no finite, non-flat bounding box to stage",
            model.name
        ));
    }
    let scale = MODEL_SIZE / size;
    let c = b.center();
    let offset = Vec3::new(-c.x, -b.min.y, -c.z) * scale;
    let place = |p: Vec3| p * scale + offset;

    // Room materials first, then the model's.
    const FLOOR: u32 = 0;
    const BACK: u32 = 1;
    const LEFT: u32 = 2;
    const MIRROR: u32 = 3;
    const GLASS: u32 = 4;
    let mut materials = vec![
        Material::diffuse("room floor", Vec3::splat(0.7)),
        Material::diffuse("room back wall", Vec3::new(0.55, 0.62, 0.75)),
        Material::diffuse("room left wall", Vec3::new(0.7, 0.38, 0.28)),
        mirror(),
        glass(),
    ];
    let first_model_material = materials.len() as u32;
    let model_material = |m: u32| match finish {
        ModelFinish::Keep => first_model_material + m,
        ModelFinish::Mirror => MIRROR,
        ModelFinish::Glass => GLASS,
    };
    if finish == ModelFinish::Keep {
        materials.extend(model.materials.iter().cloned());
    }

    let (w, t, h) = (1.6f32, 0.05f32, 2.2f32);
    let mut rb = MeshBuilder::new();
    rb.object("solid:room floor", |b| {
        b.cuboid(Vec3::new(-w, -t, -w), Vec3::new(w, 0.0, w), FLOOR)
    });
    rb.object("solid:room back wall", |b| {
        b.cuboid(Vec3::new(-w - t, -t, -w - t), Vec3::new(w, h, -w), BACK)
    });
    rb.object("solid:room left wall", |b| {
        b.cuboid(Vec3::new(-w - t, -t, -w), Vec3::new(-w, h, w), LEFT)
    });
    rb.object("solid:room mirror", |b| {
        b.cuboid(
            Vec3::new(-0.9, 0.15, -w),
            Vec3::new(0.9, 1.45, -w + 0.02),
            MIRROR,
        )
    });
    rb.object("solid:room glass sphere", |b| {
        b.sphere(Vec3::new(0.78, 0.28, 0.42), 0.28, 48, 24, GLASS)
    });
    let mut mesh = rb.finish();

    // Append the model.
    let (v0, t0) = (mesh.positions.len() as u32, mesh.indices.len() as u32);
    let m = model.mesh;
    mesh.positions.extend(m.positions.iter().map(|&p| place(p)));
    mesh.normals.extend(m.normals.iter().copied());
    mesh.uvs.extend(m.uvs.iter().copied());
    mesh.indices
        .extend(m.indices.iter().map(|t| t.map(|i| i + v0)));
    mesh.material_ids
        .extend(m.material_ids.iter().map(|&id| model_material(id)));
    if m.objects.is_empty() {
        mesh.objects.push(ObjectRange {
            name: model.name.clone(),
            first_triangle: t0,
            triangle_count: m.indices.len() as u32,
            first_vertex: v0,
            vertex_count: m.positions.len() as u32,
        });
    } else {
        mesh.objects.extend(m.objects.iter().map(|o| ObjectRange {
            first_triangle: o.first_triangle + t0,
            first_vertex: o.first_vertex + v0,
            ..o.clone()
        }));
    }
    let textures = if finish == ModelFinish::Keep {
        model.textures
    } else {
        Vec::new()
    };
    let lights = vec![
        Light::Point {
            position: Vec3::new(-0.9, 1.9, 1.1),
            intensity: Vec3::splat(6.0),
        },
        Light::Spot {
            position: Vec3::new(1.3, 2.3, 1.2),
            direction: (Vec3::new(0.0, 0.4, 0.0) - Vec3::new(1.3, 2.3, 1.2)).normalize(),
            intensity: Vec3::new(14.0, 13.0, 11.0),
            inner_angle: 18f32.to_radians(),
            outer_angle: 28f32.to_radians(),
        },
        Light::Directional {
            direction: Vec3::new(-0.35, -1.0, -0.45).normalize(),
            irradiance: Vec3::splat(1.2),
        },
    ];
    Ok(Scene {
        name: format!("room({})", model.name),
        mesh,
        materials,
        textures,
        lights,
        environment: Vec3::new(0.35, 0.4, 0.5),
        cameras: vec![
            named(
                "front",
                Vec3::new(0.0, 0.85, 2.9),
                Vec3::new(0.0, 0.45, -0.3),
                45.0,
            ),
            named(
                "mirror",
                Vec3::new(1.2, 0.7, 1.8),
                Vec3::new(-0.4, 0.6, -1.6),
                50.0,
            ),
        ],
        ..Scene::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> Scene {
        let mut b = MeshBuilder::new();
        b.object("solid:box", |b| {
            b.cuboid(Vec3::new(3.0, 5.0, 1.0), Vec3::new(5.0, 6.0, 2.0), 0)
        });
        Scene {
            name: "box".into(),
            mesh: b.finish(),
            materials: vec![Material::diffuse("red", Vec3::X)],
            ..Scene::default()
        }
    }

    #[test]
    fn the_model_stands_on_the_floor_at_unit_size() {
        for finish in [ModelFinish::Keep, ModelFinish::Mirror, ModelFinish::Glass] {
            let s = stage(model(), finish).unwrap();
            s.validate().unwrap();
            let o = s.mesh.objects.last().unwrap();
            let r = o.first_triangle as usize..(o.first_triangle + o.triangle_count) as usize;
            let pts: Vec<Vec3> = r.clone().flat_map(|p| s.mesh.triangle(p)).collect();
            let b = parallax_core::Aabb::from_points(pts);
            assert!((b.extent().max_element() - MODEL_SIZE).abs() < 1e-5);
            assert!(b.min.y.abs() < 1e-6 && b.center().x.abs() < 1e-6);
            let kinds: Vec<MaterialKind> = r
                .map(|p| s.materials[s.mesh.material_ids[p] as usize].kind)
                .collect();
            let want = match finish {
                ModelFinish::Keep => MaterialKind::Standard,
                ModelFinish::Mirror => MaterialKind::Mirror,
                ModelFinish::Glass => MaterialKind::Dielectric { ior: 1.5 },
            };
            assert!(kinds.iter().all(|&k| k == want));
        }
        assert_eq!(
            parse("room-glass:a.ply"),
            Some((ModelFinish::Glass, "a.ply"))
        );
        assert_eq!(parse("a.ply"), None);
        let mut flat = model();
        flat.mesh = Default::default();
        assert!(stage(flat, ModelFinish::Keep).is_err());
    }
}
