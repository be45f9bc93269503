//! What a hit means: position, normals, texture coordinates and material at the hit point.

use glam::{Vec2, Vec3};
use parallax_bvh::Hit;
use parallax_core::{HitSurface, NO_ID, Ray, WorldHit};
use parallax_scene::{Material, Scene};

/// The material of sampled hits whose capture kept no material id: rough, non-metallic.
static SAMPLED_DEFAULT: std::sync::LazyLock<Material> =
    std::sync::LazyLock::new(|| Material::diffuse("sampled", Vec3::ONE));

/// The surface seen by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint<'a> {
    pub position: Vec3,
    /// Geometric normal, flipped to face the incoming ray.
    pub geometric_normal: Vec3,
    /// Interpolated shading normal, on the same side as `geometric_normal`.
    pub shading_normal: Vec3,
    pub uv: Vec2,
    pub albedo: Vec3,
    pub material: &'a Material,
    pub material_id: u32,
    /// True when the ray hit the side the triangle's winding calls the front.
    pub front_face: bool,
}

impl<'a> SurfacePoint<'a> {
    pub fn new(scene: &'a Scene, ray: &Ray, hit: &Hit) -> Self {
        Self::on_triangle(scene, ray, hit.prim, hit.t, Vec2::new(hit.u, hit.v))
    }

    /// The surface of a world-space tracer's hit (the fetch pass of DIRT §4.2): exact hits
    /// read normals, material and texture from the scene by primitive and barycentrics;
    /// sampled hits take the stored sample's normal, albedo and material (the primitive's
    /// material where the sample has none but knows its primitive).
    pub fn from_world_hit(scene: &'a Scene, ray: &Ray, hit: &WorldHit) -> Self {
        match hit.surface {
            HitSurface::Exact => Self::on_triangle(scene, ray, hit.prim, hit.t, hit.barycentrics),
            HitSurface::Sampled(sample) => {
                let n = sample.normal.normalize_or(-ray.dir.normalize_or_zero());
                let front_face = n.dot(ray.dir) < 0.0;
                let n = if front_face { n } else { -n };
                // The sample's material, else its primitive's, else a rough diffuse default.
                let id = match sample.material_id {
                    NO_ID => scene
                        .mesh
                        .material_ids
                        .get(hit.prim as usize)
                        .copied()
                        .unwrap_or(NO_ID),
                    id => id,
                };
                let (material, material_id) = match scene.materials.get(id as usize) {
                    Some(m) => (m, id),
                    None => (&*SAMPLED_DEFAULT, NO_ID),
                };
                Self {
                    position: hit.position,
                    geometric_normal: n,
                    shading_normal: n,
                    uv: Vec2::ZERO,
                    albedo: sample.albedo,
                    material,
                    material_id,
                    front_face,
                }
            }
        }
    }

    fn on_triangle(scene: &'a Scene, ray: &Ray, prim: u32, t: f32, bary: Vec2) -> Self {
        let prim = prim as usize;
        let hit = Hit {
            prim: prim as u32,
            t,
            u: bary.x,
            v: bary.y,
        };
        let mesh = &scene.mesh;
        let position = ray.at(hit.t);
        let ng = mesh.geometric_normal(prim);
        let front_face = ng.dot(ray.dir) < 0.0;
        let flip = if front_face { 1.0 } else { -1.0 };
        // `TriangleMesh::shading_normal` with the geometric normal computed once.
        let [i0, i1, i2] = mesh.indices[prim];
        let n = mesh.normals[i0 as usize] * (1.0 - hit.u - hit.v)
            + mesh.normals[i1 as usize] * hit.u
            + mesh.normals[i2 as usize] * hit.v;
        let mut ns = n.normalize_or(ng) * flip;
        // Keep the shading normal in the hemisphere of the geometric one (no black facets).
        if ns.dot(ng * flip) <= 0.0 {
            ns = ng * flip;
        }
        let uv = mesh.uv(prim, hit.u, hit.v);
        let material_id = mesh.material_ids[prim];
        let material = &scene.materials[material_id as usize];
        let mut albedo = material.base_color;
        if let Some(t) = material.base_color_texture {
            albedo *= scene.textures[t as usize].sample(uv);
        }
        Self {
            position,
            geometric_normal: ng * flip,
            shading_normal: ns,
            uv,
            albedo,
            material,
            material_id,
            front_face,
        }
    }

    /// An origin for a ray leaving the surface towards `dir`: offset along the geometric
    /// normal by an amount that scales with the magnitude of the position (float spacing),
    /// so secondary rays do not re-hit the surface they start on.
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        let scale = 1e-4 * self.position.abs().max_element().max(1.0);
        let side = if dir.dot(self.geometric_normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        self.position + self.geometric_normal * (scale * side)
    }
}

#[cfg(test)]
mod tests {
    use parallax_bvh::Bvh;
    use parallax_core::{SampledSurface, WorldStats, WorldTracer};

    use super::*;

    #[test]
    fn world_hits_fetch_the_scene_or_the_sample() {
        let scene = Scene::load("cornell").unwrap();
        let bvh = Bvh::build(&scene.mesh);
        let cam = &scene.cameras[0].desc;
        let ray = Ray::new(cam.eye, (cam.target - cam.eye).normalize());
        let direct = SurfacePoint::new(&scene, &ray, &bvh.closest_hit(&ray).unwrap());
        let hit = WorldTracer::closest_hit(&bvh, &ray, &mut WorldStats::default()).unwrap();
        let fetched = SurfacePoint::from_world_hit(&scene, &ray, &hit);
        assert_eq!(fetched.position, direct.position);
        assert_eq!(fetched.shading_normal, direct.shading_normal);
        assert_eq!(fetched.material_id, direct.material_id);
        // A sampled hit without a material id takes its primitive's material; the normal is
        // turned to face the ray.
        let sampled = WorldHit {
            surface: HitSurface::Sampled(SampledSurface {
                normal: -direct.geometric_normal,
                albedo: Vec3::new(0.1, 0.2, 0.3),
                material_id: NO_ID,
            }),
            ..hit
        };
        let s = SurfacePoint::from_world_hit(&scene, &ray, &sampled);
        assert_eq!(s.material_id, direct.material_id);
        assert_eq!(s.albedo, Vec3::new(0.1, 0.2, 0.3));
        assert!(s.geometric_normal.dot(ray.dir) < 0.0);
        let unknown = WorldHit {
            prim: NO_ID,
            ..sampled
        };
        assert_eq!(
            SurfacePoint::from_world_hit(&scene, &ray, &unknown).material_id,
            NO_ID
        );
    }
}
