//! `cornell`: the Cornell box, 2 m on a side, open at the front (+z).
//!
//! The interior is x in [-1, 1], y in [0, 2], z in [-1, 1]; walls are 5 cm thick closed boxes
//! outside it (red left, green right, white floor, ceiling and back). An emissive quad just below
//! the ceiling is the only light. Inside: a tall mirror box, a glass sphere (ior 1.5) and a short
//! white box.
//!
//! | parameter      | value                                                       |
//! |----------------|-------------------------------------------------------------|
//! | light          | 0.5 x 0.4 m quad at y = 1.99, facing down, emissive (17, 12, 4) |
//! | tall box       | 0.6 x 1.2 x 0.6 m, mirror, turned 20 degrees                 |
//! | sphere         | r = 0.3 m, dielectric ior 1.5                                |
//! | short box      | 0.5 m cube, white diffuse, turned -17 degrees                |

use glam::{Affine3A, Quat, Vec2, Vec3};

use super::cameras::{named, path};
use super::shapes::MeshBuilder;
use crate::{Material, MaterialKind, Scene};

const WHITE: u32 = 0;
const RED: u32 = 1;
const GREEN: u32 = 2;
const LIGHT: u32 = 3;
const MIRROR: u32 = 4;
const GLASS: u32 = 5;

/// Wall thickness.
const T: f32 = 0.05;

fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("white", Vec3::new(0.73, 0.73, 0.73)),
        Material::diffuse("red", Vec3::new(0.65, 0.05, 0.05)),
        Material::diffuse("green", Vec3::new(0.12, 0.45, 0.15)),
        Material {
            emissive: Vec3::new(17.0, 12.0, 4.0),
            ..Material::diffuse("light", Vec3::splat(0.78))
        },
        Material {
            name: "mirror".into(),
            kind: MaterialKind::Mirror,
            base_color: Vec3::splat(0.95),
            roughness: 0.0,
            ..Material::default()
        },
        Material {
            name: "glass".into(),
            kind: MaterialKind::Dielectric { ior: 1.5 },
            base_color: Vec3::ONE,
            roughness: 0.0,
            ..Material::default()
        },
    ]
}

/// Builds the scene.
pub fn build() -> Scene {
    let mut b = MeshBuilder::new();
    b.object("solid:floor", |b| {
        b.cuboid(
            Vec3::new(-1.0 - T, -T, -1.0 - T),
            Vec3::new(1.0 + T, 0.0, 1.0),
            WHITE,
        )
    });
    b.object("solid:ceiling", |b| {
        b.cuboid(
            Vec3::new(-1.0 - T, 2.0, -1.0 - T),
            Vec3::new(1.0 + T, 2.0 + T, 1.0),
            WHITE,
        )
    });
    b.object("solid:back", |b| {
        b.cuboid(
            Vec3::new(-1.0, 0.0, -1.0 - T),
            Vec3::new(1.0, 2.0, -1.0),
            WHITE,
        )
    });
    b.object("solid:left", |b| {
        b.cuboid(
            Vec3::new(-1.0 - T, 0.0, -1.0 - T),
            Vec3::new(-1.0, 2.0, 1.0),
            RED,
        )
    });
    b.object("solid:right", |b| {
        b.cuboid(
            Vec3::new(1.0, 0.0, -1.0 - T),
            Vec3::new(1.0 + T, 2.0, 1.0),
            GREEN,
        )
    });
    b.object("light", |b| {
        let y = 1.99;
        let (hx, hz) = (0.25, 0.2);
        // Counter-clockwise seen from below: the light faces down (-y).
        b.flat_quad(
            [
                Vec3::new(-hx, y, -hz),
                Vec3::new(hx, y, -hz),
                Vec3::new(hx, y, hz),
                Vec3::new(-hx, y, hz),
            ],
            [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y],
            LIGHT,
        );
    });
    b.object("solid:tall_box", |b| {
        let xf = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(20f32.to_radians()),
            Vec3::new(-0.4, 0.6, -0.35),
        );
        b.boxed(xf, Vec3::new(0.3, 0.6, 0.3), MIRROR);
    });
    b.object("solid:short_box", |b| {
        let xf = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(-17f32.to_radians()),
            Vec3::new(0.45, 0.25, -0.2),
        );
        b.boxed(xf, Vec3::splat(0.25), WHITE);
    });
    b.object("solid:sphere", |b| {
        b.sphere(Vec3::new(-0.3, 0.3, 0.45), 0.3, 48, 24, GLASS)
    });

    let centre = Vec3::new(0.0, 1.0, 0.0);
    let orbit = |deg: f32, dist: f32, y: f32| {
        let a = deg.to_radians();
        (Vec3::new(dist * a.sin(), y, dist * a.cos()), centre)
    };
    let keys: Vec<(f32, Vec3, Vec3)> = [
        (-12.0, 4.2, 1.0),
        (-4.0, 3.9, 1.05),
        (4.0, 3.6, 1.1),
        (12.0, 3.3, 1.1),
    ]
    .iter()
    .enumerate()
    .map(|(i, &(deg, dist, y))| {
        let (eye, target) = orbit(deg, dist, y);
        (i as f32 * 2.0 / 3.0, eye, target)
    })
    .collect();
    Scene {
        name: "cornell".into(),
        mesh: b.finish(),
        materials: materials(),
        lights: Vec::new(),
        environment: Vec3::ZERO,
        cameras: vec![
            named("front", Vec3::new(0.0, 1.0, 3.9), centre, 40.0),
            named(
                "corner",
                Vec3::new(0.8, 1.6, 0.8),
                Vec3::new(-0.5, 0.5, -0.6),
                60.0,
            ),
        ],
        camera_path: Some(path(&keys, 40.0)),
        ..Scene::default()
    }
}
