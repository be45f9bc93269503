//! Shared test helpers: procedural meshes, random rays, and the BVH-vs-brute-force comparison.
#![allow(dead_code)]

use glam::{Vec2, Vec3};
use parallax_bvh::{Bvh, Hit, brute_force_all, brute_force_closest};
use parallax_core::Ray;
use parallax_scene::{ObjectRange, TriangleMesh};

/// A small deterministic generator (PCG-style LCG with an output hash).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03)
    }

    pub fn next_u32(&mut self) -> u32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = ((self.0 >> 18) ^ self.0) >> 27;
        (x as u32).rotate_right((self.0 >> 59) as u32)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }

    pub fn vec3_in(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
        Vec3::new(
            self.range(lo.x, hi.x),
            self.range(lo.y, hi.y),
            self.range(lo.z, hi.z),
        )
    }

    /// Uniform unit vector.
    pub fn dir(&mut self) -> Vec3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, std::f32::consts::TAU);
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// A mesh from positions and indices (no normals, zero uvs, material 0, one object).
pub fn mesh_from(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> TriangleMesh {
    let n = positions.len();
    let t = indices.len();
    TriangleMesh {
        normals: vec![Vec3::ZERO; n],
        uvs: vec![Vec2::ZERO; n],
        material_ids: vec![0; t],
        objects: vec![ObjectRange {
            name: "object".into(),
            first_triangle: 0,
            triangle_count: t as u32,
            first_vertex: 0,
            vertex_count: n as u32,
        }],
        positions,
        indices,
    }
}

/// `n` random triangles of size up to `size` in the cube [-1, 1]^3.
pub fn soup(n: usize, size: f32, seed: u64) -> TriangleMesh {
    let mut rng = Rng::new(seed);
    let mut p = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let c = rng.vec3_in(Vec3::splat(-1.0), Vec3::ONE);
        for _ in 0..3 {
            p.push(c + rng.vec3_in(Vec3::splat(-size), Vec3::splat(size)));
        }
    }
    let idx = (0..n as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    mesh_from(p, idx)
}

/// A regular `n x n` grid of quads in the plane y = 0 over [-1, 1]^2 (shared vertices).
pub fn grid(n: u32) -> TriangleMesh {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(Vec3::new(
                -1.0 + 2.0 * i as f32 / n as f32,
                0.0,
                -1.0 + 2.0 * j as f32 / n as f32,
            ));
        }
    }
    let mut idx = Vec::new();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            idx.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            idx.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    mesh_from(p, idx)
}

/// The cube [-1, 1]^3 as 12 outward-facing triangles with 8 shared vertices.
pub fn cube() -> TriangleMesh {
    let p: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                if i & 1 != 0 { 1.0 } else { -1.0 },
                if i & 2 != 0 { 1.0 } else { -1.0 },
                if i & 4 != 0 { 1.0 } else { -1.0 },
            )
        })
        .collect();
    let quads = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    let mut idx = Vec::new();
    for q in quads {
        idx.push([q[0], q[1], q[2]]);
        idx.push([q[0], q[2], q[3]]);
    }
    mesh_from(p, idx)
}

/// An icosphere of radius 1 around the origin, `subdiv` times subdivided (shared vertices,
/// closed, convex).
pub fn icosphere(subdiv: u32) -> TriangleMesh {
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut idx: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdiv {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize());
                p.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(idx.len() * 4);
        for [a, b, c] in idx {
            let ab = midpoint(a, b, &mut p);
            let bc = midpoint(b, c, &mut p);
            let ca = midpoint(c, a, &mut p);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        idx = next;
    }
    mesh_from(p, idx)
}

/// A UV sphere (latitude-longitude) of radius 1 with shared poles and seam: closed, convex.
pub fn uv_sphere(rings: u32, segments: u32) -> TriangleMesh {
    let mut p = vec![Vec3::Y];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            p.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            ));
        }
    }
    p.push(-Vec3::Y);
    let south = p.len() as u32 - 1;
    let v = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut idx = Vec::new();
    for s in 0..segments {
        idx.push([0, v(1, s), v(1, s + 1)]);
        idx.push([south, v(rings - 1, s + 1), v(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            idx.push([v(r, s), v(r + 1, s), v(r + 1, s + 1)]);
            idx.push([v(r, s), v(r + 1, s + 1), v(r, s + 1)]);
        }
    }
    mesh_from(p, idx)
}

/// Unit cubes on a `n^3` lattice with spacing 3 (many box faces that
/// axis-parallel rays can lie in).
pub fn cube_lattice(n: u32) -> TriangleMesh {
    let c = cube();
    let mut m = TriangleMesh::default();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let mut ci = c.clone();
                let off = Vec3::new(i as f32, j as f32, k as f32) * 3.0;
                for p in &mut ci.positions {
                    *p = *p * 0.5 + off;
                }
                m.append(&ci, 0);
            }
        }
    }
    m
}

/// Random rays with origins in `lo..hi` and uniform directions.
pub fn random_rays(n: usize, lo: Vec3, hi: Vec3, seed: u64) -> Vec<Ray> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| Ray::new(rng.vec3_in(lo, hi), rng.dir()))
        .collect()
}

/// Asserts the BVH's closest hit is brute force's, exactly: both miss, or both hit the same
/// primitive with the same record (an exact `t` tie goes to the lowest primitive id in both,
/// whatever the tree). Also checks `any_hit` against it.
pub fn check_closest(bvh: &Bvh, mesh: &TriangleMesh, ray: &Ray, what: &str) -> Option<Hit> {
    let a = bvh.closest_hit(ray);
    let b = brute_force_closest(mesh, ray);
    assert_eq!(a, b, "{what}: bvh vs brute force for {ray:?}");
    assert_eq!(
        bvh.any_hit(ray),
        b.is_some(),
        "{what}: any_hit disagrees for {ray:?}"
    );
    a
}

/// Asserts `all_hits` equals the brute-force hit list (same primitives in the same order).
pub fn check_all(bvh: &Bvh, mesh: &TriangleMesh, ray: &Ray, what: &str) -> usize {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    bvh.all_hits(ray, &mut a);
    brute_force_all(mesh, ray, &mut b);
    assert_eq!(a, b, "{what}: all hits differ for {ray:?}");
    a.len()
}
