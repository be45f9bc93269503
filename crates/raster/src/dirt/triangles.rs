//! DIRT's vertex buffer (Vardis et al. 2017, §3 "Data structures" (iii) and §4.1.2 "Fill
//! Primitives"): the three corners of every triangle, in the order of the mesh, so that an
//! entry `id` of an id buffer ([`super::DirtCapture::ids`]) names `triangles[id]`. The tracer
//! intersects rays with these corners analytically and never reads the scene, as the GPU
//! version reads the vertex buffer its geometry pass filled.
//!
//! **Invariant:** corner `k` of triangle `i` is bit for bit `mesh.triangle(i)[k]`, so an
//! intersection with the same ray-triangle test gives the same `t` and barycentrics as any
//! other structure built from the mesh (the BVH).

use glam::Vec3;
use parallax_core::Aabb;
use parallax_scene::TriangleMesh;
use rayon::prelude::*;

/// One triangle's corners.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct DirtTri {
    pub p0: Vec3,
    pub p1: Vec3,
    pub p2: Vec3,
}

/// The triangle buffer every view's id buffer indexes.
#[derive(Clone, Debug, Default)]
pub struct DirtTriangles {
    tris: Vec<DirtTri>,
    bounds: Aabb,
}

impl DirtTriangles {
    /// Gathers the corners of every triangle of `mesh` (in parallel), growing the bounds of
    /// the finite ones in the same pass (corner by corner, in order).
    pub fn from_mesh(mesh: &TriangleMesh) -> DirtTriangles {
        const CHUNK: usize = 4096;
        let mut tris = vec![DirtTri::default(); mesh.triangle_count()];
        let bounds = tris
            .par_chunks_mut(CHUNK)
            .enumerate()
            .map(|(c, out)| {
                let mut b = Aabb::EMPTY;
                for (i, o) in (c * CHUNK..).zip(out) {
                    let [p0, p1, p2] = mesh.triangle(i);
                    *o = DirtTri { p0, p1, p2 };
                    if p0.is_finite() && p1.is_finite() && p2.is_finite() {
                        b = b.grow(p0).grow(p1).grow(p2);
                    } else {
                        b = [p0, p1, p2]
                            .into_iter()
                            .filter(|p| p.is_finite())
                            .fold(b, Aabb::grow);
                    }
                }
                b
            })
            .reduce(|| Aabb::EMPTY, Aabb::union);
        DirtTriangles { tris, bounds }
    }

    /// Number of triangles.
    #[inline]
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Triangle `id` (an id buffer entry).
    #[inline(always)]
    pub fn get(&self, id: u32) -> &DirtTri {
        &self.tris[id as usize]
    }

    /// All triangles, indexed by id.
    #[inline]
    pub fn as_slice(&self) -> &[DirtTri] {
        &self.tris
    }

    /// Bounds of every finite corner (empty for an empty buffer): a ray that leaves this box
    /// meets no triangle (the far plane of the views, "scene length" in the GPU version).
    #[inline]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes held (the corners).
    pub fn bytes(&self) -> u64 {
        std::mem::size_of_val(self.tris.as_slice()) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_are_the_mesh_corners() {
        let scene = parallax_scene::Scene::load("cornell").unwrap();
        let t = DirtTriangles::from_mesh(&scene.mesh);
        assert_eq!(t.len(), scene.mesh.triangle_count());
        for i in 0..t.len() {
            let [a, b, c] = scene.mesh.triangle(i);
            assert_eq!(
                *t.get(i as u32),
                DirtTri {
                    p0: a,
                    p1: b,
                    p2: c
                }
            );
        }
        let mb = scene.mesh.bounds();
        assert_eq!((t.bounds().min, t.bounds().max), (mb.min, mb.max));
        assert_eq!(t.bytes(), 36 * t.len() as u64);
        assert!(
            DirtTriangles::from_mesh(&TriangleMesh::default())
                .bounds()
                .is_empty()
        );
    }

    /// The bounds grown in the gathering pass equal, bit for bit, the fold over every finite
    /// corner (chunk by chunk, then the chunks' union), on a mesh of several chunks with
    /// non-finite corners beside finite ones; the extreme corners sit in triangles with a
    /// non-finite corner, so skipping those triangles (or not filtering) fails.
    #[test]
    fn bounds_are_the_fold_over_the_finite_corners() {
        let mut rng = parallax_core::Rng::new(3, 11);
        let mut mesh = TriangleMesh::default();
        for i in 0..3 * 10_000u32 {
            let mut c = || (rng.next_f32() - 0.5) * 100.0;
            let p = match i % 97 {
                0 => Vec3::new(f32::NAN, c(), c()),
                1 => Vec3::new(c(), f32::INFINITY, c()),
                _ => Vec3::new(c(), c(), c()),
            };
            mesh.positions.push(p);
        }
        // Finite extremes beside a NaN corner (positions 0 and 3 * 97 are NaN ones).
        mesh.positions[1] = Vec3::splat(1e3);
        mesh.positions[3 * 97 + 2] = Vec3::splat(-1e3);
        mesh.indices = (0..10_000u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        mesh.material_ids = vec![0; 10_000];
        let t = DirtTriangles::from_mesh(&mesh);
        let reference = (0..10_000)
            .collect::<Vec<_>>()
            .chunks(4096)
            .map(|c| {
                c.iter()
                    .flat_map(|&i| mesh.triangle(i))
                    .filter(|p| p.is_finite())
                    .fold(Aabb::EMPTY, Aabb::grow)
            })
            .fold(Aabb::EMPTY, Aabb::union);
        let bits = |b: Aabb| {
            (
                b.min.to_array().map(f32::to_bits),
                b.max.to_array().map(f32::to_bits),
            )
        };
        assert_eq!(bits(t.bounds()), bits(reference));
        assert_eq!(
            (t.bounds().min, t.bounds().max),
            (Vec3::splat(-1e3), Vec3::splat(1e3))
        );
    }
}
