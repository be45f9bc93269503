//! `foliage`: a grove of high depth complexity — many thin occluders.
//!
//! Trees (tapered trunks and branches, crowns of randomly oriented leaves), tall grass blades
//! and a slatted fence stand on a ground slab, so that a view ray from the main camera crosses
//! many surfaces (8-20+). Every leaf and blade is a thin *closed* solid (a flattened tetrahedron
//! or a tapered three-sided strand), so entering and leaving it are two surfaces and parity
//! (inside/outside) tests stay meaningful. All randomness comes from a local PCG32 with a fixed
//! seed: the scene is the same on every call.
//!
//! | parameter | value                                                          |
//! |-----------|----------------------------------------------------------------|
//! | ground    | 200 x 200 m slab, top at y = 0 (downward rays always end on it) |
//! | trees     | 20 on a jittered 5 x 4 grid, x in [-9, 9], z in [-12, 3], crowns ~1-6 m high |
//! | leaves    | 800 per tree (0.45-0.7 m leaf cards), 220 per bush (0.3-0.45 m), 1 cm fold |
//! | bushes    | 44, radius 0.8-1.3 m, x in [-7, 7], z in [-6, 3.5]               |
//! | grass     | 4000 leaning blades, 0.4-1.1 m tall, x in [-6, 6], z in [0, 9]  |
//! | fence     | 94 slats (9 x 2 cm, ~1.2 m tall) at z = 4.5, two rails behind  |
//! | main view | eye (0, 1.8, 9.5), fov 40: median depth complexity ~10 (tested >= 8) |
//! | triangles | about 132k                                                     |

use glam::Vec3;
use parallax_core::math::Frame;

use super::cameras::{named, path};
use super::shapes::MeshBuilder;
use crate::{Light, Material, Scene};

const GROUND: u32 = 0;
const BARK: u32 = 1;
const LEAF: [u32; 2] = [2, 3];
const GRASS: u32 = 4;
const WOOD: u32 = 5;

const TREES_X: usize = 5;
const TREES_Z: usize = 4;
const LEAVES_PER_TREE: usize = 800;
const BUSHES: usize = 44;
const LEAVES_PER_BUSH: usize = 220;
const GRASS_BLADES: usize = 4000;

/// PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
/// Algorithms for Random Number Generation", XSH RR variant): tiny, seeded, deterministic.
struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    fn new(seed: u64, stream: u64) -> Self {
        let mut r = Self {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    fn f(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [a, b).
    fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f()
    }

    /// Uniform direction on the unit sphere.
    fn unit(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("ground", Vec3::new(0.22, 0.17, 0.11)),
        Material::diffuse("bark", Vec3::new(0.28, 0.20, 0.13)),
        Material::diffuse("leaf_dark", Vec3::new(0.10, 0.30, 0.06)),
        Material::diffuse("leaf_light", Vec3::new(0.25, 0.45, 0.10)),
        Material::diffuse("grass", Vec3::new(0.20, 0.42, 0.09)),
        Material::diffuse("fence_wood", Vec3::new(0.55, 0.42, 0.28)),
    ]
}

/// One generated tree: where its crown is (for the cameras).
struct Tree {
    crown: Vec3,
}

/// Builds the scene.
pub fn build() -> Scene {
    let mut rng = Pcg32::new(0x5ee_df01_1a9e, 7);
    let mut b = MeshBuilder::new();
    b.reserve(175_000, 135_000);
    b.object("solid:ground", |b| {
        b.cuboid(
            Vec3::new(-100.0, -0.1, -100.0),
            Vec3::new(100.0, 0.0, 100.0),
            GROUND,
        )
    });
    let mut trees = Vec::with_capacity(TREES_X * TREES_Z);
    for iz in 0..TREES_Z {
        for ix in 0..TREES_X {
            let x = -9.0 + 18.0 * (ix as f32 + 0.5) / TREES_X as f32 + rng.range(-1.2, 1.2);
            let z = -12.0 + 15.0 * (iz as f32 + 0.5) / TREES_Z as f32 + rng.range(-1.0, 1.0);
            let k = trees.len();
            trees.push(tree(&mut b, &mut rng, k, Vec3::new(x, 0.0, z)));
        }
    }
    b.object("solid:bushes", |b| {
        for _ in 0..BUSHES {
            let r = rng.range(0.8, 1.3);
            let c = Vec3::new(rng.range(-7.0, 7.0), 0.7 * r, rng.range(-6.0, 3.5));
            let radii = Vec3::new(r, 0.7 * r, r);
            leaf_ball(b, &mut rng, c, radii, LEAVES_PER_BUSH, (0.3, 0.45));
        }
    });
    grass(&mut b, &mut rng);
    fence(&mut b);

    let close_crown = trees[TREES_X * (TREES_Z - 1) + 1].crown;
    let eye = |x: f32| Vec3::new(x, 1.8, 9.5);
    let look = |x: f32| Vec3::new(x, 0.7, -8.0);
    Scene {
        name: "foliage".into(),
        mesh: b.finish(),
        materials: materials(),
        lights: vec![Light::Directional {
            direction: Vec3::new(0.3, -1.0, -0.5).normalize(),
            irradiance: Vec3::new(4.5, 4.2, 3.8),
        }],
        environment: Vec3::new(0.55, 0.7, 0.95),
        cameras: vec![
            named("main", eye(0.0), look(0.0), 40.0),
            named(
                "close",
                close_crown + Vec3::new(1.5, 0.3, 3.5),
                close_crown,
                60.0,
            ),
            named(
                "side",
                Vec3::new(17.0, 2.5, -8.0),
                Vec3::new(-5.0, 1.6, -11.0),
                55.0,
            ),
        ],
        camera_path: Some(path(
            &[
                (0.0, eye(-2.0), look(-4.0)),
                (0.5, eye(-1.0), look(-2.0)),
                (1.0, eye(0.0), look(0.0)),
                (1.5, eye(1.0), look(2.0)),
                (2.0, eye(2.0), look(4.0)),
            ],
            40.0,
        )),
        ..Scene::default()
    }
}

/// A tree at `root`: trunk and branches (one object) and a crown of leaves (another).
fn tree(b: &mut MeshBuilder, rng: &mut Pcg32, k: usize, root: Vec3) -> Tree {
    let h = rng.range(2.2, 3.0);
    let r0 = rng.range(0.12, 0.18);
    let crown = root + Vec3::new(0.0, h + rng.range(0.8, 1.2), 0.0);
    let radii = Vec3::new(
        rng.range(2.0, 2.6),
        rng.range(2.2, 2.7),
        rng.range(2.0, 2.6),
    );
    b.object(&format!("solid:tree.{k}.wood"), |b| {
        b.cylinder(root, root + Vec3::Y * h, r0, 0.6 * r0, 12, BARK);
        for _ in 0..5 {
            let start = root + Vec3::Y * (h * rng.range(0.6, 0.95));
            let mut d = rng.unit();
            d.y = d.y.abs() * 0.8 + 0.2;
            let end = crown + d.normalize() * radii * 0.7;
            b.cylinder(start, end, 0.05, 0.02, 8, BARK);
        }
    });
    b.object(&format!("solid:tree.{k}.leaves"), |b| {
        leaf_ball(b, rng, crown, radii, LEAVES_PER_TREE, (0.45, 0.7));
    });
    Tree { crown }
}

/// `count` leaves uniformly in the ellipsoid `centre +- radii`, facing mostly up, each a
/// flattened tetrahedron: a rhombus of length in `len` and half its width, folded 1 cm along
/// the midrib (closed, so both sides are surfaces).
fn leaf_ball(
    b: &mut MeshBuilder,
    rng: &mut Pcg32,
    centre: Vec3,
    radii: Vec3,
    count: usize,
    len: (f32, f32),
) {
    for i in 0..count {
        // Rejection sampling with a bounded number of tries.
        let mut p = Vec3::ZERO;
        for _ in 0..16 {
            p = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                break;
            }
        }
        let c = centre + p * radii;
        let mut n = rng.unit();
        n.y = n.y.abs() + 0.3;
        let n = n.normalize();
        let frame = Frame::from_normal(n);
        let a = rng.range(0.0, std::f32::consts::TAU);
        let along = frame.x * a.cos() + frame.y * a.sin();
        let across = n.cross(along);
        let l = rng.range(len.0, len.1);
        let (hl, hw, t) = (0.5 * l, 0.25 * l, 0.01);
        b.tetra(
            [
                c - along * hl,
                c + along * hl,
                c + across * hw + n * t,
                c - across * hw + n * t,
            ],
            LEAF[i % 2],
        );
    }
}

/// Tall grass blades, bent by a random wind, in front of the trees.
fn grass(b: &mut MeshBuilder, rng: &mut Pcg32) {
    b.object("solid:grass", |b| {
        for _ in 0..GRASS_BLADES {
            let root = Vec3::new(rng.range(-6.0, 6.0), 0.0, rng.range(0.0, 9.0));
            let h = rng.range(0.4, 1.1);
            let lean = Vec3::new(rng.range(-0.35, 0.35), 0.0, rng.range(-0.35, 0.35)) * h;
            let tip = root + Vec3::Y * h + lean;
            let w = rng.range(0.02, 0.035);
            let a = rng.range(0.0, std::f32::consts::TAU);
            let across = Vec3::new(a.cos(), 0.0, a.sin());
            b.strand(&[root, tip], &[(w, 0.004), (0.0, 0.0)], across, 3, GRASS);
        }
    });
}

/// A slatted fence across the view at z = 4.5 with two rails behind the slats.
fn fence(b: &mut MeshBuilder) {
    const SLATS: usize = 94;
    const PITCH: f32 = 0.15;
    let x0 = -0.5 * PITCH * SLATS as f32;
    b.object("solid:fence.slats", |b| {
        for i in 0..SLATS {
            let x = x0 + PITCH * i as f32;
            // Slightly varying heights, like a weathered fence.
            let top = 1.2 + 0.04 * ((i as f32 * 1.7).sin());
            b.cuboid(Vec3::new(x, 0.0, 4.5), Vec3::new(x + 0.09, top, 4.52), WOOD);
        }
    });
    b.object("solid:fence.rails", |b| {
        let x1 = x0 + PITCH * SLATS as f32;
        for y in [0.3, 0.95] {
            b.cuboid(Vec3::new(x0, y, 4.45), Vec3::new(x1, y + 0.08, 4.5), WOOD);
        }
    });
}
