//! HVVR's frame loop (`frame::EyeState`): a frame whose hierarchy was moved and whose
//! visibility buffer is the last frame's, written over, equals the same frame rendered from
//! nothing, for the beam caster and per-ray visibility.

use parallax_bvh::Bvh;
use parallax_scene::Scene;
use parallax_scene::camera::Camera;
use parallax_vr::frame::{EyeState, FrameOptions, Visibility, render_eye_with};
use parallax_vr::patterns::eye_set;
use parallax_vr::presets::{Preset, eye_cameras};
use parallax_vr::resolve::ShadingMode;
use parallax_vr::shade::ShadeOptions;

/// The atrium, its BVH and the left eye of a small rift-cv1 headset at the scene's camera and
/// with the head turned by `turn` degrees.
fn atrium_eyes(turn: f32) -> (Scene, Bvh, Camera, Camera) {
    let scene = Scene::load("atrium").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let head = scene.camera(None).unwrap();
    let mut spec = Preset::RiftCv1.spec();
    (spec.width, spec.height) = (40, 44);
    let [first, _] = eye_cameras(&spec, &head, None).unwrap();
    let [turned, _] = eye_cameras(&spec, &head.turned(turn), None).unwrap();
    (scene, bvh, first, turned)
}

/// Four-subsample MSAA frames without shadows, by `visibility`.
fn options(visibility: Visibility) -> FrameOptions {
    FrameOptions {
        spp: 4,
        mode: ShadingMode::Msaa,
        visibility,
        shade: ShadeOptions { shadows: false },
    }
}

#[test]
fn a_frame_over_the_last_frames_buffer_equals_a_frame_from_nothing() {
    // A large turn: much of what the first frame hit, the second misses or sees elsewhere, so
    // a stale entry left in the reused buffer would show.
    let (scene, bvh, first, turned) = atrium_eyes(40.0);
    for visibility in [Visibility::Beam, Visibility::BeamExact, Visibility::PerRay] {
        let opts = options(visibility);
        let set = |cam| eye_set(cam, opts.spp, true, Some([0.0, 0.0])).unwrap();
        let mut state = EyeState::new();
        let frame0 = render_eye_with(&scene, &bvh, set(first.clone()), &opts, &mut state).unwrap();
        let buffer = frame0.vis.prim.as_ptr();
        let before = frame0.vis.clone();
        state.recycle(frame0);
        let frame1 = render_eye_with(&scene, &bvh, set(turned.clone()), &opts, &mut state).unwrap();
        assert_eq!(
            frame1.vis.prim.as_ptr(),
            buffer,
            "{visibility:?}: buffer not reused"
        );
        // The same frame with the same moved hierarchy (the `Beam` kernel's `t` may differ in
        // the last bits between a moved and a built hierarchy: its tiles' depth axes) and a
        // new buffer.
        let mut other = EyeState::new();
        render_eye_with(&scene, &bvh, set(first.clone()), &opts, &mut other).unwrap();
        let fresh = render_eye_with(&scene, &bvh, set(turned.clone()), &opts, &mut other).unwrap();
        assert_ne!(
            before, fresh.vis,
            "{visibility:?}: the turn changed nothing"
        );
        let differ: Vec<(usize, u32, u32)> = (0..fresh.vis.prim.len())
            .filter(|&i| {
                frame1.vis.prim[i] != fresh.vis.prim[i]
                    || frame1.vis.t[i].to_bits() != fresh.vis.t[i].to_bits()
            })
            .map(|i| (i, frame1.vis.prim[i], fresh.vis.prim[i]))
            .collect();
        assert!(
            differ.is_empty(),
            "{visibility:?}: {} of {} entries differ, first {:?}",
            differ.len(),
            fresh.vis.prim.len(),
            &differ[..differ.len().min(8)]
        );
        assert_eq!(frame1.image, fresh.image, "{visibility:?}");
        // A set of another size takes a new buffer.
        state.recycle(frame1);
        let other = eye_set(turned.clone(), 1, true, Some([0.0, 0.0])).unwrap();
        let opts1 = FrameOptions { spp: 1, ..opts };
        let small = render_eye_with(&scene, &bvh, other, &opts1, &mut state).unwrap();
        assert_eq!(small.vis.prim.len(), small.set.ray_count());
    }
}

/// A set with other samples but as many (here the same samples in reverse order, as a moved
/// gaze could give) gets a new hierarchy, not the old one moved: the exact cast then equals
/// per-ray traversal. Moving the old one would cull each sample by another sample's beam.
#[test]
fn other_samples_of_the_same_count_take_a_new_hierarchy() {
    let (scene, bvh, first, turned) = atrium_eyes(10.0);
    let opts = options(Visibility::BeamExact);
    let mut state = EyeState::new();
    let set0 = eye_set(first, opts.spp, true, Some([0.0, 0.0])).unwrap();
    let mut set1 = eye_set(turned, opts.spp, true, Some([0.0, 0.0])).unwrap();
    set1.samples.reverse();
    let frame0 = render_eye_with(&scene, &bvh, set0, &opts, &mut state).unwrap();
    state.recycle(frame0);
    let frame1 = render_eye_with(&scene, &bvh, set1.clone(), &opts, &mut state).unwrap();
    let per_ray = FrameOptions {
        visibility: Visibility::PerRay,
        ..opts
    };
    let reference = render_eye_with(&scene, &bvh, set1, &per_ray, &mut EyeState::new()).unwrap();
    assert_eq!(frame1.vis, reference.vis);
}
