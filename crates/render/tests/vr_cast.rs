//! The beam caster (HVVR §5.3-5.5) against per-ray BVH traversal of the same subsample rays, for
//! every sampling scheme of HVVR's Table 5, on atrium and cornell at 96 x 64, spp 1 and 4.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_render::vr::{Hierarchy, SampleSet, VisibilityBuffer, cast, cast_with, trace_per_ray};
use parallax_scene::Scene;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};

const W: u32 = 96;
const H: u32 = 64;

fn camera(scene: &Scene, kind: ModelKind, w: u32, h: u32) -> Camera {
    let desc = scene.camera(None).unwrap();
    Camera::new(kind, &desc, w, h, &CameraOptions::default()).unwrap()
}

/// `(name, set)` for every scheme.
fn schemes(scene: &Scene, spp: u32) -> Vec<(&'static str, SampleSet)> {
    vec![
        (
            "grid",
            SampleSet::grid(camera(scene, ModelKind::Pinhole, W, H), spp),
        ),
        (
            "distorted",
            SampleSet::distorted(camera(scene, ModelKind::Distorted, W, H), spp).unwrap(),
        ),
        (
            "foveated",
            SampleSet::foveated(
                camera(scene, ModelKind::Pinhole, W, H),
                Vec2::new(40.0, 30.0),
                10.0,
                0.15,
                spp,
            )
            .unwrap(),
        ),
        (
            "fisheye",
            SampleSet::wide_fov(camera(scene, ModelKind::Fisheye, W, H), spp).unwrap(),
        ),
        (
            "thinlens",
            SampleSet::depth_of_field(camera(scene, ModelKind::ThinLens, W, H), spp).unwrap(),
        ),
        (
            "stereo",
            SampleSet::grid(camera(scene, ModelKind::Stereo, W / 2, H), spp),
        ),
    ]
}

#[test]
fn beam_caster_equals_per_ray_traversal_for_every_scheme() {
    for name in ["atrium", "cornell"] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        for spp in [1, 4] {
            for (scheme, set) in schemes(&scene, spp) {
                let h = Hierarchy::build(&set).unwrap();
                let mut beam = VisibilityBuffer::new(&set);
                let stats = cast(&bvh, &set, &h, &mut beam);
                // The one-ray and 8-lane kernels give the same buffer as the default (4 lanes).
                for lanes in [1, 8] {
                    let mut other = VisibilityBuffer::new(&set);
                    cast_with(&bvh, &set, &h, &mut other, lanes);
                    assert_eq!(
                        other, beam,
                        "{name} {scheme} spp {spp}: {lanes}-lane kernel differs"
                    );
                }
                let mut reference = VisibilityBuffer::new(&set);
                trace_per_ray(&bvh, &set, &mut reference);
                let agree = beam.agreement(&reference);
                let hits = reference.prim.iter().filter(|&&p| p != u32::MAX).count();
                let same_t = beam
                    .t
                    .iter()
                    .zip(&reference.t)
                    .zip(beam.prim.iter().zip(&reference.prim))
                    .filter(|((a, b), (p, q))| p == q && a.to_bits() == b.to_bits())
                    .count();
                eprintln!(
                    "{name} {scheme} spp {spp}: {} samples, {} tiles, {} blocks, agreement {agree:.6}, \
                     {hits} hits, {} leaf tests / ray",
                    set.samples.len(),
                    h.tiles.len(),
                    h.blocks.len(),
                    stats.leaf_tests as f64 / stats.rays.max(1) as f64
                );
                assert!(
                    hits > beam.prim.len() / 50,
                    "{name} {scheme}: scene not in view"
                );
                assert!(
                    agree >= 0.9999,
                    "{name} {scheme} spp {spp}: agreement {agree}"
                );
                // Same triangle means the same watertight test: the same t, bit for bit.
                let same_prim = beam
                    .prim
                    .iter()
                    .zip(&reference.prim)
                    .filter(|(a, b)| a == b)
                    .count();
                assert_eq!(same_t, same_prim, "{name} {scheme} spp {spp}");
            }
        }
    }
}

#[test]
fn fast_subsample_rays_are_bit_identical() {
    let scene = Scene::load("atrium").unwrap();
    for kind in [
        ModelKind::Pinhole,
        ModelKind::Stereo,
        ModelKind::ThinLens,
        ModelKind::Fisheye,
        ModelKind::Distorted,
    ] {
        let set = SampleSet::grid(camera(&scene, kind, 24, 16), 8);
        for i in 0..set.samples.len() {
            for k in 0..8 {
                let (a, b) = (set.fast_subsample_ray(i, k), set.subsample_ray(i, k));
                assert_eq!(a.is_some(), b.is_some());
                if let (Some(a), Some(b)) = (a, b) {
                    assert_eq!(
                        a.origin.to_array().map(f32::to_bits),
                        b.origin.to_array().map(f32::to_bits)
                    );
                    assert_eq!(
                        a.dir.to_array().map(f32::to_bits),
                        b.dir.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }
}

#[test]
fn wrong_cameras_are_refused() {
    let scene = Scene::load("cornell").unwrap();
    let pin = camera(&scene, ModelKind::Pinhole, 16, 16);
    assert!(SampleSet::distorted(pin.clone(), 1).is_err());
    assert!(SampleSet::wide_fov(pin.clone(), 1).is_err());
    assert!(SampleSet::depth_of_field(pin.clone(), 1).is_err());
    assert!(SampleSet::foveated(pin, Vec2::ZERO, -1.0, 0.1, 1).is_err());
}
