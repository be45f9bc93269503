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
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// Gathers the corners of every triangle of `mesh` (in parallel).
    pub fn from_mesh(mesh: &TriangleMesh) -> DirtTriangles {
        let tris: Vec<DirtTri> = (0..mesh.triangle_count())
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let [p0, p1, p2] = mesh.triangle(i);
                DirtTri { p0, p1, p2 }
            })
            .collect();
        let bounds = tris
            .par_chunks(4096)
            .map(|c| {
                c.iter().fold(Aabb::EMPTY, |b, t| {
                    [t.p0, t.p1, t.p2]
                        .into_iter()
                        .filter(|p| p.is_finite())
                        .fold(b, Aabb::grow)
                })
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
}
