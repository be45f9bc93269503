//! `mirrors-open`: curved mirrors in the open, reflecting surroundings the camera sees — a set-up
//! modelled on Widmer et al. 2015's Fig. 11 (two curved mirror objects whose reflections come
//! from one cube map at the camera, §5.4), beside the hard closed `mirrors` room.
//!
//! A checkered ground under an open sky (rays that leave the scene take the environment;
//! the ground reaches far enough that every downward ray meets it), a
//! **convex mirror ball** on a slim pedestal left of centre, a **concave cylindrical mirror**
//! right of centre facing the camera, a **glossy metal ball** left of them, a ring of coloured
//! pillars around the scene and low boxes behind the camera. The surroundings are placed so
//! that the sides the mirrors reflect mostly face the camera as well (the boxes' faces towards
//! the mirrors, the pillars' inner sides); what the camera cannot see is mainly what hides
//! behind the convex ball (its rim reflects it) and the sides of the boxes facing away from the
//! camera. One sun and the sky light it.
//!
//! | parameter | value |
//! |---|---|
//! | ground | one slab 0.1 m thick; x, z in [-16, 16]: 2 m tiles of two greys; plain light grey out to ±150 m |
//! | mirror ball | centre (-1.5, 1.25, -1.0), r = 0.8, mirror 0.95, on a pedestal r = 0.18 |
//! | concave mirror | arc of r = 3.5 m about (1.5, 0, 2.5), 60 degrees wide, y in [0.2, 2.4], centred on -z |
//! | glossy ball | centre (-3.3, 0.6, 0.6), r = 0.6, metallic 1, roughness 0.25 |
//! | pillars | 12 on a circle of r = 9 m about the origin, r = 0.3 m, 2.6 m tall |
//! | boxes | three, 1 m wide, 0.9-1.4 m tall, at z in [6.5, 7.5] |
//! | main camera | eye (0, 1.7, 5), target (0, 1, -1), 60 degrees |
//! | triangles | about 12k |

use glam::Vec3;

use super::cameras::{named, path};
use super::mirrors::{
    GLOSSY, MIRROR, ORANGE, WALL_BLUE, WALL_GREEN, WALL_RED, WALL_WHITE, checker_floor,
    concave_mirror, materials,
};
use super::shapes::MeshBuilder;
use crate::{Light, Scene};

/// Half-width of the ground (metres).
const OUTER: f32 = 150.0;

/// Builds the scene.
pub fn build() -> Scene {
    let mut b = MeshBuilder::new();
    // Plain ground around the tiles out to the horizon, so that no ray passes under the
    // ground's edge (a cube map at the eye would answer such a ray with the ground).
    checker_floor(&mut b, [-16.0, 16.0], [-16.0, 16.0], 2.0, Some(OUTER));
    let ball = Vec3::new(-1.5, 1.25, -1.0);
    b.object("solid:pedestal", |b| {
        let base = Vec3::new(ball.x, 0.0, ball.z);
        b.cylinder(base, base + Vec3::Y * 0.5, 0.18, 0.18, 24, WALL_WHITE)
    });
    b.object("solid:mirror_ball", |b| b.sphere(ball, 0.8, 64, 32, MIRROR));
    concave_mirror(&mut b, Vec3::new(1.5, 0.0, 2.5), 3.5, 60.0, 0.2, 2.2);
    b.object("solid:glossy_ball", |b| {
        b.sphere(Vec3::new(-3.3, 0.6, 0.6), 0.6, 48, 24, GLOSSY)
    });
    let colours = [WALL_RED, ORANGE, WALL_GREEN, WALL_BLUE, WALL_WHITE];
    for i in 0..12 {
        let a = (i as f32 * 30.0 + 15.0).to_radians();
        let base = Vec3::new(9.0 * a.cos(), 0.0, 9.0 * a.sin());
        b.object(&format!("solid:pillar.{i}"), |b| {
            b.cylinder(base, base + Vec3::Y * 2.6, 0.3, 0.3, 32, colours[i % 5])
        });
    }
    for (i, (x, h, m)) in [
        (-3.0, 1.1, WALL_GREEN),
        (1.2, 0.9, ORANGE),
        (3.5, 1.4, WALL_RED),
    ]
    .into_iter()
    .enumerate()
    {
        b.object(&format!("solid:box.{i}"), |b| {
            b.cuboid(Vec3::new(x - 0.5, 0.0, 6.5), Vec3::new(x + 0.5, h, 7.5), m)
        });
    }
    let main_eye = Vec3::new(0.0, 1.7, 5.0);
    let main_target = Vec3::new(0.0, 1.0, -1.0);
    Scene {
        name: "mirrors-open".into(),
        mesh: b.finish(),
        materials: materials(),
        lights: vec![Light::Directional {
            direction: Vec3::new(-0.4, -1.0, -0.3).normalize(),
            irradiance: Vec3::new(3.2, 3.0, 2.7),
        }],
        environment: Vec3::new(0.30, 0.38, 0.50),
        cameras: vec![
            named("main", main_eye, main_target, 60.0),
            named("ball", Vec3::new(0.2, 1.5, 2.2), ball, 50.0),
        ],
        camera_path: Some(path(
            &[
                (0.0, main_eye, main_target),
                (1.0, Vec3::new(0.8, 1.6, 4.6), Vec3::new(-0.3, 1.0, -1.0)),
                (2.0, Vec3::new(-0.8, 1.8, 4.4), Vec3::new(0.3, 1.0, -1.0)),
            ],
            60.0,
        )),
        ..Scene::default()
    }
}
