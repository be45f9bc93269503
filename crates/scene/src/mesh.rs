//! World-space triangle meshes.

use glam::{Vec2, Vec3};
use parallax_core::Aabb;

/// A named range of triangles (one glTF mesh primitive, one OBJ model, one built-in object):
/// the unit of rigid animation.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectRange {
    pub name: String,
    pub first_triangle: u32,
    pub triangle_count: u32,
    pub first_vertex: u32,
    pub vertex_count: u32,
}

/// All geometry of a scene in world space, as flat arrays (structure of arrays).
///
/// `normals` and `uvs` have one entry per vertex. A zero normal means "no shading normal":
/// use the geometric normal of the triangle (flat shading), as for meshes whose source file
/// has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
    /// Material index per triangle.
    pub material_ids: Vec<u32>,
    pub objects: Vec<ObjectRange>,
}

impl TriangleMesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Unit geometric normal of triangle `i` (right-hand rule on the vertex order); zero for a
    /// degenerate triangle.
    pub fn geometric_normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Interpolated shading normal at barycentrics `(u, v)`, falling back to the geometric
    /// normal where the vertices carry none.
    pub fn shading_normal(&self, i: usize, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.indices[i];
        let n = self.normals[a as usize] * (1.0 - u - v)
            + self.normals[b as usize] * u
            + self.normals[c as usize] * v;
        let n = n.normalize_or_zero();
        if n == Vec3::ZERO {
            self.geometric_normal(i)
        } else {
            n
        }
    }

    /// Interpolated texture coordinates at barycentrics `(u, v)`.
    pub fn uv(&self, i: usize, u: f32, v: f32) -> Vec2 {
        let [a, b, c] = self.indices[i];
        self.uvs[a as usize] * (1.0 - u - v) + self.uvs[b as usize] * u + self.uvs[c as usize] * v
    }

    /// Bounds of all vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }

    /// Appends `other`, offsetting its indices, objects and (by `material_offset`) materials.
    pub fn append(&mut self, other: &TriangleMesh, material_offset: u32) {
        let v0 = self.positions.len() as u32;
        let t0 = self.indices.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.uvs.extend_from_slice(&other.uvs);
        self.indices
            .extend(other.indices.iter().map(|t| t.map(|i| i + v0)));
        self.material_ids
            .extend(other.material_ids.iter().map(|m| m + material_offset));
        self.objects
            .extend(other.objects.iter().map(|o| ObjectRange {
                first_triangle: o.first_triangle + t0,
                first_vertex: o.first_vertex + v0,
                ..o.clone()
            }));
    }

    /// Checks the invariants: array lengths agree, indices in range, positions and normals
    /// finite, material ids below `material_count`. Returns a message naming the first problem.
    pub fn validate(&self, material_count: usize) -> Result<(), String> {
        let n = self.positions.len();
        if self.normals.len() != n || self.uvs.len() != n {
            return Err(format!(
                "{} positions but {} normals and {} uvs",
                n,
                self.normals.len(),
                self.uvs.len()
            ));
        }
        if self.material_ids.len() != self.indices.len() {
            return Err("one material id per triangle expected".into());
        }
        if n > u32::MAX as usize {
            return Err("more than 2^32 vertices".into());
        }
        if let Some((i, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(format!("vertex {i} has a non-finite position {p}"));
        }
        if let Some((i, p)) = self
            .normals
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(format!("vertex {i} has a non-finite normal {p}"));
        }
        if let Some((i, t)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(format!(
                "triangle {i} has index {:?} out of range ({n} vertices)",
                t
            ));
        }
        if let Some((i, m)) = self
            .material_ids
            .iter()
            .enumerate()
            .find(|(_, m)| **m as usize >= material_count)
        {
            return Err(format!(
                "triangle {i} uses material {m} but only {material_count} exist"
            ));
        }
        Ok(())
    }
}
