//! Procedural test meshes, so the baseline runs (and its tests pass) without any scene file.

use glam::Vec3;
use parallax_scene::TriangleMesh;

/// A small xorshift generator: deterministic meshes without a dependency.
struct XorShift(u64);

impl XorShift {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next_f32(), self.next_f32(), self.next_f32())
    }
}

/// `n` random triangles with corners within `size` of centres uniform in `[-1, 1]^3`.
pub fn random_triangles(n: usize, size: f32, seed: u64) -> TriangleMesh {
    let mut rng = XorShift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    let mut mesh = TriangleMesh::default();
    for i in 0..n {
        let c = rng.vec3() * 2.0 - 1.0;
        for _ in 0..3 {
            mesh.positions.push(c + (rng.vec3() * 2.0 - 1.0) * size);
        }
        let b = 3 * i as u32;
        mesh.indices.push([b, b + 1, b + 2]);
    }
    finish(mesh)
}

/// A UV sphere of radius `r` at the origin with `rings x segments` quads (two triangles each).
pub fn uv_sphere(r: f32, rings: u32, segments: u32) -> TriangleMesh {
    let (rings, segments) = (rings.max(2), segments.max(3));
    let mut mesh = TriangleMesh::default();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let (st, ct) = theta.sin_cos();
            let (sp, cp) = phi.sin_cos();
            mesh.positions.push(Vec3::new(st * cp, ct, st * sp) * r);
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * row + j, (i + 1) * row + j);
            mesh.indices.push([a, a + 1, b]);
            mesh.indices.push([a + 1, b + 1, b]);
        }
    }
    finish(mesh)
}

fn finish(mut mesh: TriangleMesh) -> TriangleMesh {
    mesh.normals = vec![Vec3::ZERO; mesh.positions.len()];
    mesh.uvs = vec![glam::Vec2::ZERO; mesh.positions.len()];
    mesh.material_ids = vec![0; mesh.indices.len()];
    mesh
}
