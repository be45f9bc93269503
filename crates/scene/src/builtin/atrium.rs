//! `atrium`: a Sponza-like courtyard, 12.8 x 30.8 m, open to the sky.
//!
//! Two storeys of arcades run along both long sides (x = +-3.5 m): cylindrical columns on
//! plinths with square abaci, semicircular arch blocks between them, an upper gallery floor with
//! a balustrade, a roof over the aisles; end walls close the long axis (z). Wavy banners hang in
//! front of the upper arcade and curtains behind the lower one; planters with shrubs and crates
//! stand on the floor. The point is strong depth discontinuities and disocclusions: columns in
//! front of walls, banners in front of arcades, balusters in front of the gallery.
//!
//! | parameter          | value                                   |
//! |--------------------|-----------------------------------------|
//! | floor              | x in [-6.4, 6.4], z in [-15.4, 15.4], top y = 0 |
//! | arcade axis        | x = +-3.5, columns every 3 m at z = -12 ..= 12 |
//! | lower storey       | columns 0-3.2 m, arches up to 4.5 m      |
//! | gallery floor      | y = 4.8; upper arches up to 8.8; roof 9.1 |
//! | triangles          | about 49k                                |

use std::f32::consts::FRAC_PI_2;

use glam::{Affine3A, Quat, Vec3};

use super::cameras::{named, path};
use super::shapes::{MeshBuilder, with_normals};
use crate::{Light, Material, MaterialKind, Scene};

const STONE: u32 = 0;
const FLOOR: u32 = 1;
const CLOTH: [u32; 3] = [2, 3, 4];
const METAL: u32 = 5;
const PLANT: u32 = 6;
const WOOD: u32 = 7;

/// Column centres along z.
const COLUMN_Z: [f32; 9] = [-12.0, -9.0, -6.0, -3.0, 0.0, 3.0, 6.0, 9.0, 12.0];
/// Inner face of the end walls.
const END_Z: f32 = 15.0;
/// Arcade axis.
const ARCADE_X: f32 = 3.5;

/// One storey of the arcade.
struct Storey {
    name: &'static str,
    floor_y: f32,
    plinth: (f32, f32), // half width, height
    shaft: (f32, f32),  // radius, height
    abacus: (f32, f32), // half width, height
    arch_top: f32,      // absolute y of the arch blocks' top
}

const LOWER: Storey = Storey {
    name: "lower",
    floor_y: 0.0,
    plinth: (0.4, 0.3),
    shaft: (0.28, 2.6),
    abacus: (0.4, 0.3),
    arch_top: 4.5,
};

const UPPER: Storey = Storey {
    name: "upper",
    floor_y: 4.8,
    plinth: (0.35, 0.2),
    shaft: (0.22, 2.1),
    abacus: (0.35, 0.25),
    arch_top: 8.8,
};

fn materials() -> Vec<Material> {
    let standard = |name: &str, c: Vec3, roughness: f32, metallic: f32| Material {
        name: name.into(),
        kind: MaterialKind::Standard,
        base_color: c,
        roughness,
        metallic,
        ..Material::default()
    };
    vec![
        standard("stone", Vec3::new(0.62, 0.57, 0.50), 0.8, 0.0),
        standard("floor", Vec3::new(0.34, 0.31, 0.28), 0.7, 0.0),
        standard("cloth_red", Vec3::new(0.60, 0.06, 0.05), 0.9, 0.0),
        standard("cloth_green", Vec3::new(0.08, 0.45, 0.10), 0.9, 0.0),
        standard("cloth_blue", Vec3::new(0.06, 0.12, 0.55), 0.9, 0.0),
        standard("planter_metal", Vec3::new(0.90, 0.72, 0.45), 0.3, 1.0),
        standard("plant", Vec3::new(0.12, 0.35, 0.08), 0.8, 0.0),
        standard("wood", Vec3::new(0.45, 0.30, 0.16), 0.6, 0.0),
    ]
}

/// Builds the scene.
pub fn build() -> Scene {
    let mut b = MeshBuilder::new();
    b.object("solid:floor", |b| {
        b.cuboid(
            Vec3::new(-6.4, -0.2, -15.4),
            Vec3::new(6.4, 0.0, 15.4),
            FLOOR,
        )
    });
    for (side, sx) in [("east", 1.0f32), ("west", -1.0)] {
        b.object(&format!("solid:wall.{side}"), |b| {
            let x = [6.0 * sx, 6.4 * sx];
            b.cuboid(
                Vec3::new(x[0].min(x[1]), 0.0, -END_Z),
                Vec3::new(x[0].max(x[1]), 9.1, END_Z),
                STONE,
            )
        });
        arcade_side(&mut b, side, sx);
    }
    for (side, sz) in [("north", -1.0f32), ("south", 1.0)] {
        b.object(&format!("solid:wall.{side}"), |b| {
            let z = [END_Z * sz, (END_Z + 0.4) * sz];
            b.cuboid(
                Vec3::new(-6.4, 0.0, z[0].min(z[1])),
                Vec3::new(6.4, 10.0, z[0].max(z[1])),
                STONE,
            )
        });
    }
    banners(&mut b);
    props(&mut b);

    let sun = Vec3::new(-0.4, -1.0, -0.3).normalize();
    Scene {
        name: "atrium".into(),
        mesh: b.finish(),
        materials: materials(),
        lights: vec![
            Light::Directional {
                direction: sun,
                irradiance: Vec3::new(4.0, 3.7, 3.2),
            },
            Light::Point {
                position: Vec3::new(4.8, 2.6, 1.5),
                intensity: Vec3::new(12.0, 9.0, 5.0),
            },
            Light::Point {
                position: Vec3::new(-4.8, 2.6, -4.5),
                intensity: Vec3::new(12.0, 9.0, 5.0),
            },
        ],
        environment: Vec3::new(0.6, 0.7, 0.9),
        cameras: vec![
            named(
                "main",
                Vec3::new(0.0, 1.7, 13.0),
                Vec3::new(0.0, 2.2, 0.0),
                60.0,
            ),
            named(
                "gallery",
                Vec3::new(4.6, 6.4, 11.0),
                Vec3::new(-2.0, 3.0, -4.0),
                60.0,
            ),
            named(
                "columns",
                Vec3::new(2.3, 1.4, 7.5),
                Vec3::new(3.6, 1.8, -4.0),
                60.0,
            ),
            named(
                "top",
                Vec3::new(0.5, 22.0, 6.0),
                Vec3::new(0.0, 0.0, -1.0),
                50.0,
            ),
        ],
        camera_path: Some(path(
            &[
                (0.0, Vec3::new(0.0, 1.7, 13.0), Vec3::new(0.0, 2.0, 0.0)),
                (0.5, Vec3::new(0.6, 1.7, 11.8), Vec3::new(1.5, 2.0, 0.0)),
                (1.0, Vec3::new(0.2, 1.7, 10.6), Vec3::new(1.0, 2.2, -1.0)),
                (1.5, Vec3::new(-0.6, 1.7, 9.4), Vec3::new(-1.5, 2.0, -1.0)),
                (2.0, Vec3::new(-0.4, 1.7, 8.2), Vec3::new(-2.5, 2.0, -2.0)),
            ],
            60.0,
        )),
        ..Scene::default()
    }
}

/// Both storeys of one side's arcade (`sx` = +-1), gallery floor, roof and balustrade.
fn arcade_side(b: &mut MeshBuilder, side: &str, sx: f32) {
    let x = ARCADE_X * sx;
    for st in [&LOWER, &UPPER] {
        let spring = st.floor_y + st.plinth.1 + st.shaft.1 + st.abacus.1;
        for (k, &z) in COLUMN_Z.iter().enumerate() {
            b.object(&format!("solid:column.{}.{side}.{k}", st.name), |b| {
                let (pw, ph) = st.plinth;
                let y0 = st.floor_y;
                b.cuboid(
                    Vec3::new(x - pw, y0, z - pw),
                    Vec3::new(x + pw, y0 + ph, z + pw),
                    STONE,
                );
                let (r, h) = st.shaft;
                let base = Vec3::new(x, y0 + ph, z);
                b.cylinder(base, base + Vec3::Y * h, r, 0.9 * r, 20, STONE);
                let aw = st.abacus.0;
                b.cuboid(
                    Vec3::new(x - aw, spring - st.abacus.1, z - aw),
                    Vec3::new(x + aw, spring, z + aw),
                    STONE,
                );
            });
        }
        // Piers against the end walls carry the outermost arches.
        let aw = st.abacus.0;
        for (end, sz) in [("north", -1.0f32), ("south", 1.0)] {
            b.object(&format!("solid:pier.{}.{side}.{end}", st.name), |b| {
                let z = [(END_Z - 2.0 * aw) * sz, END_Z * sz];
                b.cuboid(
                    Vec3::new(x - aw, st.floor_y, z[0].min(z[1])),
                    Vec3::new(x + aw, spring, z[0].max(z[1])),
                    STONE,
                );
            });
        }
        // Arches: between pier and column, and between neighbouring columns.
        let mut supports: Vec<f32> = vec![-(END_Z - aw)];
        supports.extend_from_slice(&COLUMN_Z);
        supports.push(END_Z - aw);
        // Local x of an arch runs along world z, local z along world -x.
        let rot = Quat::from_rotation_y(-FRAC_PI_2);
        for (k, w) in supports.windows(2).enumerate() {
            let centre = Vec3::new(x, spring, 0.5 * (w[0] + w[1]));
            let r = 0.5 * (w[1] - w[0]) - aw;
            b.object(&format!("solid:arch.{}.{side}.{k}", st.name), |b| {
                let xf = Affine3A::from_rotation_translation(rot, centre);
                b.arch(xf, r, aw, st.arch_top - spring, 2.0 * aw, 24, STONE);
            });
        }
        // The slab on top of the arcade: gallery floor (lower storey) or roof (upper).
        let (slab, y0, y1) = if st.floor_y == 0.0 {
            ("gallery", st.arch_top, UPPER.floor_y)
        } else {
            ("roof", st.arch_top, st.arch_top + 0.3)
        };
        b.object(&format!("solid:{slab}.{side}"), |b| {
            let xs = [(ARCADE_X - LOWER.abacus.0) * sx, 6.0 * sx];
            b.cuboid(
                Vec3::new(xs[0].min(xs[1]), y0, -END_Z),
                Vec3::new(xs[0].max(xs[1]), y1, END_Z),
                STONE,
            );
        });
    }
    balustrade(b, side, sx);
}

/// Rails and balusters between the upper plinths.
fn balustrade(b: &mut MeshBuilder, side: &str, sx: f32) {
    let x = ARCADE_X * sx;
    let y0 = UPPER.floor_y;
    let pw = UPPER.plinth.0;
    let mut supports: Vec<f32> = vec![-(END_Z - UPPER.abacus.0)];
    supports.extend_from_slice(&COLUMN_Z);
    supports.push(END_Z - UPPER.abacus.0);
    for (k, w) in supports.windows(2).enumerate() {
        let (z0, z1) = (w[0] + pw, w[1] - pw);
        b.object(&format!("solid:balustrade.{side}.{k}"), |b| {
            b.cuboid(
                Vec3::new(x - 0.1, y0, z0),
                Vec3::new(x + 0.1, y0 + 0.1, z1),
                STONE,
            );
            b.cuboid(
                Vec3::new(x - 0.12, y0 + 0.95, z0),
                Vec3::new(x + 0.12, y0 + 1.05, z1),
                STONE,
            );
            const N: usize = 7;
            for i in 0..N {
                let z = z0 + (z1 - z0) * (i as f32 + 0.5) / N as f32;
                let base = Vec3::new(x, y0 + 0.1, z);
                b.cylinder(base, base + Vec3::Y * 0.85, 0.05, 0.04, 10, STONE);
            }
        });
    }
}

/// Banners in front of the upper arcade (every other bay) and curtains behind the lower one.
fn banners(b: &mut MeshBuilder) {
    let mut colour = 0;
    for (side, sx) in [("east", 1.0f32), ("west", -1.0)] {
        for k in (0..COLUMN_Z.len() - 1).step_by(2) {
            let zc = 0.5 * (COLUMN_Z[k] + COLUMN_Z[k + 1]);
            let x = (ARCADE_X - UPPER.abacus.0 - 0.2) * sx;
            let phase = k as f32 * 0.9 + sx;
            b.object(&format!("solid:banner.{side}.{k}"), |b| {
                cloth(
                    b,
                    x,
                    sx,
                    zc,
                    (5.3, 7.2),
                    1.6,
                    0.08,
                    phase,
                    CLOTH[colour % 3],
                );
            });
            colour += 1;
        }
        for k in [1usize, 5] {
            let zc = 0.5 * (COLUMN_Z[k] + COLUMN_Z[k + 1]);
            let x = (ARCADE_X + LOWER.abacus.0 + 0.35) * sx;
            b.object(&format!("solid:curtain.{side}.{k}"), |b| {
                cloth(
                    b,
                    x,
                    sx,
                    zc,
                    (0.15, 3.9),
                    2.0,
                    0.12,
                    k as f32,
                    CLOTH[colour % 3],
                );
            });
            colour += 1;
        }
    }
}

/// A hanging cloth: a thin closed sheet in the plane x = `x` facing the courtyard (towards
/// -`sx`), centred on `zc`, spanning `ys`, `width` wide, with folds of amplitude `amp` that grow
/// towards the free bottom hem.
#[allow(clippy::too_many_arguments)]
fn cloth(
    b: &mut MeshBuilder,
    x: f32,
    sx: f32,
    zc: f32,
    ys: (f32, f32),
    width: f32,
    amp: f32,
    phase: f32,
    m: u32,
) {
    let surface = with_normals(move |u: f32, v: f32| {
        // u runs along +z for sx = +1 (front = dP/du x dP/dv = -x) and along -z for sx = -1.
        let z = zc + sx * (u - 0.5) * width;
        let y = ys.0 + v * (ys.1 - ys.0);
        let fold = (std::f32::consts::TAU * 2.5 * u + phase).sin() * (0.3 + 0.7 * (1.0 - v));
        let sway = 0.5 * (1.0 - v) * (1.0 - v) * (phase * 1.7).sin();
        Vec3::new(x + amp * (fold + sway), y, z)
    });
    b.sheet(20, 28, 0.015, m, surface);
}

/// Metal planters with shrubs, and a few wooden crates, on the courtyard floor.
fn props(b: &mut MeshBuilder) {
    for (k, (x, z)) in [(-1.6f32, -6.0f32), (1.6, -6.0), (-1.6, 5.0), (1.6, 5.0)]
        .into_iter()
        .enumerate()
    {
        b.object(&format!("solid:planter.{k}"), |b| {
            b.cuboid(
                Vec3::new(x - 0.4, 0.0, z - 0.4),
                Vec3::new(x + 0.4, 0.6, z + 0.4),
                METAL,
            );
        });
        b.object(&format!("solid:shrub.{k}"), |b| {
            b.sphere(Vec3::new(x, 1.0, z), 0.45, 16, 10, PLANT);
        });
    }
    for (k, (x, z, angle, half)) in [
        (-2.0f32, 1.5f32, 0.3f32, 0.35f32),
        (-1.4, 2.4, -0.2, 0.3),
        (2.2, -1.0, 0.7, 0.4),
    ]
    .into_iter()
    .enumerate()
    {
        b.object(&format!("solid:crate.{k}"), |b| {
            let xf = Affine3A::from_rotation_translation(
                Quat::from_rotation_y(angle),
                Vec3::new(x, half, z),
            );
            b.boxed(xf, Vec3::splat(half), WOOD);
        });
    }
}
