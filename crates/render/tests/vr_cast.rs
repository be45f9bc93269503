//! The beam caster (HVVR §5.3-5.5) against per-ray BVH traversal of the same subsample rays, for
//! every sampling scheme of HVVR's Table 5, on atrium and cornell at 96 x 64, spp 1 and 4.

use glam::Vec2;
use parallax_bvh::Bvh;
use parallax_render::vr::{
    CastOptions, Hierarchy, SampleSet, SampleTest, VisibilityBuffer, cast, cast_opts, cast_with,
    trace_per_ray,
};
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
                let stats = cast_with(&bvh, &set, &h, &mut beam, 4);
                // The one-ray and 8-lane kernels give the same buffer as the 4-lane one.
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

/// `(agreement, max relative t difference on equal triangles)` of two buffers.
fn compare(a: &VisibilityBuffer, b: &VisibilityBuffer) -> (f64, f32) {
    let mut max_rel = 0.0f32;
    for ((p, q), (s, t)) in a.prim.iter().zip(&b.prim).zip(a.t.iter().zip(&b.t)) {
        if p == q && *p != u32::MAX {
            max_rel = max_rel.max((s - t).abs() / t.abs().max(1e-6));
        }
    }
    (a.agreement(b), max_rel)
}

/// `(edge ties, other differences)`: differing triangles at `t` equal within 1e-5 relative,
/// and every other difference (hit vs miss, or another depth).
fn differences(a: &VisibilityBuffer, b: &VisibilityBuffer) -> (usize, usize) {
    let (mut ties, mut others) = (0, 0);
    for ((p, q), (s, t)) in a.prim.iter().zip(&b.prim).zip(a.t.iter().zip(&b.t)) {
        if p != q {
            if (s - t).abs() <= 1e-5 * t.abs() {
                ties += 1;
            } else {
                others += 1;
            }
        }
    }
    (ties, others)
}

/// HVVR's per-tile triangle set-up (`tile_setup.rs`, the default sample test) against the exact
/// watertight kernel and per-ray traversal: >= 99.99% of subsamples agree for every scheme (the
/// rest on edges), equal triangles have equal `t` within 1e-5 relative, and the 4- and 8-lane
/// set-up kernels give the same buffer.
#[test]
fn tile_setup_kernel_agrees_with_watertight_kernel_for_every_scheme() {
    for name in ["atrium", "cornell"] {
        let scene = Scene::load(name).unwrap();
        let bvh = Bvh::build(&scene.mesh);
        for spp in [1, 4] {
            for (scheme, set) in schemes(&scene, spp) {
                let h = Hierarchy::build(&set).unwrap();
                let mut exact = VisibilityBuffer::new(&set);
                cast_with(&bvh, &set, &h, &mut exact, 4);
                let mut setup = VisibilityBuffer::new(&set);
                let stats = cast(&bvh, &set, &h, &mut setup);
                assert_eq!(CastOptions::default().test, SampleTest::TileSetup);
                for lanes in [4, 8] {
                    let mut other = VisibilityBuffer::new(&set);
                    let opts = CastOptions {
                        test: SampleTest::TileSetup,
                        lanes,
                    };
                    cast_opts(&bvh, &set, &h, &mut other, opts);
                    assert_eq!(other, setup, "{name} {scheme} spp {spp}: {lanes} lanes");
                }
                let mut reference = VisibilityBuffer::new(&set);
                trace_per_ray(&bvh, &set, &mut reference);
                let (agree, rel) = compare(&setup, &exact);
                if std::env::var("VR_DIAG").is_ok() {
                    for j in 0..setup.prim.len() {
                        if setup.prim[j] != exact.prim[j] {
                            eprintln!(
                                "  diff {j}: setup {} t {} | exact {} t {}",
                                setup.prim[j], setup.t[j], exact.prim[j], exact.t[j]
                            );
                        }
                    }
                }
                let (agree_ref, rel_ref) = compare(&setup, &reference);
                let tris = stats.tris_all_out + stats.tris_partial + stats.tris_all_in;
                eprintln!(
                    "{name} {scheme} spp {spp}: set-up tiles {}/{}, agreement with watertight \
                     {agree:.6} (t rel {rel:.2e}), with per-ray {agree_ref:.6}; triangles all-out \
                     {:.3} partial {:.3} all-in {:.3}; {:.2} packet tests / ray",
                    stats.setup_tiles,
                    stats.tiles,
                    stats.tris_all_out as f64 / tris.max(1) as f64,
                    stats.tris_partial as f64 / tris.max(1) as f64,
                    stats.tris_all_in as f64 / tris.max(1) as f64,
                    stats.tri_tests as f64 / stats.rays.max(1) as f64,
                );
                if scheme == "thinlens" && spp > 1 {
                    // (At spp 1 every ray starts at the lens centre: one origin.)
                    assert_eq!(stats.setup_tiles, 0, "thin-lens tiles share no origin");
                    assert_eq!(setup, exact);
                } else {
                    // Every tile with a beam shares its origin (EVERYTHING tiles, if any, not).
                    assert!(stats.setup_tiles * 10 >= stats.tiles * 9, "{name} {scheme}");
                }
                // Every difference but 0.01% of the samples must be a tie: another triangle
                // hit at the same `t` (1e-5 relative) — a shared edge, or coplanar overlapping
                // faces (cornell's blocks stand on the floor with coplanar bottom faces: 0.3%
                // of its samples, decided by 1-ulp differences of `t` in either kernel).
                let (ties, others) = differences(&setup, &reference);
                let n = setup.prim.len() as f64;
                assert!(agree >= 0.99, "{name} {scheme} spp {spp}: {agree}");
                assert!(agree_ref >= 0.99, "{name} {scheme} spp {spp}: {agree_ref}");
                assert!(
                    others as f64 <= 1e-4 * n,
                    "{name} {scheme} spp {spp}: {others} non-edge differences ({ties} edge ties)"
                );
                assert!(
                    rel <= 1e-5 && rel_ref <= 1e-5,
                    "{name} {scheme}: t {rel} {rel_ref}"
                );
            }
        }
    }
}
