//! Resolve: fragments (primitive id + barycentrics) -> G-buffer samples, computed exactly as the
//! BVH reference renderer's surface point (normal flipped towards the viewer, shading normal
//! kept in the geometric normal's hemisphere, albedo = base colour x texture at the
//! interpolated uv).

use glam::{Vec2, Vec3};
use parallax_core::image::{GBuffer, GSample};
use parallax_scene::Scene;
use rayon::prelude::*;

use crate::raster::{Fragment, Fragments, View};

/// The G-buffer sample of fragment `f` seen in `view` (a miss for an empty fragment).
pub fn resolve_fragment(scene: &Scene, view: &View, f: Fragment) -> GSample {
    let mesh = &scene.mesh;
    let prim = f.prim as usize;
    if f.is_empty() || prim >= mesh.indices.len() {
        return GSample::MISS;
    }
    let (u, v) = (f.b1, f.b2);
    let [p0, p1, p2] = mesh.triangle(prim);
    let position = p0 * (1.0 - u - v) + p1 * u + p2 * v;
    let ng = mesh.geometric_normal(prim);
    let flip = if ng.dot(view.ray_dir_to(position)) < 0.0 {
        1.0
    } else {
        -1.0
    };
    let mut normal = mesh.shading_normal(prim, u, v) * flip;
    if normal.dot(ng * flip) <= 0.0 {
        normal = ng * flip;
    }
    let material_id = mesh.material_ids.get(prim).copied().unwrap_or(0);
    let albedo = match scene.materials.get(material_id as usize) {
        Some(m) => {
            let mut a = m.base_color;
            if let Some(t) = m
                .base_color_texture
                .and_then(|t| scene.textures.get(t as usize))
            {
                a *= t.sample(mesh.uv(prim, u, v));
            }
            a
        }
        None => Vec3::splat(0.5),
    };
    GSample {
        depth: f.depth,
        position,
        normal,
        albedo,
        material_id,
        primitive_id: f.prim,
        barycentrics: Vec2::new(u, v),
    }
}

/// Resolves layer `k` of `frags` into `g` (same size), rows in parallel.
pub(crate) fn resolve_layer(
    scene: &Scene,
    view: &View,
    frags: &Fragments,
    k: usize,
    g: &mut GBuffer,
) {
    let w = g.width() as usize;
    let GBuffer {
        depth,
        position,
        normal,
        albedo,
        material_id,
        primitive_id,
        barycentrics,
        ..
    } = g;
    depth
        .par_chunks_mut(w)
        .zip(position.par_chunks_mut(w))
        .zip(normal.par_chunks_mut(w))
        .zip(albedo.par_chunks_mut(w))
        .zip(material_id.par_chunks_mut(w))
        .zip(primitive_id.par_chunks_mut(w))
        .zip(barycentrics.par_chunks_mut(w))
        .enumerate()
        .for_each(|(y, ((((((d, p), n), a), m), pr), b))| {
            for x in 0..w {
                let s = resolve_fragment(scene, view, frags.get(x as u32, y as u32, k));
                d[x] = s.depth;
                p[x] = s.position;
                n[x] = s.normal;
                a[x] = s.albedo;
                m[x] = s.material_id;
                pr[x] = s.primitive_id;
                b[x] = s.barycentrics;
            }
        });
}
