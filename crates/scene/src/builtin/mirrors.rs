//! `mirrors`: a closed room with curved mirrors, for reflections (Widmer et al. 2015, §5.4,
//! Figs. 11-13: specular and glossy reflections through a cube map of the scene).
//!
//! A room of coloured walls and a checkered floor with diffuse boxes and a pillar; three
//! reflective objects: a **convex mirror ball**, a **concave cylindrical mirror** (a curved
//! shell facing the camera) and a **glossy metal ball** (metallic, roughness 0.25: a
//! Blinn-Phong lobe of exponent ~500 in the reflection renderer). The room is closed, so
//! every reflected ray meets a surface; three point lights light it.
//!
//! | parameter | value |
//! |---|---|
//! | room (inside) | x in [-4, 4], y in [0, 4], z in [-6, 4.5] |
//! | floor | 1 m tiles of two greys |
//! | mirror ball | centre (-2.1, 0.9, -0.5), r = 0.9, mirror 0.95 |
//! | concave mirror | arc of r = 3.2 m about (0.8, 0, 1.5), 70 degrees wide, y in [0.3, 2.7], centred on -z |
//! | glossy ball | centre (1.5, 0.6, 0.1), r = 0.6, metallic 1, roughness 0.25 |
//! | triangles | about 9k |

use glam::{Affine3A, Quat, Vec3};

use super::cameras::{named, path};
use super::shapes::MeshBuilder;
use crate::{Light, Material, MaterialKind, Scene};

pub(super) const TILE_A: u32 = 0;
pub(super) const TILE_B: u32 = 1;
pub(super) const WALL_RED: u32 = 2;
pub(super) const WALL_GREEN: u32 = 3;
pub(super) const WALL_BLUE: u32 = 4;
pub(super) const WALL_WHITE: u32 = 5;
pub(super) const ORANGE: u32 = 6;
pub(super) const MIRROR: u32 = 7;
pub(super) const GLOSSY: u32 = 8;
const CEILING: u32 = 9;

/// Room interior bounds.
const X: f32 = 4.0;
const Y: f32 = 4.0;
const Z_BACK: f32 = -6.0;
const Z_FRONT: f32 = 4.5;
/// Wall thickness.
const T: f32 = 0.1;

/// The materials of `mirrors` (and of `mirrors-open`, which leaves the ceiling's unused).
pub(super) fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("tile_light", Vec3::new(0.75, 0.74, 0.70)),
        Material::diffuse("tile_dark", Vec3::new(0.18, 0.18, 0.20)),
        Material::diffuse("wall_red", Vec3::new(0.70, 0.12, 0.10)),
        Material::diffuse("wall_green", Vec3::new(0.14, 0.55, 0.20)),
        Material::diffuse("wall_blue", Vec3::new(0.15, 0.25, 0.65)),
        Material::diffuse("wall_white", Vec3::new(0.80, 0.78, 0.72)),
        Material::diffuse("orange", Vec3::new(0.85, 0.45, 0.08)),
        Material {
            name: "mirror".into(),
            kind: MaterialKind::Mirror,
            base_color: Vec3::splat(0.95),
            roughness: 0.0,
            ..Material::default()
        },
        Material {
            name: "glossy_metal".into(),
            kind: MaterialKind::Standard,
            base_color: Vec3::new(0.92, 0.85, 0.70),
            roughness: 0.25,
            metallic: 1.0,
            ..Material::default()
        },
        Material::diffuse("ceiling", Vec3::new(0.85, 0.85, 0.85)),
    ]
}

/// Floor tiles of `size` metres over `x` x `z`, alternating [`TILE_A`] / [`TILE_B`] (the
/// last row and column clipped to the bounds), surrounded by plain [`TILE_A`] ground out to
/// `outer` metres from the origin when given: one closed slab below y = 0 (object
/// `solid:floor`) whose top is split into the tiles, so no inner walls lie between them.
pub(super) fn checker_floor(
    b: &mut MeshBuilder,
    x: [f32; 2],
    z: [f32; 2],
    size: f32,
    outer: Option<f32>,
) {
    let lines = |[lo, hi]: [f32; 2]| {
        let n = ((hi - lo) / size).ceil() as i32;
        let mut v: Vec<f32> = (0..n).map(|i| lo + i as f32 * size).collect();
        v.push(hi);
        if let Some(o) = outer {
            v.insert(0, -o);
            v.push(o);
        }
        v
    };
    let (xs, zs) = (lines(x), lines(z));
    let ring = outer.is_some() as usize;
    let (nx, nz) = (xs.len() - 1, zs.len() - 1);
    b.object("solid:floor", |b| {
        b.tiled_slab(
            &xs,
            &zs,
            [-T, 0.0],
            |i, k| {
                let inner = i >= ring && i < nx - ring && k >= ring && k < nz - ring;
                if inner && (i + k - 2 * ring) % 2 == 1 {
                    TILE_B
                } else {
                    TILE_A
                }
            },
            TILE_A,
        )
    });
}

/// A concave cylindrical mirror: a 6 cm shell on the circle of radius `r` about `c` (its
/// centre of curvature, on the viewer's side), `width_deg` wide around -z, from height
/// `y0` up by `height`; its normal points back to `c`.
pub(super) fn concave_mirror(
    b: &mut MeshBuilder,
    c: Vec3,
    r: f32,
    width_deg: f32,
    y0: f32,
    height: f32,
) {
    let half = (0.5 * width_deg).to_radians();
    b.object("solid:concave_mirror", |b| {
        b.sheet(48, 12, 0.06, MIRROR, |u, v| {
            let a = -half + 2.0 * half * u;
            let (s, cs) = a.sin_cos();
            let p = c + Vec3::new(r * s, y0 + height * v, -r * cs);
            // dP/du x dP/dv points along -(outward): towards `c`.
            let n = Vec3::new(-s, 0.0, cs);
            (p, n)
        });
    });
}

/// Builds the scene.
pub fn build() -> Scene {
    let mut b = MeshBuilder::new();
    checker_floor(&mut b, [-X, X], [Z_BACK, Z_FRONT], 1.0, None);
    b.object("solid:ceiling", |b| {
        b.cuboid(
            Vec3::new(-X - T, Y, Z_BACK - T),
            Vec3::new(X + T, Y + T, Z_FRONT + T),
            CEILING,
        )
    });
    b.object("solid:wall.left", |b| {
        b.cuboid(
            Vec3::new(-X - T, -T, Z_BACK - T),
            Vec3::new(-X, Y, Z_FRONT + T),
            WALL_RED,
        )
    });
    b.object("solid:wall.right", |b| {
        b.cuboid(
            Vec3::new(X, -T, Z_BACK - T),
            Vec3::new(X + T, Y, Z_FRONT + T),
            WALL_GREEN,
        )
    });
    b.object("solid:wall.back", |b| {
        b.cuboid(
            Vec3::new(-X, -T, Z_BACK - T),
            Vec3::new(X, Y, Z_BACK),
            WALL_BLUE,
        )
    });
    b.object("solid:wall.front", |b| {
        b.cuboid(
            Vec3::new(-X, -T, Z_FRONT),
            Vec3::new(X, Y, Z_FRONT + T),
            WALL_WHITE,
        )
    });
    // Diffuse furniture.
    b.object("solid:pillar", |b| {
        let base = Vec3::new(2.8, 0.0, -3.8);
        b.cylinder(base, base + Vec3::Y * Y, 0.35, 0.35, 32, WALL_WHITE)
    });
    b.object("solid:box.orange", |b| {
        let xf = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(25f32.to_radians()),
            Vec3::new(-2.7, 0.5, -3.2),
        );
        b.boxed(xf, Vec3::splat(0.5), ORANGE)
    });
    b.object("solid:box.white", |b| {
        let xf = Affine3A::from_rotation_translation(
            Quat::from_rotation_y(-15f32.to_radians()),
            Vec3::new(-2.9, 0.35, 2.6),
        );
        b.boxed(xf, Vec3::new(0.5, 0.35, 0.4), WALL_WHITE)
    });
    b.object("solid:box.blue", |b| {
        b.cuboid(
            Vec3::new(2.2, 0.0, 2.0),
            Vec3::new(3.2, 1.2, 3.0),
            WALL_BLUE,
        )
    });
    // Reflective objects.
    b.object("solid:mirror_ball", |b| {
        b.sphere(Vec3::new(-2.1, 0.9, -0.5), 0.9, 64, 32, MIRROR)
    });
    b.object("solid:glossy_ball", |b| {
        b.sphere(Vec3::new(1.5, 0.6, 0.1), 0.6, 48, 24, GLOSSY)
    });
    concave_mirror(&mut b, Vec3::new(0.8, 0.0, 1.5), 3.2, 70.0, 0.3, 2.4);
    let main_eye = Vec3::new(0.0, 1.6, 3.6);
    let main_target = Vec3::new(0.0, 1.1, -1.5);
    Scene {
        name: "mirrors".into(),
        mesh: b.finish(),
        materials: materials(),
        lights: vec![
            Light::Point {
                position: Vec3::new(0.0, 3.6, 0.0),
                intensity: Vec3::new(14.0, 13.0, 12.0),
            },
            Light::Point {
                position: Vec3::new(-3.0, 3.0, -4.5),
                intensity: Vec3::new(8.0, 7.0, 6.0),
            },
            Light::Point {
                position: Vec3::new(3.0, 3.0, 3.5),
                intensity: Vec3::new(6.0, 6.0, 7.0),
            },
        ],
        environment: Vec3::splat(0.05),
        cameras: vec![
            named("main", main_eye, main_target, 60.0),
            named(
                "ball",
                Vec3::new(-0.4, 1.3, 1.8),
                Vec3::new(-2.1, 0.9, -0.5),
                50.0,
            ),
        ],
        camera_path: Some(path(
            &[
                (0.0, main_eye, main_target),
                (1.0, Vec3::new(0.8, 1.5, 3.2), Vec3::new(-0.3, 1.0, -1.5)),
                (2.0, Vec3::new(-0.8, 1.7, 3.0), Vec3::new(0.3, 1.0, -1.5)),
            ],
            60.0,
        )),
        ..Scene::default()
    }
}
