//! A hierarchy moved to a new head pose (`Hierarchy::repose`, `hierarchy/pose.rs`): every
//! subsample ray of the moved camera lies in its moved tile and block beams with no tolerance,
//! the exact cast through the moved hierarchy equals per-ray traversal of the moved camera, and
//! a hierarchy of another pose or set is refused.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_scene::camera::{Camera, CameraOptions, ModelKind};
use parallax_scene::{CameraDesc, Scene};
use parallax_vr::frame::{Visibility, visibility_into};
use parallax_vr::{
    CastOptions, Hierarchy, HierarchyError, SampleSet, SetupExactness, VisibilityBuffer, cast_opts,
    trace_per_ray,
};
use proptest::prelude::*;

/// A camera of `kind`; the thin lens focused at a fixed distance, so that moving it changes
/// only its pose (its default focus is the eye-to-target distance: another focus is new
/// intrinsics, which `repose` rebuilds).
fn camera(kind: ModelKind, eye: Vec3, target: Vec3, w: u32, h: u32, fov: f32) -> Camera {
    let desc = CameraDesc::new(eye, target, Vec3::Y, fov);
    let opts = CameraOptions {
        focus_distance: Some(3.0),
        ..CameraOptions::default()
    };
    Camera::new(kind, &desc, w, h, &opts).unwrap()
}

/// The models whose beams `Hierarchy::repose` moves without a rebuild.
const MOVABLE: [ModelKind; 5] = [
    ModelKind::Pinhole,
    ModelKind::Stereo,
    ModelKind::Distorted,
    ModelKind::Fisheye,
    ModelKind::ThinLens,
];

/// The set of `camera` at `spp`: per-channel samples for the distorted eye (HVVR's subpixel
/// grids), one grid otherwise.
fn set_of(camera: Camera, spp: u32) -> SampleSet {
    match camera {
        Camera::Distorted(_) => SampleSet::distorted(camera, spp).unwrap(),
        c => SampleSet::grid(c, spp),
    }
}

/// Every ray of `set` in its tile's and its block's beam, and for a thin lens cast one lens
/// sample at a time in its tile's beam of that lens sample (no tolerance).
fn rays_in_beams(set: &SampleSet, h: &Hierarchy) -> Result<(), TestCaseError> {
    let spp = set.spp as usize;
    for b in &h.blocks {
        let first = b.first_tile as usize;
        for (ti, t) in h.tiles[first..first + b.tile_count as usize]
            .iter()
            .enumerate()
        {
            for &i in &h.order[t.start as usize..(t.start + t.len) as usize] {
                for k in 0..spp {
                    if let Some(r) = set.subsample_ray(i as usize, k) {
                        prop_assert!(t.beam.contains_ray(&r, 0.0), "tile beam misses {r:?}");
                        prop_assert!(b.beam.contains_ray(&r, 0.0), "block beam misses {r:?}");
                        if let Some(lb) = h.lens_beams.get((first + ti) * spp + k) {
                            prop_assert!(lb.contains_ray(&r, 0.0), "lens beam misses {r:?}");
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// Built at one pose, moved to another: the rays of the new pose stay in the moved beams.
    /// (Films this small make tiles of up to the whole field of view, which a turned pose may
    /// leave unbounded: `EVERYTHING`, still holding every ray.)
    #[test]
    fn moved_beams_hold_every_ray(
        model in 0usize..5,
        w in 8u32..48,
        h in 8u32..40,
        spp in prop::sample::select(vec![1u32, 4, 16]),
        eyes in prop::array::uniform2(prop::array::uniform3(-3.0f32..3.0)),
        looks in prop::array::uniform2(prop::array::uniform3(-1.0f32..1.0)),
        fov in 20.0f32..120.0,
    ) {
        let kind = MOVABLE[model];
        let [e0, e1] = eyes.map(Vec3::from);
        let [l0, l1] = looks.map(Vec3::from);
        for l in [l0, l1] {
            prop_assume!(l.length() > 0.1 && l.normalize().dot(Vec3::Y).abs() < 0.95);
        }
        let set0 = set_of(camera(kind, e0, e0 + l0, w, h, fov), spp);
        let mut set1 = set0.clone();
        set1.camera = camera(kind, e1, e1 + l1, w, h, fov);
        let mut hier = Hierarchy::build(&set0).unwrap();
        hier.repose(&set1).unwrap();
        // Moved, not built anew (the rectangles are taken on the first move).
        prop_assert!(!hier.rects.is_empty());
        prop_assert_eq!(&hier.camera, &set1.camera);
        rays_in_beams(&set1, &hier)?;
        // And back: the beams of the first pose hold its rays again.
        hier.repose(&set0).unwrap();
        rays_in_beams(&set0, &hier)?;
    }
}

/// The exact cast (`SetupExactness::Full`) through a moved hierarchy equals per-ray traversal
/// of the moved camera, bit for bit, on a scene, for the pinhole, the stereo rig, the
/// distorted eye, the fisheye and the thin lens at 1 and 16 spp (the pinholes' 16-spp sets take the sweep).
#[test]
fn cast_through_a_moved_hierarchy_equals_per_ray_traversal() {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let desc = scene.camera(None).unwrap();
    let turned = desc.eye + (desc.target - desc.eye).normalize() * 0.3;
    let aside = Vec3::new(0.7, 0.2, -0.4);
    for kind in MOVABLE {
        // (The fisheye's 210 x 130 degrees on a film large enough for tiles of tens of
        // degrees.)
        let (w, h) = match kind {
            ModelKind::Stereo => (24, 32),
            ModelKind::Fisheye => (144, 96),
            _ => (48, 32),
        };
        for spp in [1, 16] {
            let set0 = set_of(camera(kind, desc.eye, desc.target, w, h, 60.0), spp);
            let mut set1 = set0.clone();
            set1.camera = camera(kind, turned, desc.target + aside, w, h, 60.0);
            let mut hier = Hierarchy::build(&set0).unwrap();
            hier.repose(&set1).unwrap();
            // The rectangles taken ahead of the move (a frame loop's build) move it alike.
            let mut ahead = Hierarchy::build(&set0).unwrap();
            ahead.prepare_moves(&set0);
            assert!(!ahead.rects.is_empty(), "{kind:?} {spp}");
            ahead.repose(&set1).unwrap();
            assert_eq!(ahead, hier, "{kind:?} {spp}");
            // Tiles of a few degrees stay bounded at any pose.
            assert!(
                hier.tiles.iter().all(|t| !t.beam.everything),
                "{kind:?} {spp}"
            );
            let mut beam = VisibilityBuffer::new(&set1);
            let opts = CastOptions {
                exactness: SetupExactness::Full,
                ..CastOptions::default()
            };
            cast_opts(&bvh, &set1, &hier, &mut beam, opts);
            let mut reference = VisibilityBuffer::new(&set1);
            trace_per_ray(&bvh, &set1, &mut reference);
            let hits = reference.prim.iter().filter(|&&p| p != u32::MAX).count();
            assert!(
                hits > reference.prim.len() / 2,
                "{kind:?} {spp}: {hits} hits"
            );
            assert_eq!(beam, reference, "{kind:?} spp {spp}");
        }
    }
}

/// A hierarchy is refused by the caster for another pose, moved to a set of another size with
/// an error, and built anew when the intrinsics change (a new field of view).
#[test]
fn a_hierarchy_of_another_pose_or_set_is_refused() {
    let scene = Scene::load("cornell").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let desc = scene.camera(None).unwrap();
    let cam = |eye: Vec3, fov: f32| camera(ModelKind::Pinhole, eye, desc.target, 16, 12, fov);
    let set0 = SampleSet::grid(cam(desc.eye, 50.0), 4);
    let mut set1 = set0.clone();
    set1.camera = cam(desc.eye + Vec3::X * 0.1, 50.0);
    let mut hier = Hierarchy::build(&set0).unwrap();
    let mut out = VisibilityBuffer::new(&set1);
    let err = visibility_into(Visibility::Beam, &bvh, &set1, Some(&hier), &mut out);
    assert!(err.is_err(), "a hierarchy of another pose was taken");
    let stale = std::panic::catch_unwind(|| {
        let mut out = VisibilityBuffer::new(&set1);
        cast_opts(&bvh, &set1, &hier, &mut out, CastOptions::default());
    });
    assert!(
        stale.is_err(),
        "the caster cast with a hierarchy of another pose"
    );
    let other = SampleSet::grid(cam(desc.eye, 50.0), 1);
    assert!(matches!(
        hier.repose(&other),
        Err(HierarchyError::OtherSet { .. })
    ));
    // Another field of view: the rays change inside the film, so the hierarchy is built anew.
    let mut wide = set0.clone();
    wide.camera = cam(desc.eye, 70.0);
    hier.repose(&wide).unwrap();
    assert_eq!(hier, Hierarchy::build(&wide).unwrap());
}
