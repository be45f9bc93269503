//! The rays of DIRT Table 1 (Vardis et al. 2017, §5.2 "Impact of ray coherence"): one ray of
//! each type from every primary hit of the camera ("the first path event"), generated once and
//! traced by every structure:
//!
//! - visibility: towards a fixed point outside the scene's extents, ending there (occlusion
//!   queries: "terminated at the first intersection");
//! - specular: a perfect mirror's sample ([`Bsdf::Mirror`]);
//! - glossy: "BSDF importance sampling" of a rough metal ([`Bsdf::MetallicRoughness`] with
//!   metallic 1: GGX visible normals, Heitz 2018), roughness below;
//! - diffuse: a Lambertian's sample ([`Bsdf::Lambert`]: cosine-weighted hemisphere).
//!
//! The samplers are the path tracer's ([`parallax_render::bsdf`]), in the shading frame of the
//! hit. Primary hits come from the tracer given (the BVH), surfaces from the scene
//! ([`SurfacePoint`]), origins are offset off the surface ([`SurfacePoint::spawn_origin`]).
//! Directions below the geometric surface (a shading normal far from the geometric one) are
//! dropped. Random numbers come from per-pixel streams, so the rays do not depend on the
//! thread count.
//!
//! | option | type | default | meaning |
//! |---|---|---|---|
//! | `seed` | u64 | 1 | seed of the per-pixel streams |
//! | `glossy_roughness` | f32 | 0.3 | glTF perceptual roughness of the glossy rays (GGX `alpha` = roughness²) |

use glam::{Vec2, Vec3};
use parallax_core::math::Frame;
use parallax_core::sampling::Rng;
use parallax_core::{Ray, WorldStats, WorldTracer};
use parallax_render::bsdf::{Bsdf, MetallicRoughness};
use parallax_render::reference::surface::SurfacePoint;
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraModel};
use rayon::prelude::*;
use serde::Serialize;

/// The four ray types of DIRT Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayType {
    Visibility,
    Specular,
    Glossy,
    Diffuse,
}

impl RayType {
    pub const ALL: [RayType; 4] = [
        RayType::Visibility,
        RayType::Specular,
        RayType::Glossy,
        RayType::Diffuse,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayType::Visibility => "visibility",
            RayType::Specular => "specular",
            RayType::Glossy => "glossy",
            RayType::Diffuse => "diffuse",
        }
    }

    /// Visibility rays are occlusion queries; the others closest-hit queries.
    pub fn is_occlusion(self) -> bool {
        self == RayType::Visibility
    }
}

/// Options of [`ray_sets`] (see the module table).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RayOptions {
    pub seed: u64,
    pub glossy_roughness: f32,
}

impl Default for RayOptions {
    fn default() -> Self {
        Self {
            seed: 1,
            glossy_roughness: 0.3,
        }
    }
}

/// The rays of one type.
#[derive(Clone, Debug)]
pub struct RaySet {
    pub kind: RayType,
    pub rays: Vec<Ray>,
}

/// The point visibility rays aim at: above the scene, outside its bounds.
pub fn visibility_target(scene: &Scene) -> Vec3 {
    let b = scene.mesh.bounds();
    let r = b.extent().length().max(1.0);
    b.center() + Vec3::new(0.3, 1.0, 0.2).normalize() * r
}

/// One ray of each type per primary hit of `camera` (pixel centres, row-major).
pub fn ray_sets(
    scene: &Scene,
    primary: &dyn WorldTracer,
    camera: &Camera,
    opts: &RayOptions,
) -> Vec<RaySet> {
    let (w, h) = (camera.width(), camera.height());
    let light = visibility_target(scene);
    let bsdfs = [
        Bsdf::Mirror { tint: Vec3::ONE },
        Bsdf::MetallicRoughness(MetallicRoughness::new(
            Vec3::ONE,
            1.0,
            opts.glossy_roughness,
        )),
        Bsdf::Lambert { albedo: Vec3::ONE },
    ];
    let per_pixel: Vec<[Option<Ray>; 4]> = (0..h)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).map(move |x| {
                let film = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let mut none = [None; 4];
                let Some(cr) = camera.generate_ray(film, Vec2::splat(0.5), 1) else {
                    return none;
                };
                let Some(hit) = primary.closest_hit(&cr.ray, &mut WorldStats::default()) else {
                    return none;
                };
                let sp = SurfacePoint::from_world_hit(scene, &cr.ray, &hit);
                let (n, ng) = (sp.shading_normal, sp.geometric_normal);
                let mut rng = Rng::for_pixel(opts.seed, x, y, 0);
                let frame = Frame::from_normal(n);
                let wo = frame.to_local(-cr.ray.dir.normalize());
                let mut dirs = [
                    (light - sp.position).normalize(),
                    Vec3::ZERO,
                    Vec3::ZERO,
                    Vec3::ZERO,
                ];
                for (d, bsdf) in dirs[1..].iter_mut().zip(&bsdfs) {
                    let (u_lobe, u) = (rng.next_f32(), rng.next_vec2());
                    if let Some(s) = bsdf.sample(wo, u_lobe, u) {
                        *d = frame.to_world(s.wi);
                    }
                }
                for (k, d) in dirs.into_iter().enumerate() {
                    if d != Vec3::ZERO && d.is_finite() && d.dot(ng) > 0.0 {
                        let o = sp.spawn_origin(d);
                        none[k] = Some(if k == 0 {
                            Ray::segment(o, d, 0.0, (light - o).length())
                        } else {
                            Ray::new(o, d)
                        });
                    }
                }
                none
            })
        })
        .collect();
    RayType::ALL
        .iter()
        .enumerate()
        .map(|(k, &kind)| RaySet {
            kind,
            rays: per_pixel.iter().filter_map(|p| p[k]).collect(),
        })
        .collect()
}
