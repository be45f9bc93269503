//! Antialiased cube-map reflections (Widmer et al. 2015, §5.4; `reflect --spp`): `s x s`
//! primary rays per pixel over the view captured at `s` times its size, box-filtered, scored
//! against the BVH reflector on the same rays with the same filter.

use glam::Vec3;
use parallax_bvh::Bvh;
use parallax_render::score::Shading;
use parallax_scene::camera::Pinhole;
use parallax_scene::{CameraDesc, Scene};
use parallax_synth::dof::truth::masked_psnr;
use parallax_synth::lightfield::{box_filter, spp_side, supersampled};
use parallax_synth::reflect::{
    BvhReflector, CubeReflector, ReflectOptions, ReflectionCube, Reflector, render_reflections,
};
use parallax_synth::{Method, MethodOptions, capture_reference};

const FACE: u32 = 128;

/// `reflector`'s reflections of `camera`'s view with `spp` rays per pixel, box-filtered.
fn render_aa(
    scene: &Scene,
    bvh: &Bvh,
    camera: &Pinhole,
    reflector: &dyn Reflector,
    spp: u32,
    o: &ReflectOptions,
) -> parallax_synth::reflect::ReflectionImage {
    let s = spp_side(spp).unwrap();
    let fine = supersampled(camera, s);
    let reference = capture_reference(scene, bvh, &fine, 1, Shading::Fixed, 0).unwrap();
    render_reflections(reflector, &reference, camera.frame.position, FACE, o)
        .unwrap()
        .box_filtered(s)
        .unwrap()
}

/// `mirrors-open` at 96x54 with its one-layer cube map of `FACE`² faces at the eye.
fn mirrors_open_96x54() -> (Scene, Bvh, Pinhole, ReflectionCube) {
    let scene = Scene::load("mirrors-open").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let camera = Pinhole::new(&scene.camera(None).unwrap(), 96, 54).unwrap();
    let eye = camera.frame.position;
    let desc = CameraDesc::new(eye, eye - Vec3::Z, Vec3::Y, 90.0);
    let cube = ReflectionCube::capture(&scene, &bvh, &desc, FACE, 1, 0).unwrap();
    (scene, bvh, camera, cube)
}

/// The quad-tree reflector over `cube` with surface thickness 0.1.
fn thick_quadtree_reflector<'a>(scene: &'a Scene, cube: &'a ReflectionCube) -> CubeReflector<'a> {
    let mut c =
        CubeReflector::build(scene, cube, Method::QuadTree, &MethodOptions::default()).unwrap();
    c.tracer.thickness = Some(0.1);
    c
}

fn opts(n_p: u32, n_s: u32) -> ReflectOptions {
    ReflectOptions {
        n_p,
        n_s,
        n_b: 1,
        ..ReflectOptions::default()
    }
}

/// The BVH reflector at 4 rays per pixel against itself is exact; the filtered image is the
/// box filter of the fine one, and a filtered pixel reflects exactly when one of its 4 rays'
/// pixels does.
#[test]
fn antialiased_truth_against_itself_is_exact_and_filters_match() {
    let scene = Scene::load("mirrors-open").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let camera = Pinhole::new(&scene.camera(None).unwrap(), 48, 27).unwrap();
    let eye = camera.frame.position;
    let truth = BvhReflector::new(&scene, &bvh, eye, 0);
    let o = opts(1, 2);
    let a = render_aa(&scene, &bvh, &camera, &truth, 4, &o);
    let b = render_aa(&scene, &bvh, &camera, &truth, 4, &o);
    assert_eq!((a.image.width(), a.image.height()), (48, 27));
    assert_eq!(a.mask.len(), 48 * 27);
    let p = masked_psnr(&a.image, &b.image, &b.mask).unwrap();
    assert!(p.is_infinite(), "{p}");
    let fine_ref = capture_reference(
        &scene,
        &bvh,
        &supersampled(&camera, 2),
        1,
        Shading::Fixed,
        0,
    )
    .unwrap();
    let fine = render_reflections(&truth, &fine_ref, eye, FACE, &o).unwrap();
    assert!(box_filter(&fine.image, 2).unwrap().data() == a.image.data());
    for y in 0..27 {
        for x in 0..48 {
            let any = (0..4).any(|k| fine.mask[((2 * y + k / 2) * 96 + 2 * x + k % 2) as usize]);
            assert_eq!(a.mask[(y * 48 + x) as usize], any, "({x}, {y})");
        }
    }
    let n = a.reflective_pixels();
    assert!(n > 48 * 27 / 20, "{n} reflective pixels");
}

/// `mirrors-open` (96x54, 128² faces, 1 layer, thickness 0.1, quad-tree, 1/4/1): scored
/// against the same-filter truth, 4 rays per pixel score well above 1 (the point-sampled
/// mirror images of the checkered ground alias on both sides).
#[test]
fn four_rays_per_pixel_score_above_one() {
    let (scene, bvh, camera, cube) = mirrors_open_96x54();
    let c = thick_quadtree_reflector(&scene, &cube);
    let truth = BvhReflector::new(&scene, &bvh, camera.frame.position, 0);
    let o = opts(1, 4);
    let psnr = |spp: u32| {
        let t = render_aa(&scene, &bvh, &camera, &truth, spp, &o);
        let i = render_aa(&scene, &bvh, &camera, &c, spp, &o);
        masked_psnr(&i.image, &t.image, &t.mask).unwrap()
    };
    let (one, four) = (psnr(1), psnr(4));
    println!(
        "mirrors-open 96x54: PSNR over the reflective pixels {one:.2} dB at 1 spp, {four:.2} dB at 4"
    );
    assert!(four > one + 1.5, "1 spp {one:.2} dB, 4 spp {four:.2} dB");
}

/// `mirrors-open` (96x54, 128² faces, 1 layer, thickness 0.1, quad-tree, 1/8/1, 4 rays per
/// pixel): tracing the extra samples whose plane lookup weighs less than 0.5
/// (`ReflectOptions::trace_below`) traces some of them and scores at least as well as
/// looking every one up.
#[test]
fn tracing_low_weight_extra_samples() {
    let (scene, bvh, camera, cube) = mirrors_open_96x54();
    let c = thick_quadtree_reflector(&scene, &cube);
    let truth = BvhReflector::new(&scene, &bvh, camera.frame.position, 0);
    let t = render_aa(&scene, &bvh, &camera, &truth, 4, &opts(1, 8));
    let run = |trace_below: f32| {
        let o = ReflectOptions {
            trace_below,
            ..opts(1, 8)
        };
        let i = render_aa(&scene, &bvh, &camera, &c, 4, &o);
        (masked_psnr(&i.image, &t.image, &t.mask).unwrap(), i)
    };
    let ((looked_up, a), (traced, b)) = (run(0.0), run(0.5));
    println!(
        "1/8/1, 4 spp: {looked_up:.2} dB looking every extra sample up, {traced:.2} dB tracing the {} of {} lookups below weight 0.5",
        b.extras_traced, b.lookups
    );
    assert_eq!(a.extras_traced, 0);
    assert!(b.extras_traced > 0 && b.extras_traced < b.lookups);
    assert!(
        traced >= looked_up - 0.05,
        "{looked_up:.2} -> {traced:.2} dB"
    );
}

#[test]
fn bad_ray_counts_are_errors() {
    for spp in [0, 2, 5, 81, 1_000_000] {
        let e = spp_side(spp).unwrap_err().to_string();
        assert!(e.contains("rays per pixel"), "{spp}: {e}");
    }
    let scene = Scene::load("mirrors-open").unwrap();
    let bvh = Bvh::build(&scene.mesh);
    let camera = Pinhole::new(&scene.camera(None).unwrap(), 16, 9).unwrap();
    let reference = capture_reference(&scene, &bvh, &camera, 1, Shading::Fixed, 0).unwrap();
    let truth = BvhReflector::new(&scene, &bvh, camera.frame.position, 0);
    let img =
        render_reflections(&truth, &reference, camera.frame.position, 16, &opts(1, 0)).unwrap();
    // 16 x 9 is not made of 2 x 2 blocks.
    let e = img.box_filtered(2).unwrap_err().to_string();
    assert!(e.contains("blocks"), "{e}");
}
